"""Benchmarks: scripts that print the figures of docs/speed.md (run as ``python benchmarks/NAME.py``)."""

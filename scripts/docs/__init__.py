"""Generators of the tables and figures in README.md and docs/ (each one a step of scripts/regenerate.py)."""

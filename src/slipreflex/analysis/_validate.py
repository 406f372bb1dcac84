"""Validators shared by the analysis modules (private)."""

from __future__ import annotations

from ..baselines._validate import build, integer, number, setattr_frozen  # noqa: F401

__all__ = ["build", "integer", "number", "setattr_frozen"]

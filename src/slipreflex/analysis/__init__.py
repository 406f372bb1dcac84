"""slipreflex.analysis."""

"""slipreflex.baselines."""

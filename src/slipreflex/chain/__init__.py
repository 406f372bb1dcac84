"""slipreflex.chain."""

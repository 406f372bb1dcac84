"""slipreflex.sim."""

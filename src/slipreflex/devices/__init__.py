"""slipreflex.devices."""

"""slipreflex.rig.devices."""

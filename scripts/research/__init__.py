"""One-off research scripts: ablations and checks of the simulator against the paper, kept for their docs."""

"""slipreflex: event-based slip detection and reflex-like grip control."""

__version__ = "0.1.0"

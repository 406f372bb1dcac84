"""Maintainer tools: measurements of the code, the Foxglove layout, the data set converter, a fresh-machine check."""

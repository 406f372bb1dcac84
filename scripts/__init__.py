"""Maintainer scripts, a package run from the repository's top: ``python -m scripts.docs.NAME``.

``regenerate.py`` (every generated table) and ``bootstrap.sh`` (set-up) stay here; ``docs/`` holds the
table generators, ``dev/`` the tools, ``research/`` the research scripts.
"""

"""The import paths of slipreflex before its layer packages, kept working.

Until version 0.1 every module sat at the top of the package
(``slipreflex.methods`` still does; ``slipreflex.runtime`` is now
:mod:`slipreflex.rig.runtime`). Code written against the old paths keeps
working: importing an old path gives the module at its new place, the same
object (so a name patched through either path is patched for both).
Nothing inside slipreflex uses the old paths (``tests/house/test_imports.py``
checks).

Examples
--------
>>> import slipreflex.runtime, slipreflex.rig.runtime
>>> slipreflex.runtime is slipreflex.rig.runtime
True
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import importlib.util
import sys

__all__ = ["MOVED", "new_name", "install"]

#: Old module path (below ``slipreflex.``) -> its place now.
MOVED: dict[str, str] = {
    "errors": "core.errors",
    "hardware": "core.hardware",
    "interfaces": "core.interfaces",
    "validation": "core.validation",
    "registry": "core.registry",
    "grip": "core.grip",
    "taps": "core.taps",
    "_slots": "core._slots",
    "_numba_cache": "core._numba_cache",
    "experiment_specs": "core.experiment_specs",
    "paths": "files.paths",
    "csvfiles": "files.csvfiles",
    "interrupts": "files.interrupts",
    "progress": "files.progress",
    "recording": "files.recording",
    "chain": "methods.chain",
    "baselines": "methods.baselines",
    "board": "methods.board",
    "devices": "rig.devices",
    "runtime": "rig.runtime",
    "live": "rig.live",
    "lsl": "rig.lsl",
    "hands": "rig.hands",
    "experiments": "reproduce.experiments",
    "grid": "reproduce.grid",
    "replication": "reproduce.replication",
    "thresholds": "reproduce.thresholds",
    "warmup": "reproduce.warmup",
    "grasping": "reproduce.grasping",
    "paper_experiments": "reproduce.paper_experiments",
    "contract_checks": "core.contract_checks",
    "loop_results": "rig.loop_results",
    "loop_sink": "rig.loop_sink",
    "loop_start": "rig.loop_start",
    "loop_states": "rig.loop_states",
    "privileges": "rig.privileges",
    "replay": "rig.replay",
}


def new_name(name: str) -> str | None:
    """The current path of a module imported by its old ``name``, or None if it did not move.

    Examples
    --------
    >>> new_name("slipreflex.chain.encoder")
    'slipreflex.methods.chain.encoder'
    >>> new_name("slipreflex.sim") is None
    True
    """
    if not name.startswith("slipreflex."):
        return None
    old, dot, below = name[len("slipreflex."):].partition(".")   # every old path was a top-level module
    return f"slipreflex.{MOVED[old]}{dot}{below}" if old in MOVED else None


class _Alias(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds an old path and hands back the module imported at its new one."""

    def find_spec(self, fullname, path=None, target=None):
        new = new_name(fullname)
        if new is None:
            return None
        spec = importlib.util.find_spec(new)
        if spec is None:
            return None
        return importlib.machinery.ModuleSpec(fullname, self, is_package=spec.submodule_search_locations is not None)

    def create_module(self, spec):
        module = importlib.import_module(new_name(spec.name) or spec.name)
        spec.loader_state = module.__spec__   # the import system sets __spec__ to this alias; exec puts it back
        return module

    def exec_module(self, module):
        """Nothing to run (the module ran at its new path); its own spec is put back, so its relative
        imports still resolve from its package."""
        alias = module.__spec__
        if alias is not None and alias.loader_state is not None:
            module.__spec__ = alias.loader_state


def install() -> None:
    """Put the finder of old paths on ``sys.meta_path`` (once).

    Examples
    --------
    >>> install(); sum(isinstance(f, _Alias) for f in sys.meta_path)
    1
    """
    if not any(isinstance(f, _Alias) for f in sys.meta_path):
        sys.meta_path.insert(0, _Alias())   # before the path finder, which would load a second copy

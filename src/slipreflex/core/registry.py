"""One small registry of named specifications, the base of every registry in the package.

The methods (:mod:`slipreflex.methods`), the hands (:mod:`slipreflex.rig.hands`) and the
experiments (:mod:`slipreflex.core.experiment_specs`) are each a :class:`Registry` of their frozen
specification class: an ordered table of ``name -> spec`` with one way to add, find, list
and remove, one checker hook run on every registration, and the same one-line errors.
It sits at the bottom of the import graph (it imports only :mod:`slipreflex.core.errors` and
:mod:`slipreflex.core.validation`), so a registry never imports the implementations it lists:
those are named by :class:`EntryPoint` and imported when first called.

Examples
--------
>>> from dataclasses import dataclass
>>> @dataclass(frozen=True)
... class Tool:
...     name: str
>>> tools = Registry("tool", Tool, any_case=True)
>>> tools.register(Tool("saw")); tools.register(Tool("drill"))
>>> tools.names(), tools.get("SAW").name, "drill" in tools
(('saw', 'drill'), 'saw', True)
>>> tools.get("hammer")
Traceback (most recent call last):
...
slipreflex.core.errors.ParameterError: tool: unknown 'hammer' (known: saw, drill)
>>> tools.unregister("drill"); tools.names()
('saw',)
"""

from __future__ import annotations

import importlib
import importlib.util
import os
import re
import sys
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from typing import Any, Generic, Protocol, TypeVar

from .errors import ParameterError
from .validation import choice

__all__ = ["Registry", "EntryPoint", "PLUGIN_ENV", "load_plugin_file", "load_env_plugins"]

#: The environment variable naming plugin files (Python files, separated by ``os.pathsep``) that every
#: registry loads before its first lookup; ``slipreflex --plugin FILE`` adds to it, so the worker
#: processes of a run load the same files.
PLUGIN_ENV: str = "SLIPREFLEX_PLUGINS"
_loaded_files: dict[str, Any] = {}
_env_read = ""   # the variable's value whose files are loaded


class _Named(Protocol):
    @property
    def name(self) -> str: ...


S = TypeVar("S", bound=_Named)


class Registry(Generic[S]):
    """An ordered table of specifications of one class, keyed by their ``name``.

    Parameters
    ----------
    kind : str
        What one entry is, for messages ("method", "hand", "experiment").
    spec_type : type
        The class every registered specification is an instance of (it has a ``name``).
    any_case : bool
        Names are looked up in any case (``"DATH"`` finds ``"dath"``).
    label : str, optional
        How an unknown name is introduced (default ``kind``; ``"--hand-type"`` for the CLI's option).
    check : callable, optional
        ``check(spec)`` runs on every registration before it is stored; it raises
        :class:`~slipreflex.core.errors.ParameterError` (naming the spec) to refuse one.
    protected : iterable of str
        Names that cannot be unregistered (the paper's own).
    before_read : callable, optional
        Called before every lookup or listing (a plugin loader that runs once).
    group : str, optional
        The entry-point group through which installed packages add entries (``"slipreflex.hands"``):
        read once, before the first lookup or listing (:meth:`load_entry_points`).

    Every lookup or listing first loads the plugin files named in :data:`PLUGIN_ENV` (once per
    process; :func:`load_plugin_file`).

    Examples
    --------
    >>> from slipreflex.rig.hands import HANDS
    >>> HANDS.kind, HANDS.names()
    ('hand', ('ilimb', 'ability'))
    """

    def __init__(self, kind: str, spec_type: type[S], *, any_case: bool = False, label: str | None = None,
                 check: Callable[[S], None] | None = None, protected: Iterable[str] = (),
                 before_read: Callable[[], Any] | None = None, group: str | None = None) -> None:
        self.kind, self.spec_type, self.any_case = kind, spec_type, any_case
        self.label = label or kind
        self.check, self.protected, self.before_read = check, tuple(protected), before_read
        self.group, self._group_read = group, group is None
        self._specs: dict[str, S] = {}

    def _table(self) -> dict[str, S]:
        load_env_plugins()
        if not self._group_read:
            self.load_entry_points()
        if self.before_read is not None:
            self.before_read()
        return self._specs

    def load_entry_points(self) -> tuple[str, ...]:
        """Register what installed packages declare in this registry's entry-point group (once).

        A package declares, in its ``pyproject.toml``::

            [project.entry-points."slipreflex.hands"]
            my-hand = "my_package.hand:MY_HAND"

        where the object is a specification, a sequence of them, or a function returning
        either; read in name order; a name already registered is kept.

        Returns
        -------
        tuple of str
            The names added by this call.

        Raises
        ------
        ParameterError
            When an entry point cannot be loaded or gives something else (naming it).

        Examples
        --------
        >>> from slipreflex.rig.hands import HANDS
        >>> HANDS.load_entry_points()       # nothing installed declares one here, and it runs once
        ()
        """
        if self._group_read or self.group is None:
            return ()
        self._group_read = True
        from importlib.metadata import entry_points  # deferred: heavy (importlib.metadata, ~30 ms of import)

        added = []
        for ep in sorted(entry_points(group=self.group), key=lambda e: e.name):
            try:
                obj = ep.load()
                got = obj() if callable(obj) and not isinstance(obj, self.spec_type) else obj
                specs = [got] if isinstance(got, self.spec_type) else list(got)  # pyright: ignore[reportArgumentType]
            except Exception as err:  # a broken plugin is the user's to fix: say which one
                raise ParameterError(f"{self.kind} plugin {ep.name!r} ({ep.value}): cannot load: {err}") from err
            for spec in specs:
                if not isinstance(spec, self.spec_type):
                    raise ParameterError(f"{self.kind} plugin {ep.name!r} ({ep.value}): gave {spec!r}, "
                                         f"not a {self.spec_type.__name__}")
                if self.add_new(spec):
                    added.append(spec.name)
        return tuple(added)

    def register(self, spec: S, *, replace: bool = False) -> None:
        """Add ``spec`` at the end of the order (``replace``: a spec of the same name keeps its place).

        Examples
        --------
        >>> from slipreflex.rig.hands import HANDS
        >>> HANDS.register(HANDS.get("ilimb"))
        Traceback (most recent call last):
        ...
        slipreflex.core.errors.ParameterError: hand 'ilimb' is already registered (pass replace=True)
        >>> HANDS.register("ilimb")
        Traceback (most recent call last):
        ...
        slipreflex.core.errors.ParameterError: the hand registry takes a HandSpec, got str
        """
        if not isinstance(spec, self.spec_type):
            raise ParameterError(f"the {self.kind} registry takes a {self.spec_type.__name__}, "
                                 f"got {type(spec).__name__}")
        name: str = spec.name
        if name in self._specs and not replace:
            raise ParameterError(f"{self.kind} {name!r} is already registered (pass replace=True)")
        if self.check is not None:
            self.check(spec)
        self._specs[name] = spec

    def add_new(self, spec: S) -> bool:
        """Register ``spec`` unless its name is taken (what a plugin loader does); True if added.

        Examples
        --------
        >>> from slipreflex.rig.hands import HANDS
        >>> HANDS.add_new(HANDS.get("ilimb"))
        False
        """
        if spec.name in self._specs:
            return False
        self.register(spec)
        return True

    def canonical(self, name: str) -> str:
        """The registered name ``name`` refers to; an unknown one is a one-line error listing the known.

        Examples
        --------
        >>> from slipreflex.rig.hands import HANDS
        >>> HANDS.canonical(" Ability ")
        'ability'
        """
        return choice(self.label, name.strip() if isinstance(name, str) else name, self._table(),
                      any_case=self.any_case)

    def get(self, name: str) -> S:
        """The specification registered as ``name``.

        Examples
        --------
        >>> from slipreflex.rig.hands import HANDS
        >>> HANDS.get("ilimb").label
        'i-Limb'
        """
        return self._table()[self.canonical(name)]

    def find(self, name: Any) -> S | None:
        """The specification registered as ``name``, or None (no error).

        Examples
        --------
        >>> from slipreflex.rig.hands import HANDS
        >>> HANDS.find("shadow") is None
        True
        """
        table = self._table()
        if not isinstance(name, str):
            return None
        return table.get(name.casefold() if self.any_case else name)

    def names(self) -> tuple[str, ...]:
        """Registered names, in registration order.

        Examples
        --------
        >>> from slipreflex.rig.hands import HANDS
        >>> HANDS.names()
        ('ilimb', 'ability')
        """
        return tuple(self._table())

    def specs(self) -> tuple[S, ...]:
        """Registered specifications, in registration order.

        Examples
        --------
        >>> from slipreflex.rig.hands import HANDS
        >>> [s.tactile for s in HANDS.specs()]
        [False, True]
        """
        return tuple(self._table().values())

    def unregister(self, name: str) -> None:
        """Remove the specification registered as ``name`` (a protected one is an error).

        Examples
        --------
        >>> from slipreflex.core.experiment_specs import EXPERIMENTS
        >>> EXPERIMENTS.unregister("drop")
        Traceback (most recent call last):
        ...
        slipreflex.core.errors.ParameterError: experiment 'drop' is built in and cannot be unregistered
        """
        key = self.canonical(name)
        if key in self.protected:
            raise ParameterError(f"{self.kind} {key!r} is built in and cannot be unregistered")
        del self._specs[key]

    def __contains__(self, name: object) -> bool:
        return self.find(name) is not None

    def __iter__(self) -> Iterator[str]:
        return iter(self.names())

    def __len__(self) -> int:
        return len(self._table())

    def __repr__(self) -> str:
        return f"Registry({self.kind!r}: {', '.join(self.names())})"


@dataclass(frozen=True)
class EntryPoint:
    """A function named ``"module:function"``, imported when first called (with bound arguments).

    Like Gymnasium's ``entry_point`` strings: a registry lists implementations that
    sit above it without importing them. Picklable, so a spec runs in worker processes.

    Parameters
    ----------
    target : str
        ``"package.module:function"``.
    args : tuple
        Positional arguments put before the caller's (like :func:`functools.partial`).

    Examples
    --------
    >>> EntryPoint("math:hypot", (3.0,))(4.0)
    5.0
    """

    target: str
    args: tuple = ()

    def __post_init__(self) -> None:
        module, _, name = self.target.partition(":")
        if not module or not name.isidentifier():
            raise ParameterError(f"EntryPoint target must be 'module:function', got {self.target!r}")

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        module, _, name = self.target.partition(":")
        return getattr(importlib.import_module(module), name)(*self.args, *args, **kwargs)


def load_plugin_file(path: str | os.PathLike[str]) -> Any:
    """Run one plugin file (a Python file that registers hands, experiments, methods or loads), once.

    The file is imported as the module ``slipreflex_plugin_<stem>`` (so what it defines pickles
    into worker processes); loading the same file again returns the same module.

    Parameters
    ----------
    path : str or path
        A ``.py`` file.

    Returns
    -------
    module
        The plugin's module.

    Raises
    ------
    ParameterError
        One line naming the file: missing, not a ``.py`` file, or raising when run.

    Examples
    --------
    >>> load_plugin_file("no-such-plugin.py")
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: plugin no-such-plugin.py: no such file
    """
    text_path = os.fspath(path)
    resolved = os.path.realpath(text_path)
    if resolved in _loaded_files:
        return _loaded_files[resolved]
    if not os.path.isfile(resolved):
        raise ParameterError(f"plugin {text_path}: no such file")
    if not resolved.endswith(".py"):
        raise ParameterError(f"plugin {text_path}: not a Python file (.py)")
    stem = re.sub(r"\W", "_", os.path.basename(resolved)[:-3])
    name = f"slipreflex_plugin_{stem}"
    if name in sys.modules:
        raise ParameterError(f"plugin {text_path}: another plugin file is already loaded as {name}")
    spec = importlib.util.spec_from_file_location(name, resolved)
    if spec is None or spec.loader is None:  # pragma: no cover - a .py file always has a loader
        raise ParameterError(f"plugin {text_path}: cannot be imported")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    _loaded_files[resolved] = module
    try:
        spec.loader.exec_module(module)
    except Exception as err:  # the plugin's own error, in one line naming the file
        del sys.modules[name], _loaded_files[resolved]
        where = f"line {err.lineno}: " if isinstance(err, SyntaxError) else ""
        raise ParameterError(f"plugin {text_path}: {where}{type(err).__name__}: {err}") from err
    return module


def load_env_plugins() -> tuple[str, ...]:
    """Load the plugin files :data:`PLUGIN_ENV` names (each once; an empty variable loads nothing).

    Returns
    -------
    tuple of str
        The files named.

    Examples
    --------
    >>> import os
    >>> PLUGIN_ENV in os.environ or load_env_plugins() == ()
    True
    """
    global _env_read
    value = os.environ.get(PLUGIN_ENV, "")
    files = tuple(f for f in value.split(os.pathsep) if f.strip())
    if value != _env_read:
        for file in files:
            load_plugin_file(file)
        _env_read = value
    return files

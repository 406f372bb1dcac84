"""The registry of reflex methods: one specification per method, in one place.

Every slip-detection / reflex method the package can run (the paper's fixed
threshold and DATH chains, NMSD, SWT-SD, and any method added later or by
user code) is described by one frozen :class:`MethodSpec`: its name, the
label tables print, which stream it reads, the rate it runs at, whether its
command is a closing ramp, how to build it, how figures draw its detections,
and, for methods whose threshold is calibrated at rest, the statistic the
threshold rule measures. The experiment runner, the report, the figures, the
CLI's ``--methods`` and the study read only these specifications, so a method
registered here works everywhere without touching them.

In the spirit of Gymnasium's ``register`` / ``make``:

* :func:`names` lists the registered methods in their one order
  (registration order: the paper's DATH, fixed, NMSD, SWT-SD first, as in its table);
* :func:`make` builds a fresh reflex by name (any case: ``"DATH"`` is ``"dath"``);
* :func:`register` adds a method; :func:`get` returns its specification;
* an installed package adds methods to every command (``reproduce --methods``)
  through the ``slipreflex.methods`` entry-point group (:func:`load_plugins`).

Adding a method
---------------
A method built on the paper's chain (:class:`slipreflex.methods.chain.SlipReflex`) with
other parameters takes two lines: :func:`chain_method` writes the
specification (builder and detection drawing included) from the chain's
keyword parameters.

>>> from slipreflex import methods
>>> methods.register(methods.chain_method("dath-d8", "DATH, D = 8", dath=True, dath_samples=8))
>>> "dath-d8" in methods.names()
True
>>> methods.make("DATH-D8", p0=200.0).params.dath_samples
8
>>> methods.unregister("dath-d8")

Any other method writes a builder ``build(p0, context, **params)`` returning an
object that satisfies :class:`slipreflex.core.interfaces.Reflex` (check it with
:func:`slipreflex.testing.check_reflex`). For runs in worker processes
(``reproduce --jobs N``) the builder must be picklable: a module-level
function, or a :func:`functools.partial` of one.

>>> from slipreflex.methods.chain import SlipReflex
>>> def build_slow(p0, context, **params):
...     return SlipReflex(n=32, p0=p0, **params)
>>> methods.register(methods.MethodSpec(name="slow", label="slow MPI", input_kind="slip",
...                                     fs=1 / 0.003, build=build_slow))
>>> methods.make("slow", p0=100.0).params.n
32
>>> methods.unregister("slow")

Examples
--------
>>> names()[:4]
('dath', 'fixed', 'nmsd', 'swt')
>>> get("SWT").label, get("swt").ramp, get("dath").input_kind
('SWT-SD', True, 'slip')
>>> make("nmsd", threshold=40.0, speed=500.0).fs
260.0
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..core import hardware as hw
from ..core.errors import ParameterError
from ..core.interfaces import InputKind, Reflex
from ..core.registry import EntryPoint, Registry
from ..core.validation import choice, flag, positive, text

__all__ = ["MethodSpec", "MethodContext", "Detections", "register", "unregister", "get", "names",
           "make", "label", "canonical", "chain_method", "applicable", "INPUT_NAMES", "calibrated",
           "load_plugins", "ENTRY_POINT_GROUP", "EntryPoint", "METHODS",
           "FIXED", "DATH", "NMSD", "SWT", "AUTHORS_GUI", "AUTHORS_CHAIN", "DATH_EVENT",
           "DATH_FLOOR", "DATH_LEAK"]

#: Names of the paper's four methods (the one place they are spelled).
FIXED, DATH, NMSD, SWT = "fixed", "dath", "nmsd", "swt"

_NAME = re.compile(r"^[a-z][a-z0-9_.-]*$")


@dataclass(frozen=True)
class MethodContext:
    """What a builder may need beyond the method's own parameters.

    Parameters
    ----------
    thresholds : mapping of str to float
        Thresholds calibrated at rest, by method name
        (:func:`slipreflex.reproduce.experiments.calibrate`).
    speed : float or None
        The hand's closing speed (finger units per second) for methods that
        ramp the command; None takes the simulated hand's
        (``slipreflex.sim.HandParams().speed_units_s``).
    options : mapping
        Run-wide settings a builder may read (``swt_persist`` from
        ``reproduce --swt-persist``); a builder ignores the ones it does not know.
    method : str
        The method being built (set by :func:`make`); :attr:`threshold` reads
        its entry of ``thresholds``.

    Examples
    --------
    >>> MethodContext(thresholds={"nmsd": 40.0}, method="nmsd").threshold
    40.0
    >>> MethodContext(speed=300.0).closing_speed()
    300.0
    """

    thresholds: Mapping[str, float] = field(default_factory=dict)
    speed: float | None = None
    options: Mapping[str, Any] = field(default_factory=dict)
    method: str = ""

    @property
    def threshold(self) -> float | None:
        """The calibrated threshold of :attr:`method`, or None.

        Examples
        --------
        >>> MethodContext().threshold is None
        True
        """
        return self.thresholds.get(self.method)

    def closing_speed(self) -> float:
        """:attr:`speed`, or the simulated hand's closing speed when it is None.

        Examples
        --------
        >>> MethodContext().closing_speed() > 0
        True
        """
        if self.speed is not None:
            return positive("speed", self.speed)
        return float(hw.FINGER_SPEED_UNITS_S)   # the simulated hand's default (sim.HandParams)


@dataclass(frozen=True)
class Detections:
    """What a trial figure draws for a method: its sensor trace and its detections.

    Parameters
    ----------
    sensor : numpy.ndarray, shape (K,)
        The trace to draw, one value per input sample.
    sensor_label : str
        Axis label of the trace.
    events : numpy.ndarray of bool, shape (K,)
        Samples at which the method detected something.
    event_label : str
        Legend of the detections.

    Examples
    --------
    >>> import numpy as np
    >>> int(Detections(np.zeros(3), "x", np.array([False, True, False]), "spikes").events.sum())
    1
    """

    sensor: np.ndarray
    sensor_label: str
    events: np.ndarray
    event_label: str


@dataclass(frozen=True)
class MethodSpec:
    """Everything the package needs to know about one method.

    Parameters
    ----------
    name : str
        Registry key, lower case (``[a-z][a-z0-9_.-]*``); names are matched
        case-insensitively.
    label : str
        How tables and figures name it ("SWT-SD").
    input_kind : {"slip", "tactile"}
        The stream its ``step`` reads.
    fs : float
        The rate (Hz) it runs at (and records its calibration at).
    build : callable
        ``build(p0, context, **params) -> Reflex``: a fresh reflex starting
        from finger position ``p0``; ``context`` is a :class:`MethodContext`;
        ``params`` override the method's defaults.
    ramp : bool
        Its command is a closing ramp (NMSD's rule): the paper's *total* is the
        closing time it generated, not the span of its command changes.
    detections : callable, optional
        ``detections(reflex, x) -> Detections``, with ``x`` the method's input
        stream of a whole trial (volts, or tactile frames); None draws no trace.
    rest_statistic : callable, optional
        ``rest_statistic(frames, fs) -> 1-D array``: the signed statistic whose
        spread at rest sets the method's threshold
        (:func:`slipreflex.methods.baselines.rest_threshold`); None when the method
        needs no calibration.
    color : str
        Its colour in every figure (a matplotlib colour).
    paper : bool
        One of the paper's four methods (run by default).
    threshold_unit : str
        Unit of its calibrated threshold, for the report ("N/s").

    Examples
    --------
    >>> get("fixed").paper, get("fixed").rest_statistic is None
    (True, True)
    """

    name: str
    label: str
    input_kind: InputKind
    fs: float
    build: Callable[..., Reflex]
    ramp: bool = False
    detections: Callable[[Any, np.ndarray], Detections] | None = None
    rest_statistic: Callable[[np.ndarray, float], np.ndarray] | None = None
    color: str = "0.5"
    paper: bool = False
    threshold_unit: str = ""

    def __post_init__(self) -> None:
        text("MethodSpec.name", self.name)
        if not _NAME.match(self.name):
            raise ParameterError(f"MethodSpec.name must be lower case letters, digits, '-', '_' or '.', "
                                 f"starting with a letter, got {self.name!r}")
        text("MethodSpec.label", self.label)
        choice("MethodSpec.input_kind", self.input_kind, ("slip", "tactile"))
        object.__setattr__(self, "fs", positive("MethodSpec.fs", self.fs))
        for name in ("build", "detections", "rest_statistic"):
            v = getattr(self, name)
            if not callable(v) and not (v is None and name != "build"):
                raise ParameterError(f"MethodSpec.{name} must be callable, got {v!r}")
        flag("MethodSpec.ramp", self.ramp)
        flag("MethodSpec.paper", self.paper)


#: The method registry (the order is the one method order everywhere); the functions below read it.
#: Entry-point group through which installed packages add methods (see :func:`load_plugins`).
ENTRY_POINT_GROUP: str = "slipreflex.methods"
METHODS: Registry[MethodSpec] = Registry("method", MethodSpec, any_case=True, group=ENTRY_POINT_GROUP)


def load_plugins() -> tuple[str, ...]:
    """Register the methods that installed packages declare as entry points (once per process).

    A package adds methods to every ``slipreflex`` command by declaring, in its
    ``pyproject.toml``::

        [project.entry-points."slipreflex.methods"]
        my-method = "my_package.methods:MY_METHODS"

    where the object is a :class:`MethodSpec`, a sequence of them, or a
    function returning either. Entry points are read in name order the first
    time the registry is asked for a method; a method already registered under
    the same name is kept.

    Returns
    -------
    tuple of str
        The names added by this call.

    Raises
    ------
    ParameterError
        When an entry point cannot be loaded or does not give MethodSpecs (naming it).

    Examples
    --------
    >>> load_plugins()          # nothing installed declares one here, and it runs once
    ()
    """
    return METHODS.load_entry_points()


def register(spec: MethodSpec, *, replace: bool = False) -> None:
    """Add ``spec`` to the registry (at the end of the method order).

    Parameters
    ----------
    spec : MethodSpec
    replace : bool
        Allow replacing a method of the same name (keeps its place).

    Examples
    --------
    >>> register(get("dath"))
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: method 'dath' is already registered (pass replace=True)
    """
    METHODS.register(spec, replace=replace)


def unregister(name: str) -> None:
    """Remove a method from the registry.

    Examples
    --------
    >>> register(chain_method("tmp", "tmp")); unregister("TMP"); "tmp" in names()
    False
    """
    METHODS.unregister(name)


def canonical(name: str) -> str:
    """The registered name ``name`` refers to (any case).

    Raises
    ------
    ParameterError
        ``"method: unknown 'x' (known: fixed, dath, ...)"``.

    Examples
    --------
    >>> canonical("SWT")
    'swt'
    """
    return METHODS.canonical(name)


def get(name: str) -> MethodSpec:
    """The specification of a registered method (any case).

    Examples
    --------
    >>> get("Nmsd").fs
    260.0
    """
    return METHODS.get(name)


def names(*, paper: bool = False) -> tuple[str, ...]:
    """Registered method names in the one method order (``paper=True``: the paper's four).

    Examples
    --------
    >>> names(paper=True)
    ('dath', 'fixed', 'nmsd', 'swt')
    """
    return tuple(s.name for s in METHODS.specs() if s.paper or not paper)


def calibrated() -> tuple[str, ...]:
    """Methods whose threshold is calibrated at rest (they have a ``rest_statistic``), in order.

    Examples
    --------
    >>> calibrated()[:2]
    ('nmsd', 'swt')
    """
    return tuple(s.name for s in METHODS.specs() if s.rest_statistic is not None)


def label(name: str) -> str:
    """The label of a method for tables; an unregistered name labels itself.

    Examples
    --------
    >>> label("swt"), label("not-a-method")
    ('SWT-SD', 'not-a-method')
    """
    spec = METHODS.find(name)
    return spec.label if spec else str(name)


def make(name: str, *, p0: float = 0.0, context: MethodContext | None = None, **params: Any) -> Reflex:
    """Build a fresh reflex of the method ``name``.

    Parameters
    ----------
    name : str
        A registered method (any case).
    p0 : float
        Starting finger position (the grasp's).
    context : MethodContext, optional
        Calibrated thresholds, closing speed and run options.
    **params
        The method's own parameters, overriding its defaults and the context
        (an unknown one is an error of the method's parameter class).

    Examples
    --------
    >>> make("swt", context=MethodContext(thresholds={"swt": 0.02}, speed=500.0)).params.threshold
    0.02
    >>> make("dath", p0=200.0, kp=3.0).params.kp
    3.0
    """
    spec = get(name)
    ctx = dataclasses.replace(context or MethodContext(), method=spec.name)
    return spec.build(float(p0), ctx, **params)


#: What each input kind is, for messages.
INPUT_NAMES: dict[str, str] = {"slip": "slip-sensor samples", "tactile": "tactile frames"}


def applicable(name: str, supplies: tuple[str, ...] | frozenset[str] | set[str], where: str) -> MethodSpec:
    """The specification of ``name`` after checking its input is one ``where`` supplies.

    Parameters
    ----------
    name : str
        A registered method (any case).
    supplies : collection of {"slip", "tactile"}
        The input kinds the command's source gives.
    where : str
        What supplies them, for the message ("detect's CSV of slip-sensor volts").

    Raises
    ------
    ParameterError
        One line: an unknown method, or one whose input is not supplied, naming the
        methods that would apply.

    Examples
    --------
    >>> applicable("DATH-event", {"slip"}, "the DAQ").name
    'dath-event'
    >>> applicable("nmsd", {"slip"}, "the DAQ")      # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    slipreflex.core.errors.ParameterError: --method nmsd reads tactile frames, which the DAQ does not supply ...
    """
    spec = get(name)
    if spec.input_kind not in supplies:
        fits = [s.name for s in METHODS.specs() if s.input_kind in supplies]
        raise ParameterError(f"--method {spec.name} reads {INPUT_NAMES[spec.input_kind]}, which {where} does "
                             f"not supply (methods that apply: {', '.join(fits) or 'none'})")
    return spec


# --- the built-in methods -------------------------------------------------------------------
# The registry sits below the implementations it lists: a built-in's builder, detection drawing
# and rest statistic are named by entry point ("module:function", :class:`EntryPoint`) and
# imported when first called, so this module imports none of chain, baselines, board or sim.


def chain_method(name: str, label: str, *, color: str = "0.5", paper: bool = False,
                 **chain_params: Any) -> MethodSpec:
    """The specification of a method that is the paper's chain with other parameters.

    Parameters
    ----------
    name, label : str
        Registry name and table label.
    color : str
        Figure colour.
    paper : bool
        One of the paper's methods.
    **chain_params
        Keyword parameters of :class:`slipreflex.methods.chain.SlipReflex`
        (``dath``, ``threshold``, ``dath_samples``, ``n``, ``kp``, ...); the
        chain runs at the DAQ's rate unless ``fs`` is given.

    Examples
    --------
    >>> spec = chain_method("dath-n8", "DATH, N = 8", dath=True, n=8)
    >>> spec.build(150.0, MethodContext()).params.n, spec.input_kind
    (8, 'slip')
    """
    fs = chain_params.get("fs", hw.DAQ_FS)
    return MethodSpec(name=name, label=label, input_kind="slip", fs=fs,
                      build=EntryPoint("slipreflex.methods.chain.builders:build_chain", (dict(chain_params), name)),
                      detections=_CHAIN_DETECTIONS, color=color, paper=paper)


_CHAIN_DETECTIONS = EntryPoint("slipreflex.methods.chain.builders:chain_detections")

# the paper's table order (DATH, fixed, NMSD, SWT-SD) is the one method order everywhere
register(chain_method(DATH, "DATH", dath=True, color="#1f77b4", paper=True))
register(chain_method(FIXED, "fixed", dath=False, color="#ff7f0e", paper=True))
register(MethodSpec(name=NMSD, label="NMSD", input_kind="tactile", fs=hw.NMSD_FS,
                    build=EntryPoint("slipreflex.methods.baselines.builders:build_nmsd"), ramp=True,
                    detections=EntryPoint("slipreflex.methods.baselines.builders:nmsd_method_detections"),
                    rest_statistic=EntryPoint("slipreflex.methods.baselines.nmsd:nmsd_rest_statistic"),
                    color="#2ca02c", paper=True, threshold_unit="N/s"))
register(MethodSpec(name=SWT, label="SWT-SD", input_kind="tactile", fs=hw.SWT_FS,
                    build=EntryPoint("slipreflex.methods.baselines.builders:build_swt"), ramp=True,
                    detections=EntryPoint("slipreflex.methods.baselines.builders:swt_method_detections"),
                    rest_statistic=EntryPoint("slipreflex.methods.baselines.swt:swt_rest_statistic"),
                    color="#d62728", paper=True, threshold_unit="N"))

# The paper's chain as the microcontroller runs it (fixed point, slipreflex.methods.board): beside the
# float chain in `reproduce --methods dath,dath-board`; not one of the paper's methods.
_BOARD_DETECTIONS = EntryPoint("slipreflex.methods.board:board_method_detections")
register(MethodSpec(name="dath-board", label="DATH (board)", input_kind="slip", fs=hw.DAQ_FS,
                    build=EntryPoint("slipreflex.methods.board:build_board_method", (True,)),
                    detections=_BOARD_DETECTIONS, color="#17becf"))
register(MethodSpec(name="fixed-board", label="fixed (board)", input_kind="slip", fs=hw.DAQ_FS,
                    build=EntryPoint("slipreflex.methods.board:build_board_method", (False,)),
                    detections=_BOARD_DETECTIONS, color="#bcbd22"))


# Variants of the paper's chain (docs/method.md, "Variants"), beside the paper's methods in
# `reproduce --methods fixed,dath,nmsd,swt,authors-gui,dath-event`; not run by default.
AUTHORS_GUI, AUTHORS_CHAIN, DATH_EVENT = "authors-gui", "authors-chain", "dath-event"
DATH_FLOOR, DATH_LEAK = "dath-floor", "dath-leak"


def _preset(preset: str, name: str, fixed: Mapping[str, Any] | None = None) -> EntryPoint:
    return EntryPoint("slipreflex.methods.chain.builders:build_preset", (preset, name, dict(fixed or {})))


register(MethodSpec(name=AUTHORS_GUI, label="authors' GUI", input_kind="slip", fs=hw.DAQ_FS,
                    build=_preset(AUTHORS_GUI, AUTHORS_GUI), detections=_CHAIN_DETECTIONS, color="#9467bd"))
# the authors' chain with the paper's hand rule (every finger at the command): what the +20 does
register(MethodSpec(name=AUTHORS_CHAIN, label="authors' chain, no +20", input_kind="slip", fs=hw.DAQ_FS,
                    build=_preset(AUTHORS_GUI, AUTHORS_CHAIN, {"slip_finger_offset": 0.0}),
                    detections=_CHAIN_DETECTIONS, color="#7f7f7f"))
register(MethodSpec(name=DATH_EVENT, label="DATH, event MPI", input_kind="slip", fs=hw.DAQ_FS,
                    build=_preset(DATH_EVENT, DATH_EVENT), detections=_CHAIN_DETECTIONS, color="#8c564b"))
# DATH whose threshold never drops below one ADC step (docs/method.md, "A DATH floor")
register(chain_method(DATH_FLOOR, "DATH, floor 1 LSB", dath=True, dath_floor=hw.ADC_LSB, color="#e377c2"))
# DATH whose accumulator forgets with a 0.1 s time constant (docs/method.md, "An accumulator that forgets")
register(chain_method(DATH_LEAK, "DATH, leak 0.1 s", dath=True, acc_leak=round(0.1 * hw.DAQ_FS, 6),
                      color="#aec7e8"))

# The fixed-threshold chain whose encoder is a spiking graph (docs/neuromorphic.md): the graph the
# `nir export` command writes, or any NIR graph through `--nir-graph FILE`; not run by default.
NIR = "nir"
register(MethodSpec(name=NIR, label="NIR graph", input_kind="slip", fs=hw.DAQ_FS,
                    build=EntryPoint("slipreflex.neuro.method:build_nir"),
                    detections=EntryPoint("slipreflex.neuro.method:nir_detections"), color="#ff9896"))


def nir_method(graph: str) -> MethodSpec:
    """The ``nir`` method bound to the NIR graph file ``graph`` (what ``--nir-graph FILE`` registers).

    Examples
    --------
    >>> nir_method("fixed.nir").build.args
    ('fixed.nir',)
    """
    spec = get(NIR)
    return dataclasses.replace(spec, build=EntryPoint("slipreflex.neuro.method:build_nir_file", (graph,)))

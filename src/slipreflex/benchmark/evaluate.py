"""The operating-point benchmark over a data set: every method swept, chosen on training trials, scored held out.

:func:`evaluate` ties :mod:`~slipreflex.benchmark.sweep` (detections at every threshold) to
:mod:`~slipreflex.benchmark.protocol` (folds, choice, scores, curves) for every method that
applies, the energy statistic and the learned baseline included. A threshold given in the
data's units (``thresholds``) or calibrated on a separate rest recording (:func:`rest_thresholds`)
replaces the choice for that method in every fold.

Examples
--------
>>> from slipreflex.benchmark import read_folder, shipped_dataset
>>> ev = evaluate(read_folder(shipped_dataset()), methods=("energy",), protocol=ProtocolConfig(bootstrap=20))
>>> ev.kind, [p.method for p in ev.points], ev.points[0].slip_trials
('onset', ['energy'], 3)
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from .. import methods as registry
from ..core.errors import DataError, ParameterError
from ..methods.baselines import rest_threshold
from ..methods.chain import run_chain
from . import learned
from .protocol import OperatingPoint, ProtocolConfig, folds, operating_point
from .run import Skipped, _check_data_rate, _scaled, _trial_reflex, applicable
from .sweep import (
    AGGREGATIONS,
    BASELINES,
    ENERGY,
    LEARNED,
    Sweep,
    channel_inputs,
    energy_statistic,
    grid,
    prepare,
    statistic_detector,
    sweeps_of,
)
from .trials import RecordedTrial

__all__ = ["Evaluation", "evaluate", "method_names", "rest_thresholds", "channel_note", "select_channels"]


@dataclass(frozen=True)
class Evaluation:
    """Every method's operating point on one data set.

    Attributes
    ----------
    kind : str
        ``"onset"`` or ``"trial"`` (trial-level labels: classification).
    points : list of OperatingPoint
    skipped : list of Skipped
        Methods that did not run, and why.
    same : dict
        ``method@rate`` of a method left out of ``points`` -> the one whose scores it repeats
        at every threshold.
    fixed : dict
        Method -> the threshold it was given (data's units), not chosen.
    protocol : ProtocolConfig
    split : str
        How the trials were split, in words.
    channels : str
        What the chain methods read and how channels were aggregated, in words.

    Examples
    --------
    >>> Evaluation("onset", [], [], {}, {}, ProtocolConfig(), "leave-one-trial-out", "").kind
    'onset'
    """

    kind: str
    points: list[OperatingPoint]
    skipped: list[Skipped]
    same: dict[str, str]
    fixed: dict[str, float]
    protocol: ProtocolConfig
    split: str
    channels: str
    trials: int = 0
    positives: int = 0
    negative_min: float = 0.0
    rates_hz: tuple[float, float] = field(default=(np.nan, np.nan))
    interrupted: bool = False


def select_channels(trials: Sequence[RecordedTrial], names: Sequence[str] | None) -> list[RecordedTrial]:
    """The trials with only the channel columns ``names`` (their layout dropped); unchanged for None.

    Raises
    ------
    ParameterError
        A name that is not a channel of every trial.

    Examples
    --------
    >>> from slipreflex.benchmark import read_folder, shipped_dataset
    >>> tr = select_channels(read_folder(shipped_dataset())[:1], ["s1_txl1_z"])[0]
    >>> tr.channel_names, tr.layout
    (('s1_txl1_z',), None)
    """
    if not names:
        return list(trials)
    out = []
    for tr in trials:
        missing = [n for n in names if n not in tr.channel_names]
        if missing:
            more = ", ..." if len(tr.channel_names) > 8 else ""
            raise ParameterError(f"--channels: {missing[0]!r} is not a channel of {tr.path} "
                                 f"(its channels: {', '.join(tr.channel_names[:8])}{more})")
        idx = [tr.channel_names.index(n) for n in names]
        out.append(dataclasses.replace(tr, channels=tr.channels[:, idx], channel_names=tuple(names), layout=None))
    return out


def channel_note(trials: Sequence[RecordedTrial], reduction: str, aggregate: str, chosen: bool) -> str:
    """What the methods read, in words (printed above every table).

    Examples
    --------
    >>> from slipreflex.benchmark import read_folder, shipped_dataset
    >>> channel_note(read_folder(shipped_dataset())[:1], "z-sum", "any", False)[:40]
    'layout 2x4x4x3: the chain methods read z'
    """
    tr = trials[0]
    n = len(tr.channel_names)
    if tr.layout is not None:
        shape = "x".join(str(d) for d in tr.layout.shape)
        return (f"layout {shape}: the chain methods read {reduction}, NMSD and SWT-SD the normal component of "
                f"each of {tr.layout.taxels} taxels (an alarm on any taxel counts); energy and learned read all "
                f"{n} channels")
    head = f"{n} channel(s){' chosen by --channels' if chosen else ', no layout line'}"
    what = {"any": "each channel on its own with the same threshold, an alarm on any channel counting",
            "sum": "the sum of the channels' changes", "magnitude": "the length of the vector of the channels' changes"}
    return (f"{head}: aggregation {aggregate}: the chain methods read {what[aggregate]}; energy and learned read "
            f"all {n}; NMSD and SWT-SD need a layout")


def method_names(trials: Sequence[RecordedTrial], asked: Sequence[str] | None) -> tuple[list[str], list[Skipped]]:
    """Methods to run (registered ones that apply to every trial, then the baselines) and those skipped.

    Examples
    --------
    >>> from slipreflex.benchmark import read_folder, shipped_dataset
    >>> names, skipped = method_names(read_folder(shipped_dataset()), None)
    >>> names[:2], "energy" in names, [s.method for s in skipped][:2]
    (['dath', 'fixed'], True, ['dath-board', 'fixed-board'])
    """
    wanted = list(asked) if asked else [*registry.names(), *BASELINES]
    names, skipped = [], []
    for name in wanted:
        if name in BASELINES:
            why = learned.available() if name == LEARNED else None
        else:
            why = next((r for r in (applicable(name, tr) for tr in trials) if r), None)
        if why:
            skipped.append(Skipped(name, why))
        else:
            names.append(name)
    if asked and skipped:
        raise ParameterError(f"--methods: {skipped[0].method} does not apply to this data: it {skipped[0].reason}")
    return names, skipped


def rest_thresholds(rest: RecordedTrial, names: Sequence[str], rate: str, k: float, *, reduction: str = "z-sum",
                    aggregate: str = "any") -> dict[str, float]:
    """Thresholds from a separate rest recording: ``k`` sd of each method's statistic over all of it.

    A chain method's statistic is its low-passed input minus its mean (the largest over
    channels read on their own); NMSD's and SWT-SD's their rest statistics; the energy's
    its mean plus ``k`` sd. The learned baseline keeps its chosen threshold.

    Raises
    ------
    DataError
        A rest recording on which a method's statistic does not vary.

    Examples
    --------
    >>> from slipreflex.benchmark import read_folder, shipped_dataset
    >>> thr = rest_thresholds(read_folder(shipped_dataset())[0], ["fixed", "energy"], "data", 5.0)
    >>> sorted(thr), thr["fixed"] > 0
    (['energy', 'fixed'], True)
    """
    out: dict[str, float] = {}
    for name in names:
        if name == LEARNED:
            continue
        if name == ENERGY:
            e = energy_statistic(rest.channels, rest.fs)
            out[name] = float(e.mean() + k * e.std())
        elif registry.get(name).input_kind == "slip":
            spec, base = registry.get(name), _trial_reflex(name)
            sds = []
            for _, x in channel_inputs(rest, reduction, aggregate):
                det = prepare(name, rest, rate, reduction=reduction, aggregate=aggregate)
                over = {"fs": det.fs, **(_scaled(base, spec.fs, det.fs) if rate == "data" else {})}
                sds.append(float(np.std(run_chain(x, dataclasses.replace(base.params, **over)).filtered)))
            out[name] = k * max(sds)
        else:
            frames = rest.normal_frames()
            out[name] = rest_threshold(frames - frames[0], name, rest.fs, k=k)
        if not out[name] > 0:
            raise DataError(f"{rest.path}: {name}'s statistic does not vary on the rest recording; "
                            "give its threshold with --threshold")
    return out


def _learned_sweeps(trials, splits, cfg: ProtocolConfig, reduction: str, aggregate: str):
    per_fold = []
    for train, _ in splits:
        model = learned.fit([trials[i] for i in train], tolerance_s=cfg.tolerance_s, seed=cfg.seed,
                            reduction=reduction, aggregate=aggregate)
        dets = [statistic_detector(LEARNED, "data", tr.t, tr.fs,
                                   learned.probability(model, tr, reduction=reduction, aggregate=aggregate))
                for tr in trials]
        per_fold.append(sweeps_of(dets, trials, learned.PROBABILITY_GRID, refractory_s=cfg.refractory_s,
                                  tolerance_s=cfg.tolerance_s))
    return per_fold


def _sweeps(name: str, rate: str, trials, given: float | None, protocol: ProtocolConfig, reduction: str,
            aggregate: str) -> tuple[list[Sweep], int | None]:
    """Every trial's sweep of a registered method or the energy, and the given threshold's grid index."""
    dets = [prepare(name, tr, rate, reduction=reduction, aggregate=aggregate) for tr in trials]
    thr = grid(max(d.top for d in dets))
    fix = None
    if given is not None:
        thr = np.unique(np.r_[thr, given])
        fix = int(np.searchsorted(thr, given))
    return sweeps_of(dets, trials, thr, refractory_s=protocol.refractory_s,
                     tolerance_s=protocol.tolerance_s), fix


def _same(a: Sequence[Sweep], b: Sequence[Sweep]) -> bool:
    return all(np.array_equal(x.thresholds, y.thresholds) and np.array_equal(x.hit, y.hit)
               and np.array_equal(x.false_alarms, y.false_alarms)
               and np.array_equal(x.latency_ms, y.latency_ms, equal_nan=True) for x, y in zip(a, b))


def evaluate(trials: Sequence[RecordedTrial], *, methods: Sequence[str] | None = None,
             rates: Sequence[str] = ("data",), reduction: str = "z-sum", aggregate: str = "any",
             protocol: ProtocolConfig | None = None, thresholds: Mapping[str, float] | None = None,
             channels_chosen: bool = False,
             on_method: Callable[[str], None] | None = None) -> Evaluation:
    """Every method (``methods``, or every one that applies) at every rate, by the protocol.

    Raises
    ------
    ParameterError
        An unknown aggregation, a threshold for a method that is not run, a bad split.

    Examples
    --------
    >>> from slipreflex.benchmark import read_folder, shipped_dataset
    >>> ev = evaluate(read_folder(shipped_dataset()), methods=("fixed",), thresholds={"fixed": 1e9},
    ...               protocol=ProtocolConfig(bootstrap=0))
    >>> ev.points[0].detected, ev.points[0].false_alarms, ev.fixed
    (0, 0, {'fixed': 1000000000.0})
    """
    protocol = protocol or ProtocolConfig()
    if aggregate not in AGGREGATIONS:
        raise ParameterError(f"--aggregate: unknown {aggregate!r} (known: {', '.join(AGGREGATIONS)})")
    names, skipped = method_names(trials, methods)
    fixed = dict(thresholds or {})
    for m in fixed:
        if m not in names:
            raise ParameterError(f"--threshold: {m} is not among the methods run ({', '.join(names)})")
    if "data" in rates:
        _check_data_rate([n for n in names if n not in BASELINES], trials)
    kind = "trial" if trials[0].trial_label is not None else "onset"
    splits = folds([tr.name for tr in trials], protocol.test)
    held = [i for _, h in splits for i in h]
    held_fold = {i: f for f, (_, h) in enumerate(splits) for i in h}
    points: list[OperatingPoint] = []
    seen: dict[str, list[Sweep]] = {}
    same: dict[str, str] = {}
    interrupted = False
    try:
        for rate in rates:
            for name in names:
                if name in BASELINES and rate != "data":
                    continue
                if on_method is not None:
                    on_method(f"{name}@{rate}")
                fix = None
                if name == LEARNED:
                    per_fold = _learned_sweeps(trials, splits, protocol, reduction, aggregate)
                    held_out = [per_fold[held_fold[i]][i] for i in held]
                else:
                    sw, fix = _sweeps(name, rate, trials, fixed.get(name), protocol, reduction, aggregate)
                    twin = next((k for k, v in seen.items() if k.endswith("@" + rate) and _same(v, sw)), None)
                    if twin is not None and name not in fixed:
                        same[f"{name}@{rate}"] = twin
                        continue
                    seen[f"{name}@{rate}"] = sw
                    per_fold = [sw] * len(splits)
                    held_out = [sw[i] for i in held]
                points.append(operating_point(name, rate, kind, per_fold, held_out, splits, protocol, fixed=fix))
    except KeyboardInterrupt:            # the methods finished so far are kept, marked partial
        interrupted = True
    split = ("leave-one-trial-out" if protocol.test is None else
             f"declared split: {len(held)} held-out trial(s) ({', '.join(protocol.test)}), "
             f"{len(trials) - len(held)} training")
    fs = [tr.fs for tr in trials]
    return Evaluation(kind, points, skipped, same, fixed, protocol, split,
                      channel_note(trials, reduction, aggregate, channels_chosen), len(trials),
                      sum(tr.positive for tr in trials), points[0].negative_min if points else 0.0,
                      (min(fs), max(fs)), interrupted)

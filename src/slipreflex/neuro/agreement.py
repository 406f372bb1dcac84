"""The graphs held against Eq. 1-9, stage by stage, on recorded and simulated signals.

For one signal, :func:`compare` runs the chain (:func:`slipreflex.methods.chain.run_chain`: the paper's
rules, fixed threshold or DATH) and a graph in a backend, and counts:

* spikes: the chain's spikes that the graph also fires, same polarity, at the same sample
  and within one sample; and the graph's spikes the chain also fires within one sample;
* windows (Eq. 3): windows whose spike count is equal;
* commands (Eq. 5-9): windows whose MPI command is equal.

The host stages are the chain's own (the same filter output feeds both; the windows and the
MPI read the graph's spikes with the chain's batch functions), so every difference is the
encoder's. Signals (:func:`signals`): the shipped example recording, the shipped data set's
trials (their tactile channel reduced and resampled to the DAQ rate as ``benchmark`` does,
threshold by the benchmark's rest rule), and open-loop simulated drops and pours on each of
the paper's bottles.

Examples
--------
>>> import numpy as np
>>> sig = Signal("step", "demo", np.r_[np.full(48, 0.4), np.full(48, 0.45)], 333.33, 0.008)
>>> a = compare(sig, "fixed", "reference")
>>> a.chain_spikes == a.graph_spikes == a.same_sample, a.windows == a.windows_equal
(True, True)
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..benchmark import BenchmarkConfig, read_folder, shipped_dataset
from ..benchmark.run import reduce_channels, to_rate
from ..core import hardware as hw
from ..files.csvfiles import read_slip_csv
from .backends import run_backend
from .graph import chain_graph

__all__ = ["Signal", "Agreement", "compare", "measure", "signals", "shipped_signals", "simulated_signals", "table",
           "stage_table", "GRAPHS", "GROUPS"]

#: The graphs held against the chain: the fixed-threshold chain's and DATH's closest.
GRAPHS: tuple[str, ...] = ("fixed", "dath")

#: Signal groups, in table order.
GROUPS: tuple[str, ...] = ("example", "imanlab", "drop", "pour")


@dataclass(frozen=True)
class Signal:
    """Raw slip-sensor-like samples at ``fs``, with the encoder threshold that suits them.

    Examples
    --------
    >>> Signal("a", "demo", np.zeros(3), 333.33, 0.008).raw.size
    3
    """

    name: str
    group: str
    raw: np.ndarray
    fs: float
    threshold: float


@dataclass(frozen=True)
class Agreement:
    """Counts of one graph in one backend against the chain on one signal (or summed over several).

    Examples
    --------
    >>> Agreement("g", "fixed", "reference", 4, 4, 4, 4, 4, 2, 2, 2).spike_share
    1.0
    """

    group: str
    graph: str
    backend: str
    chain_spikes: int
    graph_spikes: int
    same_sample: int
    within_one: int
    graph_matched: int
    windows: int
    windows_equal: int
    commands_equal: int

    @property
    def spike_share(self) -> float:
        """Share of the chain's spikes the graph fires within one sample (1.0 when there are none)."""
        return self.within_one / self.chain_spikes if self.chain_spikes else 1.0

    def __add__(self, other: Agreement) -> Agreement:
        counts = [getattr(self, f) + getattr(other, f) for f in _COUNTS]
        return Agreement(self.group, self.graph, self.backend, *counts)


_COUNTS = ("chain_spikes", "graph_spikes", "same_sample", "within_one", "graph_matched", "windows",
           "windows_equal", "commands_equal")


def _polarity(spikes: np.ndarray) -> np.ndarray:
    pol = np.zeros(spikes.shape[0], dtype=np.int8)
    pol[spikes[:, 0] > 0] = 1
    if spikes.shape[1] > 1:
        pol[(spikes[:, 1] > 0) & (pol == 0)] = -1
    return pol


def _matched(a: np.ndarray, b: np.ndarray, reach: int) -> int:
    """Spikes of ``a`` with a spike of the same polarity in ``b`` at most ``reach`` samples away."""
    hit = np.zeros(a.size, dtype=bool)
    for shift in range(-reach, reach + 1):
        moved = np.roll(b, shift)
        if shift > 0:
            moved[:shift] = 0
        elif shift < 0:
            moved[shift:] = 0
        hit |= (a != 0) & (moved == a)
    return int(hit.sum())


def compare(signal: Signal, graph: str, backend: str) -> Agreement:
    """One graph (``"fixed"`` or ``"dath"``) in one backend against the chain on one signal.

    Examples
    --------
    >>> rise = Signal("rise", "demo", 0.4 + np.linspace(0.0, 0.2, 64), 333.33, 0.008)
    >>> a = compare(rise, "fixed", "reference")
    >>> a.chain_spikes > 0 and a.same_sample == a.chain_spikes
    True
    """
    from ..methods.chain import count_windows, mpi, run_chain  # deferred: heavy (numba kernels)

    dath = graph == "dath"
    res = run_chain(signal.raw, fs=signal.fs, threshold=signal.threshold, dath=dath, p0=100.0)
    p = res.params
    chain_pol = np.where(res.events, np.sign(res.accumulator), 0).astype(np.int8)
    x = res.filtered
    d = np.diff(x, prepend=x[:1] if p.x0 is None else p.x0)
    g = chain_graph(p.threshold, dath=dath, fs=p.fs)
    graph_pol = _polarity(run_backend(backend, g, d[:, None]))
    counts = count_windows(graph_pol != 0, p.n)
    commands = mpi(counts, p0=p.p0, kp=p.kp, ki=p.ki, reset_after=p.reset_after, lo=p.lo, hi=p.hi)
    return Agreement(
        signal.group, graph, backend, int((chain_pol != 0).sum()), int((graph_pol != 0).sum()),
        _matched(chain_pol, graph_pol, 0), _matched(chain_pol, graph_pol, 1), _matched(graph_pol, chain_pol, 1),
        int(counts.size), int((counts == res.counts).sum()), int((commands == res.commands).sum()))


def shipped_signals() -> list[Signal]:
    """The shipped example recording and the shipped data set's seven trials.

    Examples
    --------
    >>> [s.group for s in shipped_signals()][:2]
    ['example', 'imanlab']
    """
    from ..methods.chain import run_chain  # deferred: heavy (numba kernels)

    example = Path(__file__).resolve().parents[3] / "examples" / "slip_example.csv"
    out = []
    if example.is_file():                       # a source checkout; an installed wheel has no examples/
        _, raw = read_slip_csv(example)
        out.append(Signal("slip_example.csv", "example", raw, hw.DAQ_FS, 0.008))
    cfg = BenchmarkConfig()
    for trial in read_folder(shipped_dataset()):
        (_, x), = reduce_channels(trial, cfg.reduction)
        t, x, fs = to_rate(trial.t, x, hw.DAQ_FS)
        rest = run_chain(x[t < t[0] + cfg.calibration_s], fs=fs).filtered
        out.append(Signal(trial.path.name, "imanlab", x, fs, float(cfg.rest_k * np.std(rest))))
    return out


def simulated_signals(seeds: tuple[int, ...] = (0, 1)) -> list[Signal]:
    """Open-loop simulated drops and pours on each of the paper's bottles (no reflex acts).

    Each run: the grasp, 1 s at rest, the paper's drop (then 2 s) or pour (its whole
    length, then 2 s), the slip sensor's volts at the DAQ rate.

    Examples
    --------
    >>> [s.name for s in simulated_signals(seeds=(0,))][:2]       # doctest: +SKIP
    ['drop TR seed 0', 'drop DK seed 0']
    """
    from ..sim import BOTTLES, PAPER_DROP, PAPER_POUR, Rig, simulate_open_loop  # deferred: heavy (numba)

    out = []
    for kind, what in (("drop", PAPER_DROP), ("pour", PAPER_POUR)):
        length = 2.0 if kind == "drop" else PAPER_POUR.volume_ml / 1000 / PAPER_POUR.rate_l_min * 60 + 2.0
        for bottle in BOTTLES:
            for seed in seeds:
                rig = Rig(bottle, seed=seed)
                rig.grasp()
                rig.perturb(what, at=rig.t + 1.0)
                tr = simulate_open_loop(rig, 1.0 + length)
                out.append(Signal(f"{kind} {bottle} seed {seed}", kind, np.asarray(tr.volts), hw.DAQ_FS, 0.008))
    return out


def signals(simulated: bool = True) -> list[Signal]:
    """Every signal of the agreement table.

    Examples
    --------
    >>> sorted({s.group for s in signals(simulated=False)})
    ['example', 'imanlab']
    """
    return shipped_signals() + (simulated_signals() if simulated else [])


def measure(backends: tuple[str, ...], *, simulated: bool = True) -> list[Agreement]:
    """Both graphs in every backend of ``backends`` on every signal (:func:`signals`).

    Examples
    --------
    >>> rows = measure(("reference",), simulated=False)           # doctest: +SKIP
    >>> sorted({r.graph for r in rows})                           # doctest: +SKIP
    ['dath', 'fixed']
    """
    sigs = signals(simulated=simulated)
    return [compare(s, g, b) for g in GRAPHS for b in backends for s in sigs]


def summed(rows: list[Agreement]) -> dict[tuple[str, str, str], Agreement]:
    """Rows summed per (graph, backend, group).

    Examples
    --------
    >>> a = Agreement("drop", "fixed", "reference", 1, 1, 1, 1, 1, 2, 2, 2)
    >>> summed([a, a])[("fixed", "reference", "drop")].windows
    4
    """
    out: dict[tuple[str, str, str], Agreement] = {}
    for r in rows:
        key = (r.graph, r.backend, r.group)
        out[key] = out[key] + r if key in out else r
    return out


def _share(n: int, of: int) -> str:
    return f"{n}/{of} ({100 * n / of:.1f} %)" if of else "-"


def table(rows: list[Agreement]) -> str:
    """The agreement table (markdown): one row per graph, backend and signal group.

    Examples
    --------
    >>> print(table([Agreement("drop", "fixed", "reference", 2, 2, 2, 2, 2, 4, 4, 4)]).splitlines()[-1])
    | fixed | reference | drop | 2 | 2/2 (100.0 %) | 2/2 (100.0 %) | 2/2 (100.0 %) | 4/4 (100.0 %) | 4/4 (100.0 %) |
    """
    head = ("| graph | backend | signals | chain spikes | same sample | within one sample | graph spikes "
            "matched | windows equal | commands equal |\n|---|---|---|---|---|---|---|---|---|")
    lines = [head]
    for (graph, backend, group), a in summed(rows).items():
        lines.append(f"| {graph} | {backend} | {group} | {a.chain_spikes} | {_share(a.same_sample, a.chain_spikes)} "
                     f"| {_share(a.within_one, a.chain_spikes)} | {_share(a.graph_matched, a.graph_spikes)} "
                     f"| {_share(a.windows_equal, a.windows)} | {_share(a.commands_equal, a.windows)} |")
    return "\n".join(lines)


def stage_table(rows: list[Agreement]) -> str:
    """Per stage of Eq. 1-9: where it runs, exact or approximate, and the measured agreement
    (all signals, the package's executor).

    Examples
    --------
    >>> stage_table([]).splitlines()[0]
    '| stage | equations | where | fixed-threshold graph | DATH graph |'
    """
    tot: dict[str, Agreement | None] = {g: None for g in GRAPHS}
    for r in rows:
        if r.backend == "reference":
            before = tot[r.graph]
            tot[r.graph] = r if before is None else before + r
    cells = {}
    for g, a in tot.items():
        if a is None:
            cells[g] = ("-", "-", "-")
            continue
        cells[g] = (f"within one sample {_share(a.within_one, a.chain_spikes)}, same sample "
                    f"{_share(a.same_sample, a.chain_spikes)}", _share(a.windows_equal, a.windows),
                    _share(a.commands_equal, a.windows))
    fx, dt = cells["fixed"], cells["dath"]
    return "\n".join([
        "| stage | equations | where | fixed-threshold graph | DATH graph |",
        "|---|---|---|---|---|",
        "| low-pass filter | section 1.1 | host (the chain's filter) | exact (same code) | exact (same code) |",
        "| change d_k = x_k - x_(k-1) | Eq. 1 | host | exact (same code) | exact (same code) |",
        "| accumulate and fire, reset to 0 | Eq. 1-2 | graph: Affine (+1, -1) into two IF neurons, each spike "
        "giving the other theta back (Linear, one step later) | approximate (two accumulators; the other neuron "
        f"keeps the overshoot): {fx[0]} | approximate: {dt[0]} |",
        "| DATH threshold | Eq. 4 | none (NIR has no adaptive threshold) | - | lost: theta0 throughout |",
        f"| spike counts per window | Eq. 3 | host (the chain's window counter) | exact given the spikes: {fx[1]} "
        f"equal | exact given the spikes: {dt[1]} equal |",
        f"| MPI: PI, max-hold, saturation, reset | Eq. 5-9 | host (the chain's MPI) | exact given the counts: "
        f"{fx[2]} equal | exact given the counts: {dt[2]} equal |",
    ])

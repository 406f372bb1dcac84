"""The prose of report.md: the run's setup, the figure captions, the discussion.

Every number in it is read from its one definition. Re-exported by
:mod:`slipreflex.analysis.report`.

Examples
--------
>>> paper_figure("drop", "response")
'Fig. 13'
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from ... import methods
from ...core import experiment_specs
from ...core import hardware as hw
from ...methods import label as _label
from ...methods.baselines import CLOSE_S
from ...methods.baselines.swt import SWT_LEVEL
from ...methods.chain import ReflexParams
from ..onset import OnsetParams
from ..paper import BOTTLE_ORDER, EXPERIMENTS, PAPER, PAPER_SUCCESS, paper_value
from ..trial import MAX_RESPONSE_S, TrialRow
from .tables import _finite, void

__all__ = [
    "setup_lines", "discussion_text", "trial_caption", "zoom_caption", "bars_caption", "SUCCESS_CAPTION",
    "GRIP_CAPTION", "paper_figure"
]


# --- the prose of report.md: the run's setup, the figure captions, the discussion -------------
#
# Every number here is read from its one definition (the run's configuration, the method
# registry, the hardware constants, the analysis parameters, the paper's table), so the text
# follows --rest-k, --swt-persist, --drop-mass, --pour-volume and the rest.

def paper_figure(experiment: str, plot: str) -> str:
    """The paper's figure a plot of ``experiment`` is like ("" when the paper has none).

    Examples
    --------
    >>> paper_figure("pour", "total"), paper_figure("pour", "zoom")
    ('Fig. 17', '')
    """
    return experiment_specs.get(experiment).paper_figures.get(plot, "")


def _like_paper(experiment: str, plot: str) -> str:
    fig = paper_figure(experiment, plot)
    return f" (like the paper's {fig})" if fig else ""


def _median(values: Iterable[float]) -> float:
    v = [float(x) for x in values if _finite(x)]
    return float(np.median(v)) if v else float("nan")


def _and_join(words: Sequence[str]) -> str:
    return " and ".join(words) if len(words) <= 2 else ", ".join(words[:-1]) + " and " + words[-1]


def _window_ms() -> float:
    """One MPI window of the paper's chain (ms): N samples at the DAQ's rate."""

    return 1e3 * hw.WINDOW_N / hw.DAQ_FS


def _paper_success(experiment: str, method: str) -> str:
    return PAPER_SUCCESS.get((experiment, "all", method), "not reported")


def trial_caption(experiment: str, bottle: str, method: str) -> str:
    """Caption of one example trial's figure.

    Examples
    --------
    >>> trial_caption("drop", "TR", "dath")[:38]
    'One drop trial, bottle TR, method DATH'
    """
    return (f"One {experiment} trial, bottle {bottle}, method {_label(method)}{_like_paper(experiment, 'trial')}: "
            "I onset, II first response, III last change")


def zoom_caption(bottle: str, method: str, experiment: str) -> str:
    """Caption of the zoom on an example trial's slips.

    Examples
    --------
    >>> zoom_caption("DK", "dath", "pour")
    'The same pour trial zoomed on its slips, every axis scaled to the zoom (DK, DATH)'
    """
    return (f"The same {experiment} trial zoomed on its slips, every axis scaled to the zoom "
            f"({bottle}, {_label(method)})")


def bars_caption(experiment: str, metric: str) -> str:
    """Caption of a bar chart of ``metric`` ("response" or "total").

    Examples
    --------
    >>> bars_caption("pour", "total").startswith("Total controller time, pour (like the paper's Fig. 17)")
    True
    """
    what = "Response" if metric == "response" else "Total controller"
    return f"{what} time, {experiment}{_like_paper(experiment, metric)}; diamonds: the paper"


#: Caption of the success chart.
SUCCESS_CAPTION: str = ("Success per trial (bars) and per slip event (dots): the slip suppressed before the "
                        "bottle slipped out")
#: Caption of the grip-without-slip chart.
GRIP_CAPTION: str = ("Grip added without slip: how far the hand closed (finger units, mean ± sd per trial) "
                     "while no true slip was under way; a pre-emptive squeeze the response times do not show")


def setup_lines(result: Any, command: str | None = None) -> list[str]:
    """Bullet lines describing a run (a :class:`slipreflex.reproduce.experiments.ReproduceResult`).

    Examples
    --------
    >>> from slipreflex.reproduce.experiments import ReproduceConfig, ReproduceResult
    >>> r = ReproduceResult(ReproduceConfig(trials=1, rest_k=4), [], [], {"nmsd": 10.0, "swt": 0.02},
    ...                     {}, 3.0, 2)
    >>> [s for s in setup_lines(r) if "threshold" in s][0][:48]
    'NMSD threshold 10 N/s, SWT-SD threshold 0.02 N: '
    >>> "4 sd" in " ".join(setup_lines(r))
    True
    """

    c = result.config
    lines = [f"command: `{command}`"] if command else []
    lines += [
        f"grid: {c.trials} trials x bottles {', '.join(c.bottles)} x experiments "
        f"{', '.join(c.experiments)} x methods {', '.join(c.methods)} "
        f"= {c.trials * len(c.bottles) * len(c.experiments) * len(c.methods)} trials, "
        f"{len(result.rows)} result rows (slip events)",
        f"master seed {c.seed}; trial seeds spawned per experiment, bottle and trial "
        "(numpy SeedSequence), " + ("each method its own (independent seeds)" if getattr(c, "independent_seeds", False)
                                    else "shared by every method (paired comparison)")
        + ("; each trial's placement, grip height and friction vary from its seed (sim.variations)"
           if getattr(c, "variations", False) else "; every repeat is the nominal plant"),
        f"drop: {c.drop.mass_kg * 1e3:g} g from {c.drop.height_m * 1e2:g} cm above the opening; "
        f"pour: {c.pour.volume_ml:g} ml at {c.pour.rate_l_min:g} L/min ({c.pour.duration_s:.0f} s)",
        f"protocol: grasp to {getattr(c, 'grasp_force_n', hw.CONTACT_FORCE_N):g} N, "
        "settle (simulator's grasp routine), "
        f"{c.rest_s:g} s of rest recorded, perturbation, {c.after_s:g} s after it ends",
        _chain_line(),
    ]
    lines += _plant_lines(c)
    if result.thresholds:
        lines.append(_threshold_line(result.thresholds, c))
    return lines + _analysis_lines(c) + [
        f"wall time {result.wall_s:.1f} s on {result.jobs} worker process(es) "
        f"({os.cpu_count()} cores), calibration {result.calibration_wall_s:.1f} s"]


def _plant_lines(c: Any) -> list[str]:
    """The plant's open-loop first slip and contact friction, computed for the run's bottles."""
    from ...sim import BOTTLES  # deferred: heavy (numba kernels)
    from ...sim.calibration import plant_lines  # deferred: heavy (numba kernels)

    names = [b for b in c.bottles if b in BOTTLES]
    return plant_lines([BOTTLES[b] for b in names], getattr(c, "grasp_force_n", hw.CONTACT_FORCE_N)) if names else []


def _chain_line() -> str:

    rp = ReflexParams()
    return (f"{_label(methods.FIXED)} / {_label(methods.DATH)}: the paper's chain (theta0 = "
            f"{rp.threshold:g} V, D = {rp.dath_samples}, N = {rp.n}, Kp = {rp.kp:g}, Ki = {rp.ki:g}, "
            f"reset after {rp.reset_after} zero windows) at the DAQ's {hw.DAQ_FS:.2f} Hz")


def _threshold_line(thresholds: dict[str, float], c: Any) -> str:
    swt_fs = methods.get(methods.SWT).fs
    parts = [f"{_label(m)} threshold {v:.3g} {methods.get(m).threshold_unit}".rstrip()
             for m, v in thresholds.items()]
    return (", ".join(parts) + f": {c.rest_k:g} sd of each method's own statistic on "
            f"{c.calibration_s:g} s rest recordings of all three bottles (pooled), the same for every "
            f"bottle; SWT-SD persistence {c.swt_persist} samples ({1e3 * c.swt_persist / swt_fs:.0f} ms) "
            "after the crossing")


def _analysis_lines(c: Any) -> list[str]:
    from ...sim import BOTTLES  # deferred: heavy (numba kernels)

    op = OnsetParams()
    travel = sorted({c.bottle(b).grip_travel_m if hasattr(c, "bottle") else BOTTLES[b].grip_travel_m
                     for b in c.bottles})
    return [
        f"onset: paper's recipe with k = {op.k:g} sd over the first {op.baseline_s * 1e3:.0f} ms; slip "
        f"episodes must peak at {op.peak_factor:g}x the threshold; responses later than "
        f"{MAX_RESPONSE_S:g} s are not responses",
        "success: the bottle had not slipped out completely by the end of the slip's window; "
        "slipped out = the simulator's *fallen out*, the bottle has slid its grip travel ("
        + ", ".join(f"{x * 1e2:g} cm" for x in travel)
        + ") below where it was grasped, the fingertips reach the shoulder and lose contact",
    ]


class _Rows:
    """The rows of a run with the selections the discussion needs."""

    def __init__(self, result: Any) -> None:

        # rows read back from results.csv are dicts of strings: type them once
        self.rows = [r if isinstance(r, TrialRow) else TrialRow.from_dict(r) for r in result.rows if not void(r)]
        self.summary, self.config = result.summary, result.config

    def sel(self, **kw: Any) -> list[Any]:
        return [r for r in self.rows if all(r[k] == v for k, v in kw.items())]

    @staticmethod
    def pct(sub: Sequence[Any], pred: Any) -> str:
        return f"{100 * sum(1 for r in sub if pred(r)) / len(sub):.0f}% of {len(sub)}" if sub else "n/a"


def discussion_text(result: Any) -> list[str]:
    """Why our numbers differ from the paper's, with the figures computed from this run.

    Every number in the text comes from the run (its rows and configuration) or from
    its one definition in the package.

    Examples
    --------
    >>> from slipreflex.reproduce.experiments import ReproduceConfig, ReproduceResult
    >>> discussion_text(ReproduceResult(ReproduceConfig(trials=1), [], [], {}, {}, 0.0, 1))[0][:2]
    '**'
    """
    d = _Rows(result)
    parts = (_simulated_rig(d), _onset_paragraph(d), _fixed_vs_dath(d), _bottles_paragraph(d),
             _total_paragraph(d), _tactile_paragraph(d), _pour_slips_paragraph(d), _success_paragraph(d))
    return [p for p in parts if p]


def _simulated_rig(d: _Rows) -> str:
    cal = _and_join([f"{_label(m)}'s" for m in methods.calibrated() if m in d.config.methods])
    return ("**Simulated rig, not the paper's rig.** Every number here comes from the simulator "
            "(`slipreflex.sim`, docs/simulator.md): friction, pad compliance, hand speed and latency, "
            "sensor noise and the bottles' surfaces are physical estimates, not fits to the paper's "
            "results, and nothing in the simulator or in the methods was tuned to bring our numbers "
            "closer to the paper's (the only thresholds derived from data are "
            f"{cal or 'those of the calibrated methods'}, by their one rule). Absolute times are "
            "therefore not expected to match; what can carry over is the ordering of methods and bottles.")


def _onset_paragraph(d: _Rows) -> str:
    parts, late_pours = [], 0
    for e in experiment_specs.names():
        err = np.array([r.onset_error_ms for r in d.sel(experiment=e) if _finite(r.onset_error_ms)])
        if err.size:
            late = int((err > LATE_ONSET_MS).sum())
            late_pours += late if experiment_specs.get(e).slip_events == "segmented" else 0
            parts.append(f"{e}: median absolute error {np.median(np.abs(err)):.1f} ms, largest "
                         f"{np.abs(err).max():.0f} ms, {late} of {err.size} found more than "
                         f"{LATE_ONSET_MS:.0f} ms after the true onset")
    if not parts:
        return ""
    text = ("**Onset estimate.** The paper's accelerometer recipe against the simulator's true onsets "
            f"(the contacts' stick to slip): {'; '.join(parts)}.")
    if late_pours:
        text += (" A pour's slip under rate-and-state friction creeps before it accelerates, and the "
                 "accelerometer's envelope crosses its rest threshold only once it does: those onsets, and "
                 "the response times measured from them, start late.")
    return text + (" On the real rig the IMU is taped to a flexible bottle and feels the mass or the water "
                   "before the grasp gives way, so the paper's onsets, and its response times, carry more "
                   "spread than ours.")


#: An accelerometer onset this much (ms) after the simulator's true onset is called late in the report.
LATE_ONSET_MS: float = 100.0


def _fixed_vs_dath(d: _Rows) -> str:
    F, D = methods.FIXED, methods.DATH
    pairs: dict[tuple, dict[str, float]] = {}
    for r in d.rows:
        if r.method in (F, D) and _finite(r.response_ms):
            pairs.setdefault((r.experiment, r.bottle, r.trial, r.event), {})[r.method] = r.response_ms
    both = [v for v in pairs.values() if len(v) == 2]
    if not both:
        return ""
    same = sum(1 for v in both if abs(v[F] - v[D]) < 1e-6)
    return (f"**Fixed threshold vs DATH response.** In {same} of {len(both)} paired slips "
            "(same seed, same bottle) the two chains responded at exactly the same time. That "
            "follows from the method (docs/method.md section 1.2): DATH changes the threshold only after the first "
            "spike, and the MPI raises the command at the end of the first window holding a spike, "
            "so on the same input the first response cannot differ. The paper's fixed and DATH "
            "trials were separate physical runs, so their response times differ by trial-to-trial "
            "variation (and by how soon the first spike comes on each run). DATH differs from the "
            "fixed threshold in what follows the first spike: more spikes, a larger and longer "
            "command rise.")


def _bottles_paragraph(d: _Rows) -> str:
    by = {(x["experiment"], x["bottle"], x["method"]): x for x in d.summary}
    parts, tx_first = [], False
    for e in EXPERIMENTS:
        vals = {b: by[(e, b, methods.DATH)]["response_mean_ms"] for b in BOTTLE_ORDER
                if (e, b, methods.DATH) in by}
        vals = {b: v for b, v in vals.items() if _finite(v)}
        if len(vals) >= 2:
            order = sorted(vals, key=lambda b: vals[b])
            tx_first = tx_first or order[0] == "TX"
            parts.append(f"{e}: " + ", ".join(f"{b} {vals[b]:.0f} ms" for b in order) + " (paper: "
                         + ", ".join(f"{b} {p.mean:g} ms" for b in order
                                     if (p := paper_value(e, "response_ms", b, methods.DATH)) is not None
                                     and p.mean is not None) + ")")
    if not parts:
        return ""
    para = "**Bottles.** DATH's mean response by bottle, fastest first: " + "; ".join(parts) + "."
    if tx_first:
        para += (" As in the paper, the textured TX bottle is answered fastest. In the simulator "
                 "its surface makes the slip sensor fluctuate most; on the smooth transparent and "
                 "dark surfaces the sensor moves by only a few ADC steps over several millimetres "
                 "of sliding (see the zoomed DK pour figure), so the first spike, and with it the "
                 "first MPI response, comes later, and DATH cannot act before that first spike.")
    return para


def _paper_chain_totals() -> tuple[float, float]:
    """Smallest and largest mean total of the paper's chains (fixed, DATH), ms."""
    v = [p.mean for (e, metric, b, m), p in PAPER.items()
         if metric == "total_ms" and m in (methods.FIXED, methods.DATH) and p.mean is not None]
    return min(v), max(v)


def _total_paragraph(d: _Rows) -> str:

    drops = [r for r in d.sel(experiment="drop") if _finite(r.true_slip_ms)]
    chain = [r for r in d.rows if r.method in (methods.FIXED, methods.DATH) and r.n_increases > 0]
    if not (drops and chain):
        return ""
    w, (lo, hi) = _window_ms(), _paper_chain_totals()
    return (f"**Total controller time.** In the simulator a drop makes the bottle slide "
            f"{_median(r.true_slip_mm for r in drops):.1f} mm in "
            f"{_median(r.true_slip_ms for r in drops):.0f} ms (medians) before the pads stick "
            f"again. The fixed and DATH chains see spikes for only a few {w:.0f} ms windows (median "
            f"{_median(r.n_increases for r in chain):.0f} command increases per slip), so the "
            f"first-to-last change of the MPI command is a small multiple of {w:.0f} ms, far below the "
            f"paper's {lo:.0f}-{hi:.0f} ms: the paper's bottles kept creeping and vibrating for hundreds "
            "of milliseconds and its sensor kept seeing motion. For NMSD and SWT-SD the total is the "
            f"closing time generated, {CLOSE_S * 1e3:.0f} ms per detection, and short slips give few "
            "detections.")


def _tactile_paragraph(d: _Rows) -> str:

    tactile = {m for m in methods.names() if methods.get(m).input_kind == "tactile"}
    tac = [r for r in d.rows if r.method in tactile and r.n_events > 0]
    if not tac:
        return ""
    missed = "; ".join(
        f"{_label(m)} missed {_Rows.pct(sub, lambda r: not _finite(r.response_ms))} {e} slips"
        for m in methods.names() for e in EXPERIMENTS
        if (sub := [r for r in tac if r.method == m and r.experiment == e]))
    shape = " x ".join(map(str, hw.TACTILE_SHAPE))
    persist_ms = 1e3 * d.config.swt_persist / methods.get(methods.SWT).fs
    persistence = (f"SWT-SD needs the level-{SWT_LEVEL} detail to stay over threshold for {persist_ms:.0f} ms "
                   "after the crossing, so a slip that is over sooner, like the simulated drops, cannot "
                   "trigger it. " if d.config.swt_persist else
                   f"SWT-SD decides at the crossing of the level-{SWT_LEVEL} detail, whose 21 ms window "
                   "already holds the change that follows (docs/method.md section 2.1). ")
    return (f"**NMSD and SWT-SD.** Both read the index fingertip's {shape} array with thresholds from "
            f"one rule ({d.config.rest_k:g} sd of the method's statistic at rest, the same for every "
            f"bottle). {missed} (no command within {MAX_RESPONSE_S:g} s of the onset). {persistence}The paper "
            "gives no thresholds, wavelet or persistence rule for either method, so their absolute "
            "numbers depend on these choices (documented in docs/reproduce.md) more than on anything "
            "else.")


def _pour_slips_paragraph(d: _Rows) -> str:
    pour_trials = {(r.bottle, r.method, r.trial): r.n_events for r in d.sel(experiment="pour")}
    if not pour_trials:
        return ""
    two = sum(1 for n in pour_trials.values() if n >= 2)
    kept = [r for r in d.sel(experiment="pour") if r.method in (methods.FIXED, methods.DATH)
            and r.n_events > 0 and r.success]
    vol = _median(r.load_at_onset for r in d.sel(experiment="pour", event=0) if r.n_events > 0)
    para = (f"**Slips per pour.** {two} of {len(pour_trials)} pour trials showed two or more "
            f"slips (paper: two in most trials, near 200 and 400 ml); the first came at a median "
            f"{vol:.0f} ml.")
    if kept and 2 * two < len(pour_trials):
        para += _stiff_grasp_sentence(kept)
    return para


def _stiff_grasp_sentence(kept: Sequence[Any]) -> str:
    from ...sim import BOTTLES, HandParams  # deferred: heavy (numba kernels)

    hp = HandParams()
    k_n = 1.0 / (1.0 / hp.pad_normal_stiffness_n_m + 1.0 / hp.finger_stiffness_n_m
                 + 1.0 / BOTTLES["TR"].wall_stiffness_n_m)
    per_unit = k_n * hp.travel_per_unit_m
    return (" After the first slip the MPI raised the fingers by a median "
            f"{_median(r.rise for r in kept):.0f} position units in the trials that kept the "
            f"bottle; in the simulator a unit adds about {per_unit:.2f} N per contact (pad, finger "
            f"and wall springs in series over {hp.travel_per_unit_m * 1e3:.1f} mm per unit), a "
            f"grip several times the {hw.CONTACT_FORCE_N:.1f} N of the grasp, which holds the rest of "
            "the water without another slip. The paper's MPI added \"just enough force\" for the "
            "first slip and the bottle slipped again as the water rose: the simulated grasp is "
            "stiffer than the real one.")


def _success_paragraph(d: _Rows) -> str:
    text = ["**Success.**"]
    drop_rows, pour_rows = d.sel(experiment="drop"), d.sel(experiment="pour")
    if drop_rows:
        text.append(f"The bottle stayed in the grasp in {_Rows.pct(drop_rows, lambda r: r.success)} drop "
                    f"rows (paper: {_paper_success('drop', methods.DATH)} with DATH, "
                    f"{_paper_success('drop', methods.FIXED)} with the fixed threshold).")
        if all(r.success for r in drop_rows):
            text.append(f"The simulated {d.config.drop.mass_kg * 1e3:g} g drop is a small, short slip "
                        "that stops by itself once the landing transient has passed, so no method "
                        "loses a bottle to it and the drop cannot separate the methods by success.")
    if pour_rows:
        ran = [m for m in methods.names() if d.sel(experiment="pour", method=m)]
        per = ", ".join(f"{_label(m)} {_Rows.pct(d.sel(experiment='pour', method=m), lambda r: r.success)}"
                        for m in ran)
        text.append(f"In the pours: {per} (paper: {_paper_success('pour', methods.DATH)} with DATH).")
    falls = [1e3 * (r.fell_out_s - r.onset_s) for r in d.rows
             if r.fell_out and _finite(r.onset_s) and r.fell_out_s >= r.onset_s]
    if falls:
        text.append(
            "A pour's slip starts at the friction limit and accelerates (kinetic friction is below "
            f"static): a bottle that fell was gone a median {_median(falls):.0f} ms after the onset. "
            "The paper's bottles slipped more gently.")
    if pour_rows:
        text += _pour_response_sentences(d)
    return " ".join(text)


def _pour_response_sentences(d: _Rows) -> list[str]:

    ran = [m for m in methods.names() if d.sel(experiment="pour", method=m)]
    med = {m: _median(r.response_ms for r in d.sel(experiment="pour", method=m)) for m in ran}
    resp = ", ".join(f"{_label(m)} " + (f"{med[m]:.0f} ms" if _finite(med[m]) else "none (never responded)")
                     for m in ran)
    out = [f"Median pour response: {resp}."]
    mpi = [med[m] for m in (methods.DATH, methods.FIXED) if m in med and _finite(med[m])]
    if methods.NMSD in med and _finite(med[methods.NMSD]) and mpi and med[methods.NMSD] < min(mpi):
        out.append(f"NMSD commands on the very sample that detects ({hw.NMSD_FS:g} Hz) and keeps closing at "
                   f"the hand's full speed, while the MPI raises the command only at the end of a "
                   f"{_window_ms():.0f} ms window, to P0 + Kp v + Ki h, so against a fast slip the paper's "
                   "controller is at a disadvantage in the simulator.")
    pre = {m: sum(1 for r in d.sel(experiment="pour", method=m) if r.n_events == 0 and r.n_increases > 0)
           for m in ran}
    if any(pre.values()):
        out.append("Trials in which the command rose although the accelerometer never showed a "
                   "slip (the grip was raised on small motions and no slip followed): "
                   + ", ".join(f"{_label(m)} {n}" for m, n in pre.items() if n) + ".")
    return out

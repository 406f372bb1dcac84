"""The simulated tactile array held against recorded data (docs/benchmark.md, "The simulator against the data").

The same measures on both, at the data's rate, from the normal component of every taxel:

* **noise**: per taxel, the sd of the sample-to-sample change over the calibration span
  divided by sqrt(2) (the white-noise level; slow load changes barely enter), median over taxels;
* **noise colour**: lag-1 autocorrelation of that change (-0.5 for white noise, 0 for a
  random walk, between for coloured noise);
* **steps**: the fraction of zero changes per taxel (quantisation and repeated readings),
  and the fraction of frames identical to the one before (a stream that repeats frames);
* **load drift**: the sd of the arrays' total normal force over the calibration span over its
  own white noise (1 when the span is at rest and the noise white);
* **noise under load**: the taxel noise between the calibration span and the onset (to the
  end for a control: the arm moving, or the bottle filling) over that in the span;
* **tails**: excess kurtosis of NMSD's statistic over the calibration span (0 for Gaussian);
* **slip**: over the first 0.25 s after the onset, the largest change of the total normal
  force over its noise, and the largest NMSD and SWT-SD statistic over their thresholds
  (``rest_k`` sd of the statistic in the calibration span);
* **non-slip motion**: the same three, as the largest over every 0.25 s window between the
  calibration span and the onset (to the end for a control): what the same statistics reach
  without slip while the arm moves (or the bottle fills), so the slip is held against motion,
  not against rest; and the slip's force change over the controls' (or, simulated, over the
  trial's own) largest motion.

An empty cell says why (:func:`empty_reason`); the header gives the rate everything was
measured at, the data's own (the median of its trials' rates).

The simulated side: the built-in bottle TR grasped with the paper's 0.8 N, at rest for
``calibration_s`` (the calibration span), then either poured into until it first slips (the
simulator's calibrated open-loop fact) or hit by the paper's drop (10 g from 2 cm), its
index array sampled at the data's rate; the onset is the simulator's true first slip.

Examples
--------
>>> rows = _measures_of(np.random.default_rng(0).normal(0, 1, (200, 4, 4)), 60.0, None, 1.0, 5.0)
>>> round(rows["noise"], 1), round(rows["noise_lag1"], 1)
(1.0, -0.5)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..core import hardware as hw
from ..files.csvfiles import write_columns
from ..methods import NMSD, SWT
from ..methods.baselines import nmsd_statistic, rest_threshold, swt_statistic
from ..methods.baselines.calibration import REST_K
from .report import _plt

__all__ = ["Comparison", "compare", "write_comparison", "format_comparison", "plot_comparison",
           "MEASURES", "SLIP_WINDOW_S", "empty_reason"]

#: Span after the onset over which the slip measures are taken (s): 15 samples at 60 Hz, and
#: inside the shortest labelled slip of the shipped set (0.3 s).
SLIP_WINDOW_S: float = 0.25

#: Measure key, label, unit ("signal" means the channel's own unit: counts, N).
MEASURES: tuple[tuple[str, str], ...] = (
    ("noise", "taxel noise, sd of change / sqrt 2 (channel unit)"),
    ("noise_lag1", "lag-1 autocorrelation of the change (white: -0.5)"),
    ("zero_steps", "fraction of zero changes per taxel"),
    ("repeated_frames", "fraction of frames identical to the previous one"),
    ("drift_ratio", "total normal force: sd over the calibration span / its white noise"),
    ("load_noise_ratio", "taxel noise after the calibration span, before any slip / in it"),
    ("nmsd_kurtosis", "NMSD statistic: excess kurtosis over the calibration span"),
    ("slip_force_ratio", "slip: largest change of total normal force in 0.25 s / its noise"),
    ("slip_nmsd_ratio", "slip: largest NMSD statistic in 0.25 s / NMSD threshold"),
    ("slip_swt_ratio", "slip: largest SWT-SD statistic in 0.25 s / SWT-SD threshold"),
    ("motion_force_ratio", "non-slip motion: largest change of total normal force in any 0.25 s / its noise"),
    ("motion_nmsd_ratio", "non-slip motion: largest NMSD statistic in any 0.25 s / NMSD threshold"),
    ("motion_swt_ratio", "non-slip motion: largest SWT-SD statistic in any 0.25 s / SWT-SD threshold"),
    ("slip_over_motion", "slip's force change / the largest non-slip motion's (controls'; simulated: its own)"),
)


@dataclass(frozen=True)
class Comparison:
    """Measures per source: ``rows[source][measure]`` (NaN where not defined).

    Attributes
    ----------
    sources : tuple of str
        Column names: "real, controls", "real, slip trials", "simulated pour", "simulated drop".
    rows : dict
    fs : float
        The rate everything was measured at (Hz).
    curves : dict
        What the figure draws: per source, lists of (time from onset, normalised total force)
        and the taxel noise spectra.

    Examples
    --------
    >>> c = Comparison(("simulated pour",), {"simulated pour": {"noise": 0.005}}, 60.0, {})
    >>> c.rows["simulated pour"]["noise"]
    0.005
    """

    sources: tuple[str, ...]
    rows: dict
    fs: float
    curves: dict


def _noise(frames: np.ndarray) -> np.ndarray:
    d = np.diff(frames.reshape(len(frames), -1), axis=0)
    return d.std(axis=0) / math.sqrt(2.0)


def _measures_of(frames: np.ndarray, fs: float, onset_index: int | None, calibration_s: float,
                 rest_k: float) -> dict[str, float]:
    """The measures of one recording ``frames`` (K, rows, cols) at ``fs``."""
    from scipy.stats import kurtosis  # deferred: heavy (scipy.stats)


    f = np.asarray(frames, dtype=float).reshape(len(frames), -1)
    cal = f[: max(8, int(round(calibration_s * fs)))]
    d = np.diff(cal, axis=0)
    noise = np.median(d.std(axis=0)) / math.sqrt(2.0)
    lag1 = []
    for j in range(d.shape[1]):
        x = d[:, j] - d[:, j].mean()
        if x.std() > 0:
            lag1.append(float(np.mean(x[1:] * x[:-1]) / x.var()))
    total = cal.sum(axis=1)
    total_noise = np.diff(total).std() / math.sqrt(2.0)
    s_cal = nmsd_statistic(cal, fs)[2:].ravel()
    out = {
        "noise": float(noise),
        "noise_lag1": float(np.median(lag1)) if lag1 else float("nan"),
        "zero_steps": float(np.mean(d == 0)),
        "repeated_frames": float(np.mean(np.all(np.diff(f, axis=0) == 0, axis=1))),
        "drift_ratio": float(total.std() / total_noise) if total_noise > 0 else float("nan"),
        "load_noise_ratio": _load_noise_ratio(f, len(cal), onset_index, noise),
        "nmsd_kurtosis": float(kurtosis(s_cal)),
        "slip_force_ratio": float("nan"), "slip_nmsd_ratio": float("nan"), "slip_swt_ratio": float("nan"),
        "slip_over_motion": float("nan"),
    }
    out.update(_motion(f, fs, len(cal), onset_index, total_noise, cal, rest_k))
    if onset_index is not None:
        w = slice(onset_index, min(len(f), onset_index + max(2, int(round(SLIP_WINDOW_S * fs)))))
        tot = f.sum(axis=1)
        out["slip_force_ratio"] = float(np.max(np.abs(tot[w] - tot[onset_index])) / total_noise)
        s = np.abs(nmsd_statistic(f, fs)).max(axis=1)
        out["slip_nmsd_ratio"] = float(s[w].max() / rest_threshold(cal, NMSD, fs, k=rest_k))
        c = np.abs(swt_statistic(f)).max(axis=1)
        out["slip_swt_ratio"] = float(c[w].max() / rest_threshold(cal, SWT, fs, k=rest_k))
    return out


def _motion(f: np.ndarray, fs: float, n_cal: int, onset_index: int | None, total_noise: float,
            cal: np.ndarray, rest_k: float) -> dict[str, float]:
    """The slip measures' largest values over every 0.25 s window of non-slip time after the calibration span."""
    nan = float("nan")
    out = {"motion_force_ratio": nan, "motion_nmsd_ratio": nan, "motion_swt_ratio": nan}
    w = max(2, int(round(SLIP_WINDOW_S * fs)))
    stop = len(f) if onset_index is None else onset_index
    if stop - n_cal < w or not total_noise > 0:
        return out
    tot = f.sum(axis=1)
    span = tot[n_cal:stop]
    out["motion_force_ratio"] = float(max(np.abs(span[k:k + w] - span[k]).max()
                                          for k in range(len(span) - w + 1)) / total_noise)
    s = np.abs(nmsd_statistic(f, fs)).max(axis=1)[n_cal:stop]
    out["motion_nmsd_ratio"] = float(s.max() / rest_threshold(cal, NMSD, fs, k=rest_k))
    c = np.abs(swt_statistic(f)).max(axis=1)[n_cal:stop]
    out["motion_swt_ratio"] = float(c.max() / rest_threshold(cal, SWT, fs, k=rest_k))
    return out


def empty_reason(source: str, measure: str) -> str:
    """Why a cell of the comparison is empty.

    Examples
    --------
    >>> empty_reason("real, controls", "slip_force_ratio")
    'a control has no slip'
    """
    if measure.startswith("slip") and source == "real, controls":
        return "a control has no slip"
    if measure.startswith("slip") and source.startswith("simulated"):
        return "the simulated trial did not slip"
    if measure.startswith("motion") or measure == "load_noise_ratio":
        return "less than 0.25 s (or 8 samples) of non-slip time after the calibration span"
    if source.startswith("real"):
        return "no trial of this kind with a tactile layout"
    return "the signal does not vary (no noise to divide by)"


def _load_noise_ratio(f: np.ndarray, n_cal: int, onset_index: int | None, noise: float) -> float:
    """Taxel noise between the calibration span and the onset (or the end) over the span's."""
    later = f[n_cal:onset_index]
    if len(later) < 8 or not noise > 0:
        return float("nan")
    return float(np.median(np.diff(later, axis=0).std(axis=0)) / math.sqrt(2.0) / noise)


def _spectrum(frames: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """Median over taxels of the Welch spectrum of each taxel (linear trend removed), normalised to its mean."""
    from scipy.signal import welch  # deferred: heavy (scipy.signal)

    d = np.asarray(frames, float).reshape(len(frames), -1)
    f, p = welch(d, fs=fs, nperseg=min(32, len(d)), detrend="linear", axis=0)
    p = np.median(p / np.maximum(p.mean(axis=0, keepdims=True), 1e-300), axis=1)
    return f, p


def _simulated(fs: float, calibration_s: float, seed: int, kind: str):
    """Index-array frames of the simulated rig: at rest for ``calibration_s``, then a pour
    (until its first slip) or a drop; returns ``(frames, t, onset index)``."""
    from ..sim import Drop, Pour, Rig, simulate_open_loop  # deferred: heavy (numba kernels)

    rig = Rig("TR", seed=seed)
    rig.grasp(hw.CONTACT_FORCE_N)
    rest = simulate_open_loop(rig, calibration_s, tactile_fs=fs)
    if kind == "pour":
        rig.perturb(Pour())
        run = simulate_open_loop(rig, 25.0, tactile_fs=fs)
    else:
        rig.perturb(Drop(), at=rig.t + 0.5)
        run = simulate_open_loop(rig, 1.5, tactile_fs=fs)
    if not len(run.onsets):
        return rest.tactile, None, None
    onset = float(run.onsets[0])
    keep = run.tactile_t >= onset - 1.0          # from 1 s before the first slip
    tt = run.tactile_t[keep]
    frames = np.concatenate([rest.tactile, run.tactile[keep]])
    t = np.r_[rest.tactile_t - rest.tactile_t[0], calibration_s + tt - tt[0]]
    return frames, t, len(rest.tactile) + int(np.searchsorted(tt, onset))


def compare(trials: Sequence, *, calibration_s: float = 1.0, rest_k: float = REST_K, seed: int = 1) -> Comparison:
    """Measure the recorded trials (controls and slip trials) and the simulated array alike.

    Examples
    --------
    >>> from slipreflex.benchmark import read_folder, shipped_dataset
    >>> c = compare(read_folder(shipped_dataset()))            # doctest: +SKIP
    >>> c.sources                                                # doctest: +SKIP
    ('real, controls', 'real, slip trials', 'simulated pour', 'simulated drop')
    """
    arrays = [tr for tr in trials if tr.layout is not None and tr.trial_label is None]
    fs = float(np.median([tr.fs for tr in (arrays or trials)]))
    groups = {"real, controls": [tr for tr in arrays if not tr.slips],
              "real, slip trials": [tr for tr in arrays if tr.slips]}
    rows: dict[str, dict[str, float]] = {}
    curves: dict[str, dict] = {}
    for name, trs in groups.items():
        per = []
        curves[name] = {"onset": [], "spectrum": []}
        for tr in trs:
            fr = tr.normal_frames()
            on = int(np.flatnonzero(tr.slip)[0]) if tr.slips else None
            m = _measures_of(fr, tr.fs, on, calibration_s, rest_k)
            per.append(m)
            curves[name]["spectrum"].append(_spectrum(fr[: int(calibration_s * tr.fs)], tr.fs))
            if on is not None:
                tot = fr.reshape(len(fr), -1).sum(axis=1)
                scale = m["noise"] * math.sqrt(fr[0].size)
                curves[name]["onset"].append((tr.t - tr.t[on], (tot - tot[on]) / scale))
        rows[name] = {k: float(np.nanmedian([p[k] for p in per])) if per and not all(
            math.isnan(p[k]) for p in per) else float("nan") for k, _ in MEASURES}
    controls_motion = rows["real, controls"]["motion_force_ratio"]
    rows["real, slip trials"]["slip_over_motion"] = rows["real, slip trials"]["slip_force_ratio"] / controls_motion
    for kind in ("pour", "drop"):
        name = f"simulated {kind}"
        frames, t, on = _simulated(fs, calibration_s, seed, kind)
        m = _measures_of(frames, fs, on, calibration_s, rest_k)
        m["slip_over_motion"] = m["slip_force_ratio"] / m["motion_force_ratio"]
        rows[name] = m
        curves[name] = {"onset": [], "spectrum": [_spectrum(frames[: int(calibration_s * fs)], fs)]}
        if on is not None and t is not None:
            tot = frames.reshape(len(frames), -1).sum(axis=1)
            scale = m["noise"] * math.sqrt(frames[0].size)
            curves[name]["onset"].append((t - t[on], (tot - tot[on]) / scale))
    return Comparison(tuple(rows), rows, fs, curves)


def write_comparison(c: Comparison, path: str | Path) -> Path:
    """``vs_sim.csv``: one row per measure, one column per source.

    Examples
    --------
    >>> c = Comparison(("a b",), {"a b": {k: 1.0 for k, _ in MEASURES}}, 60.0, {})
    >>> write_comparison(c, __import__("tempfile").mkdtemp() + "/v.csv").read_text().splitlines()[0]
    'measure,description,a_b'
    """
    path = Path(path)
    cols: dict[str, list] = {"measure": [k for k, _ in MEASURES], "description": [d for _, d in MEASURES]}
    for s in c.sources:
        cols[s.replace(", ", "_").replace(" ", "_")] = [float(f"{c.rows[s][k]:.4g}") for k, _ in MEASURES]
    write_columns(path, cols)
    return path


def format_comparison(c: Comparison, *, markdown: bool = False) -> str:
    """The comparison as a text (or Markdown) table.

    Examples
    --------
    >>> c = Comparison(("a",), {"a": {k: 1.0 for k, _ in MEASURES}}, 60.0, {})
    >>> format_comparison(c, markdown=True).splitlines()[2].startswith("| taxel noise")
    True
    """
    head = [f"measure (all at {c.fs:.1f} Hz, the data's rate)", *c.sources]
    reasons: list[str] = []

    def cell(s: str, k: str) -> str:
        v = c.rows[s].get(k, float("nan"))
        if math.isfinite(v):
            return f"{v:.3g}"
        why = empty_reason(s, k)
        if why not in reasons:
            reasons.append(why)
        return f"- ({reasons.index(why) + 1})"

    rows = [[d, *(cell(s, k) for s in c.sources)] for k, d in MEASURES]
    notes = [f"({i + 1}) {why}" for i, why in enumerate(reasons)]
    if markdown:
        out = ["| " + " | ".join(head) + " |", "|" + "|".join("---" for _ in head) + "|"]
        return "\n".join(out + ["| " + " | ".join(r) + " |" for r in rows] + [""] + [f"- {n}" for n in notes])
    w = [max(len(r[i]) for r in [head, *rows]) for i in range(len(head))]
    lines = ["  ".join(x.ljust(w[i]) for i, x in enumerate(r)).rstrip() for r in [head, *rows]]
    lines.insert(1, "  ".join("-" * x for x in w))
    return "\n".join(lines + notes)


def plot_comparison(c: Comparison, path: str | Path) -> Path:
    """Left: the total normal force around the onset in units of its noise; right: the noise spectra.

    Examples
    --------
    >>> c = Comparison(("simulated pour",), {}, 60.0, {"simulated pour": {"onset": [], "spectrum": []}})
    >>> plot_comparison(c, __import__("tempfile").mkdtemp() + "/v.png").suffix
    '.png'
    """

    plt = _plt()
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4))
    colors = {"real, controls": "0.5", "real, slip trials": "#d62728", "simulated pour": "#1f77b4",
              "simulated drop": "#2ca02c"}
    for s in c.sources:
        for i, (t, y) in enumerate(c.curves.get(s, {}).get("onset", [])):
            keep = (t >= -1.0) & (t <= 1.0)
            a.plot(t[keep], y[keep], color=colors.get(s, "k"), lw=1.2, label=s if i == 0 else None)
        for i, (f, p) in enumerate(c.curves.get(s, {}).get("spectrum", [])):
            b.semilogy(f, p, color=colors.get(s, "k"), lw=1.0, alpha=0.8, label=s if i == 0 else None)
    a.axvline(0, color="k", lw=0.6, ls="--")
    a.set_xlabel("time from the labelled (real) or true (simulated) slip onset (s)")
    a.set_yscale("symlog", linthresh=3.0)
    a.axhspan(-3, 3, color="0.9", lw=0)
    a.set_ylabel("change / (taxel noise x sqrt(taxels)), symlog")
    a.set_title("total normal force at slip, in units of its noise", fontsize=10)
    if a.get_legend_handles_labels()[0]:
        a.legend(fontsize=8)
    a.grid(alpha=0.3)
    b.set_xlabel("frequency (Hz)")
    b.set_ylabel("taxel spectrum / its mean (median over taxels)")
    b.set_title(f"taxels over the calibration span, trend removed ({c.fs:.0f} Hz; white noise is flat)",
                fontsize=10)
    if b.get_legend_handles_labels()[0]:
        b.legend(fontsize=8)
    b.grid(alpha=0.3, which="both")
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path

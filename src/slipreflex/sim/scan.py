"""The slip sensor's characterization scan (paper Fig. 4-9).

The sensor is moved down the white/black test surface at 1 mm/s, 3 mm
away, for 5 cm, sampled by the DAQ at 333.33 Hz. The test surface is 1 cm
white then 3 cm black on the 3D-printed stand; the scan starts 5 mm above
the white part and ends 5 mm below the black part (on the stand), so the
whole surface is crossed with a margin at each end. The volts come from the
same sensor model the rig uses (track, OPR5005 transfer curve, noise,
10-bit ADC; :mod:`slipreflex.sim.kernel`).

:func:`scan` returns a :class:`ScanResult`; :meth:`ScanResult.analyse`
runs the paper's chain stages (:func:`slipreflex.lowpass`,
:func:`slipreflex.encode_trace`) with the fixed threshold and with DATH and
summarizes them per region.

Examples
--------
>>> from slipreflex.sim import scan
>>> r = scan(seed=0)
>>> r.t.size, round(float(r.position[-1]), 4)
(16667, 0.05)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from dataclasses import replace as _replace

import numpy as np

from ..core import hardware as hw
from ..core.errors import ParameterError
from ..methods import DATH, FIXED
from ..methods.chain import encode_trace, lowpass
from . import kernel as K
from .objects import SURFACES, Surface, resolve_surface
from .params import SlipSensorParams
from .rig import fill_slip_sensor_params, seed_sequence
from .sensors import Track

__all__ = ["scan", "ScanResult", "PAPER_LAYOUT", "ScanSummary", "ScanEnsemble", "scan_ensemble", "ENSEMBLE_SEEDS",
           "calibrate_surface"]

#: The paper's test surface on its stand: (surface, length in m), top to bottom.
PAPER_LAYOUT: tuple[tuple[str, float], ...] = (("stand", 0.005), ("white", 0.010), ("black", 0.030),
                                              ("stand", 0.005))


@dataclass(frozen=True)
class ScanResult:
    """A characterization scan: time, sensor position along the surface, volts.

    Attributes
    ----------
    t : ndarray
        Sample times (s).
    position : ndarray
        Distance travelled along the surface (m).
    volts : ndarray
        Raw slip-sensor volts (ADC-quantized).
    regions : list of (name, start_m, end_m)
        Where each surface of the layout lies along the path.
    speed : float
        Scan speed (m/s).
    fs : float
        Sampling rate (Hz).

    Examples
    --------
    >>> r = scan(distance=0.002, layout=(("white", 0.002),))
    >>> r.regions
    [('white', 0.0, 0.002)]
    """

    t: np.ndarray
    position: np.ndarray
    volts: np.ndarray
    regions: list
    speed: float
    fs: float
    analysis: dict = field(default_factory=dict)

    def analyse(self, threshold: float = 2 * hw.PAPER_LSB, cutoff: float = 10.0,
                dath_samples: int = hw.WINDOW_N, margin: float = 2.5e-3) -> ScanSummary:
        """Filter, encode with the fixed threshold and with DATH, and summarize per region.

        Parameters
        ----------
        threshold : float
            Base threshold (V); the paper's 0.008 V by default.
        cutoff : float
            Low-pass cutoff (Hz).
        dath_samples : int
            DATH duration (samples).
        margin : float
            Distance (m) kept clear of each region's edges.

        Returns
        -------
        ScanSummary
            Also stored, with the per-sample traces, in ``self.analysis``
            (keys "filtered", "fixed", "dath": the latter two are
            :class:`slipreflex.EncoderTrace`).

        Examples
        --------
        >>> s = scan(seed=0).analyse()
        >>> s.spikes["dath"] > s.spikes["fixed"]
        True
        """

        x = lowpass(self.volts, fs=self.fs, cutoff=cutoff)
        fixed = encode_trace(x, threshold=threshold, dath=False)
        dath = encode_trace(x, threshold=threshold, dath=True, dath_samples=dath_samples)
        self.analysis.update(filtered=x, fixed=fixed, dath=dath)
        ranges: dict = {}
        spikes_in: dict = {}
        spacing: dict = {}
        for name, a, b in self.regions:
            sel = (self.position >= a + margin) & (self.position <= b - margin)
            if not sel.any():
                continue
            key = name if name not in ranges else f"{name}@{a * 1000:g}mm"
            ranges[key] = (float(x[sel].min()), float(x[sel].max()))
            for meth, tr in ((FIXED, fixed), (DATH, dath)):
                pos = self.position[sel & tr.events]
                spikes_in[(meth, key)] = int(pos.size)
                spacing[(meth, key)] = float(np.diff(pos).min() * 1000.0) if pos.size > 1 else None
        return ScanSummary(ranges=ranges, spikes={FIXED: int(fixed.events.sum()), DATH: int(dath.events.sum())},
                           spikes_in=spikes_in, min_spacing_mm=spacing)

    def to_frame(self) -> dict[str, np.ndarray]:
        """Per-sample columns: t, position_mm, volts, and (after :meth:`analyse`) filtered,
        accumulator/threshold/spike for "fixed" and "dath".

        Examples
        --------
        >>> sorted(scan(distance=0.001, layout=(("black", 0.001),)).to_frame())
        ['position_mm', 't', 'volts']
        """
        out = {"t": self.t, "position_mm": self.position * 1000.0, "volts": self.volts}
        if self.analysis:
            out["filtered"] = self.analysis["filtered"]
            for meth in (FIXED, DATH):
                tr = self.analysis[meth]
                out[f"{meth}_accumulator"] = tr.accumulator
                out[f"{meth}_threshold"] = tr.threshold
                out[f"{meth}_spike"] = tr.events.astype(np.int64)
        return out


@dataclass(frozen=True)
class ScanSummary:
    """Numbers of one scan analysis (see :meth:`ScanResult.analyse`).

    Attributes
    ----------
    ranges : dict
        Region name -> (min, max) of the filtered volts inside that region
        (2.5 mm in from its edges, clear of the spot's blur).
    spikes : dict
        Method ("fixed", "dath") -> spike count over the whole scan.
    spikes_in : dict
        (method, region) -> spike count inside that region.
    min_spacing_mm : dict
        (method, region) -> smallest distance between consecutive spikes
        inside the region (mm), or None with fewer than two spikes.

    Examples
    --------
    >>> ScanSummary({}, {}, {}, {}).spikes
    {}
    """

    ranges: dict
    spikes: dict
    spikes_in: dict
    min_spacing_mm: dict


def _sensor_params(sensor: SlipSensorParams, track: Track) -> np.ndarray:
    P = fill_slip_sensor_params(np.zeros(K.P_SIZE), sensor, track)
    P[K.P_LAM] = 1.0
    return P


def scan(seed: int | np.random.SeedSequence | np.random.Generator | None = 0, *, speed: float = 1e-3,
         distance: float = 0.05, layout: Sequence[tuple[Surface | str, float]] = PAPER_LAYOUT,
         sensor: SlipSensorParams | None = None, fs: float = hw.DAQ_FS) -> ScanResult:
    """Simulate the characterization scan over a layout of surfaces.

    Parameters
    ----------
    seed : int, SeedSequence or Generator
        Texture and noise seed.
    speed : float
        Scan speed (m/s); the paper's UR10 moved at 1 mm/s.
    distance : float
        Length of the scan (m); the paper's is 5 cm.
    layout : sequence of (Surface or name, length_m)
        Surfaces top to bottom (default: :data:`PAPER_LAYOUT`).
    sensor : SlipSensorParams, optional
    fs : float
        Sampling rate (Hz); the DAQ's 333.33 Hz by default.

    Returns
    -------
    ScanResult

    Examples
    --------
    >>> r = scan(seed=1, distance=0.004, layout=(("black", 0.004),))
    >>> 3.3 < float(r.volts.mean()) < 3.37
    True
    """
    if not (math.isfinite(speed) and speed > 0):
        raise ParameterError(f"speed must be > 0, got {speed!r}")
    if not (math.isfinite(distance) and distance > 0):
        raise ParameterError(f"distance must be > 0, got {distance!r}")
    if not (math.isfinite(fs) and fs > 0):
        raise ParameterError(f"fs must be > 0, got {fs!r}")
    surfaces = [(resolve_surface(s, where=f"layout[{i}]"), float(length)) for i, (s, length) in enumerate(layout)]
    for i, (_, length) in enumerate(surfaces):
        if not (math.isfinite(length) and length > 0):
            raise ParameterError(f"layout[{i}] length must be > 0, got {length!r}")
    sensor = sensor or SlipSensorParams()
    ss = seed_sequence(seed)
    tex_ss, key_ss = ss.spawn(2)
    track = Track.build(surfaces, np.random.default_rng(tex_ss), lead=0.005, sensor=sensor)
    keys = key_ss.generate_state(8, dtype=np.uint64)
    n = int(math.floor(distance / speed * fs + 1e-9)) + 1
    t = np.arange(n) / fs
    pos = t * speed
    volts = np.empty(n)
    K.volts_along(_sensor_params(sensor, track), track.rho, keys, pos, volts)
    edges = np.cumsum([0.0] + [length for _, length in surfaces])
    regions = [(s.name, float(edges[i]), float(edges[i + 1])) for i, (s, _) in enumerate(surfaces)]
    return ScanResult(t=t, position=pos, volts=volts, regions=regions, speed=speed, fs=fs)



#: Texture seeds of a scan ensemble (the claims on the scan are judged over their distribution).
ENSEMBLE_SEEDS: int = 200


@dataclass(frozen=True)
class ScanEnsemble:
    """The characterization scan's numbers over many texture seeds (one entry per seed).

    Attributes
    ----------
    seeds : ndarray of int
        The texture seeds (``base + 0 .. n - 1``).
    white_lo, white_hi, black_lo, black_hi : ndarray
        Filtered level range (V) inside each region (see :class:`ScanSummary`).
    fixed_gap, dath_gap : ndarray
        Smallest spike spacing (mm) on white or black of the fixed threshold
        and of DATH (NaN with fewer than two spikes in both).
    fixed_spikes, dath_spikes : ndarray of int
        Spikes over the whole scan.
    step_mm : float
        Travel between two samples (mm): the finest spacing a scan can show.

    Examples
    --------
    >>> e = scan_ensemble(4)
    >>> e.white_lo.shape, bool((e.white_lo < e.white_hi).all())
    ((4,), True)
    """

    seeds: np.ndarray
    white_lo: np.ndarray
    white_hi: np.ndarray
    black_lo: np.ndarray
    black_hi: np.ndarray
    fixed_gap: np.ndarray
    dath_gap: np.ndarray
    fixed_spikes: np.ndarray
    dath_spikes: np.ndarray
    step_mm: float

    def __len__(self) -> int:
        return int(self.seeds.size)

    def band(self, name: str, central: float = 0.90) -> tuple[float, float]:
        """The central ``central`` fraction of one statistic over the seeds (NaN left out).

        Examples
        --------
        >>> lo, hi = scan_ensemble(8).band("white_lo")
        >>> lo <= hi
        True
        """
        x = np.asarray(getattr(self, name), dtype=float)
        x = x[np.isfinite(x)]
        if not x.size:
            return float("nan"), float("nan")
        q = (1.0 - central) / 2.0
        return float(np.quantile(x, q)), float(np.quantile(x, 1.0 - q))


def _gap(summary: ScanSummary, method: str) -> float:
    g = [v for (m, region), v in summary.min_spacing_mm.items()
         if m == method and region in ("white", "black") and v is not None]
    return float(min(g)) if g else float("nan")


def scan_ensemble(n: int = ENSEMBLE_SEEDS, *, base: int = 0, sensor: SlipSensorParams | None = None,
                  layout: Sequence[tuple[Surface | str, float]] = PAPER_LAYOUT) -> ScanEnsemble:
    """The characterization scan analysed on ``n`` texture seeds ``base .. base + n - 1`` (about 10 ms each).

    Parameters
    ----------
    n : int
        Seeds (default :data:`ENSEMBLE_SEEDS`).
    base : int
        First seed (a study gives each plant its own).
    sensor : SlipSensorParams, optional
    layout : sequence of (Surface or name, length_m)

    Returns
    -------
    ScanEnsemble

    Examples
    --------
    >>> e = scan_ensemble(3, base=10)
    >>> e.seeds.tolist(), round(e.step_mm, 4)
    ([10, 11, 12], 0.003)
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ParameterError(f"n must be an integer >= 1, got {n!r}")
    cols: dict[str, list] = {k: [] for k in ("white_lo", "white_hi", "black_lo", "black_hi", "fixed_gap",
                                              "dath_gap", "fixed_spikes", "dath_spikes")}
    nan = (float("nan"), float("nan"))
    for s in range(base, base + n):
        r = scan(seed=s, sensor=sensor, layout=layout)
        a = r.analyse()
        for region in ("white", "black"):
            lo, hi = a.ranges.get(region, nan)
            cols[f"{region}_lo"].append(lo)
            cols[f"{region}_hi"].append(hi)
        cols["fixed_gap"].append(_gap(a, FIXED))
        cols["dath_gap"].append(_gap(a, DATH))
        cols["fixed_spikes"].append(a.spikes[FIXED])
        cols["dath_spikes"].append(a.spikes[DATH])
    arrays = {k: np.asarray(v, dtype=np.int64 if k.endswith("spikes") else float) for k, v in cols.items()}
    return ScanEnsemble(seeds=np.arange(base, base + n), step_mm=1e3 * 1e-3 / hw.DAQ_FS, **arrays)


def calibrate_surface(name: str, level_v: tuple[float, float], *, n: int = ENSEMBLE_SEEDS,
                      sensor: SlipSensorParams | None = None, iterations: int = 6) -> Surface:
    """A scan surface's reflectance and texture so that the ensemble's median level range is ``level_v``.

    The median over ``n`` texture seeds of the region's filtered range midpoint
    is brought to the midpoint of ``level_v`` (by the reflectance) and its
    median width to the width of ``level_v`` (by the texture's rms), by fixed
    point iteration: the level is nearly linear in the reflectance above the
    sensor's saturation knee, and the width in the texture. Calibrated on
    ensemble statistics, not on a few seeds, so that no lucky draw sets a
    constant. Open loop only (the paper's scan, Fig. 6-9).

    Examples
    --------
    >>> s = calibrate_surface("black", (3.32, 3.35), n=8, iterations=1)
    >>> s.name, 0.2 < s.reflectance < 0.5
    ('black', True)
    """


    surf = SURFACES[name]
    sensor = sensor or SlipSensorParams()
    want_mid, want_w = 0.5 * (level_v[0] + level_v[1]), level_v[1] - level_v[0]
    layout_of = lambda s: [(s if n_ == name else SURFACES[n_], length) for n_, length in PAPER_LAYOUT]  # noqa: E731
    for _ in range(iterations):
        e = scan_ensemble(n, sensor=sensor, layout=layout_of(surf))
        lo, hi = getattr(e, f"{name}_lo"), getattr(e, f"{name}_hi")
        mid, w = float(np.median(0.5 * (lo + hi))), float(np.median(hi - lo))
        refl = float(np.clip(surf.reflectance - (want_mid - mid) / sensor.supply_v, 0.0, 1.0))
        surf = _replace(surf, reflectance=refl, texture=float(np.clip(surf.texture * want_w / w, 0.0, 0.5)))
    return surf

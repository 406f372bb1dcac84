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

import numpy as np

from .. import hardware as hw
from ..chain import encode_trace, lowpass
from ..errors import ParameterError
from ..methods import DATH, FIXED
from . import kernel as K
from .objects import Surface, resolve_surface
from .params import SlipSensorParams
from .rig import fill_slip_sensor_params, seed_sequence
from .sensors import Track

__all__ = ["scan", "ScanResult", "PAPER_LAYOUT", "ScanSummary"]

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


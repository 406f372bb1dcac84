"""Sensor models that do not need the physics loop: surface textures and transfer curves.

* :func:`texture` draws a unit-variance texture along a surface with a
  power-law spectrum (deterministic under a seed);
* :class:`Track` is what the slip sensor sees along a path: the reflectance
  of a layout of surfaces with their texture, blurred by the sensor's spot
  (edges and texture alike: the sensor integrates its whole spot), sampled every
  :data:`TRACK_DX` metres; the physics kernel interpolates it at the
  surface's position under the sensor, so the signal moves when, and only
  when, the surface moves;
* :func:`opr5005_volts` is the OPR5005 driver's transfer curve
  (reflectance -> volts before noise and ADC).

Examples
--------
>>> import numpy as np
>>> from slipreflex.sim.sensors import opr5005_volts
>>> [round(float(v), 2) for v in opr5005_volts(np.array([0.333, 0.93]))]
[3.34, 0.4]
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.fft

from .objects import Surface
from .params import SlipSensorParams

__all__ = ["TRACK_DX", "texture", "Track", "opr5005_volts"]

#: Spatial sampling of textures and tracks (m): 5 um, 8 samples per period of
#: the finest default texture wavelength (40 um).
TRACK_DX: float = 5e-6

#: Tracks kept by :meth:`Track.build` (least recently used dropped first). A study builds the
#: same track many times: every rig of a calibration search has the same seed and sensor, and
#: every method of a trial cell the same trial seed; a default track is ~26,000 floats (210 kB).
TRACK_CACHE_SIZE: int = 48
_TRACKS: OrderedDict = OrderedDict()


def texture(n: int, dx: float, exponent: float, min_wavelength: float, max_wavelength: float,
            rng: np.random.Generator) -> np.ndarray:
    """A periodic, zero-mean, unit-rms random texture with a power-law spectrum.

    Parameters
    ----------
    n : int
        Number of samples.
    dx : float
        Sample spacing (m).
    exponent : float
        Amplitude spectrum ``|A(k)| ~ k**-exponent`` inside the band.
    min_wavelength, max_wavelength : float
        Band limits (m).
    rng : numpy.random.Generator
        Source of the random phases and amplitudes.

    Returns
    -------
    numpy.ndarray
        ``n`` samples, mean 0, rms 1 (all zeros if the band is empty).

    Examples
    --------
    >>> import numpy as np
    >>> t = texture(4096, 5e-6, 1.0, 40e-6, 5e-3, np.random.default_rng(0))
    >>> round(float(t.std()), 6), abs(float(t.mean())) < 1e-12
    (1.0, True)
    """
    k = np.fft.rfftfreq(n, dx)
    band = (k >= 1.0 / max_wavelength) & (k <= 1.0 / min_wavelength) & (k > 0)
    amp = np.zeros_like(k)
    amp[band] = k[band] ** (-exponent)
    coef = (rng.standard_normal(k.size) + 1j * rng.standard_normal(k.size)) * amp
    # scipy's FFT: the same numbers as numpy's here, about twice as fast on a track's awkward length
    # (26002 = 2 x 13001, a prime)
    out = np.asarray(scipy.fft.irfft(coef, n))
    sd = out.std()
    return out / sd if sd > 0 else out


#: Unit textures kept by :func:`_kept_texture` (least recently used dropped first; each ~210 kB).
TEXTURE_CACHE_SIZE: int = 32
_TEXTURES: OrderedDict = OrderedDict()


def _kept_texture(n: int, dx: float, surf: Surface, rng: np.random.Generator) -> np.ndarray:
    """:func:`texture` of ``surf``'s spectrum, kept by every input and the generator's whole state (a hit leaves
    the generator where a draw would): the plants of a study differ in a surface's reflectance and texture
    amplitude, which scale the unit texture, while its seed and spectrum stay (read it, never write it).

    Examples
    --------
    >>> from slipreflex.sim import SURFACES
    >>> r1, r2 = np.random.default_rng(3), np.random.default_rng(3)
    >>> a, b = _kept_texture(64, 5e-6, SURFACES["white"], r1), _kept_texture(64, 5e-6, SURFACES["white"], r2)
    >>> a is b, r1.random() == r2.random()
    (True, True)
    """
    spectrum = (surf.texture_exponent, surf.texture_min_wavelength_m, surf.texture_max_wavelength_m)
    key = (int(n), float(dx), repr(spectrum), repr(rng.bit_generator.state))
    hit = _TEXTURES.get(key)
    if hit is not None:
        _TEXTURES.move_to_end(key)
        rng.bit_generator.state = hit[1]
        return hit[0]
    t = texture(n, dx, *spectrum, rng)
    t.flags.writeable = False
    _TEXTURES[key] = (t, rng.bit_generator.state)
    while len(_TEXTURES) > TEXTURE_CACHE_SIZE:
        _TEXTURES.popitem(last=False)
    return t


def opr5005_volts(reflectance: np.ndarray | float, params: SlipSensorParams | None = None) -> np.ndarray:
    """Mean output of the OPR5005 driver for a given effective reflectance.

    ``V_lin = supply * (1 - reflectance)``, softly saturated at ``v_sat``
    (see :class:`~slipreflex.sim.params.SlipSensorParams`). No noise, no ADC.

    Parameters
    ----------
    reflectance : float or array
        Effective reflectance(s) in [0, 1].
    params : SlipSensorParams, optional

    Returns
    -------
    numpy.ndarray

    Examples
    --------
    >>> round(float(opr5005_volts(0.0)), 6)
    5.0
    """
    p = params or SlipSensorParams()
    vlin = p.supply_v * (1.0 - np.asarray(reflectance, dtype=float))
    z = (vlin - p.v_sat) / p.knee_v
    return p.v_sat + p.knee_v * np.logaddexp(0.0, z)


def _spot_blur(x: np.ndarray, sigma: float, dx: float) -> np.ndarray:
    """``x`` seen through the sensor's Gaussian spot (sd ``sigma``): a diffuse reflective sensor integrates
    its whole spot, so edges and texture are blurred alike (ends padded with their end values).

    Examples
    --------
    >>> import numpy as np
    >>> y = _spot_blur(np.r_[np.zeros(400), np.ones(400)], 1e-4, 5e-6)
    >>> round(float(y[400] + y[399]), 6), round(float(y[0]), 12), round(float(y[-1]), 12)
    (1.0, 0.0, 1.0)
    """
    if sigma <= 0:
        return x
    from scipy.signal import fftconvolve  # deferred: heavy (scipy)

    half = int(np.ceil(4 * sigma / dx))
    xs = np.arange(-half, half + 1) * dx
    ker = np.exp(-0.5 * (xs / sigma) ** 2)
    ker /= ker.sum()
    padded = np.concatenate([np.full(half, x[0]), x, np.full(half, x[-1])])
    return fftconvolve(padded, ker, mode="valid")


@dataclass(frozen=True)
class Track:
    """What the slip sensor sees along a path over one or more surfaces.

    Attributes
    ----------
    rho : numpy.ndarray
        Effective reflectance every ``dx`` metres (texture included).
    dx : float
        Spacing (m).
    origin : float
        Index offset: surface position ``p`` (m) maps to sample ``(p + origin) / dx``.

    Examples
    --------
    >>> import numpy as np
    >>> from slipreflex.sim import SURFACES
    >>> tr = Track.build([(SURFACES["white"], 0.01)], np.random.default_rng(0), lead=0.002)
    >>> 0.85 < float(tr.rho[tr.rho.size // 2]) < 1.0
    True
    """

    rho: np.ndarray
    dx: float
    origin: float

    @classmethod
    def build(cls, layout: Sequence[tuple[Surface, float]], rng: np.random.Generator, *,
              lead: float = 0.0, sensor: SlipSensorParams | None = None, dx: float = TRACK_DX) -> Track:
        """Lay surfaces end to end and sample what the sensor sees.

        Parameters
        ----------
        layout : sequence of (Surface, length_m)
            Surfaces in the order the sensor meets them. The first extends
            ``lead`` metres before position 0 and the last extends to the end.
        rng : numpy.random.Generator
            Texture source (one independent texture per segment).
        lead : float
            Margin (m) before position 0 (for negative displacements).
        sensor : SlipSensorParams, optional
            For the spot size that blurs what the sensor sees (edges between
            surfaces and the texture alike).
        dx : float
            Grid spacing (m).

        Returns
        -------
        Track
            Its ``rho`` may be shared with other tracks built from the same inputs: read it, never
            write it.

        Examples
        --------
        >>> import numpy as np
        >>> from slipreflex.sim import SURFACES
        >>> r1, r2 = np.random.default_rng(5), np.random.default_rng(5)
        >>> a = Track.build([(SURFACES["white"], 0.01)], r1)
        >>> b = Track.build([(SURFACES["white"], 0.01)], r2)   # the same track, from the cache
        >>> a.rho is b.rho, r1.random() == r2.random()           # and the generators end alike
        (True, True)
        """
        sensor = sensor or SlipSensorParams()
        # the key holds every input, the generator's whole state included, so a hit returns the same
        # bits a build would, and leaves the generator where a build would have left it
        key = (repr(list(layout)), float(lead), repr(sensor), float(dx), repr(rng.bit_generator.state))
        hit = _TRACKS.get(key)
        if hit is not None:
            _TRACKS.move_to_end(key)
            track, after = hit
            rng.bit_generator.state = after
            return track
        track = cls._build(layout, rng, lead=lead, sensor=sensor, dx=dx)
        _TRACKS[key] = (track, rng.bit_generator.state)
        while len(_TRACKS) > TRACK_CACHE_SIZE:
            _TRACKS.popitem(last=False)
        return track

    @classmethod
    def _build(cls, layout: Sequence[tuple[Surface, float]], rng: np.random.Generator, *,
               lead: float, sensor: SlipSensorParams, dx: float) -> Track:
        total = lead + sum(length for _, length in layout)
        n = int(np.ceil(total / dx)) + 2
        pos = np.arange(n) * dx - lead
        edges = np.cumsum([0.0] + [length for _, length in layout])
        seg = np.clip(np.searchsorted(edges, pos, side="right") - 1, 0, len(layout) - 1)
        base = np.array([s.reflectance for s, _ in layout])[seg]
        tex = np.zeros(n)
        for i, (surf, _) in enumerate(layout):
            mask = seg == i
            t = _kept_texture(n, dx, surf, rng)
            tex[mask] = (surf.reflectance * surf.texture * t)[mask]
            # the second draw per segment was the tactile undulation (removed); its random numbers are
            # still drawn (not transformed) so that every later segment's texture, and the scan
            # calibrated on them, stay bit for bit
            m = n // 2 + 1
            rng.standard_normal(m)
            rng.standard_normal(m)
        rho = np.clip(_spot_blur(base + tex, sensor.spot_sigma_m, dx), 0.0, 1.0)
        return cls(rho=np.ascontiguousarray(rho), dx=dx, origin=lead)

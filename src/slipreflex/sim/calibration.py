"""Calibration of the plant to the paper's open-loop facts, by code.

The one open-loop fact of the paper's grasp is the first pour slip: with the
0.8 N grasp and before any controller acts, the bottle first slips near
200 ml (paper Fig. 15 and section III-B). It fixes the grasp's static
capacity. The pads' static friction ``mu_s`` is the least known constant of
that capacity, so it is the one calibrated: :func:`calibrate_bottle` finds
the ``mu_s`` (``mu_k`` keeps its ratio to ``mu_s``) at which the open-loop
first slip, as the paper's accelerometer recipe and flow sensor observe it
(:func:`first_slip`), comes at the target volume, for any variant of the plant (a
different latency, stiffness or friction law recalibrates instead of
silently moving the volume). Nothing here looks at a closed-loop result.

:func:`drop_fall_capacity` answers the paper's other open-loop question:
the largest static capacity at which a 10 g drop, without a reflex, still
ends in complete slippage (the report sets it beside the capacity the first
pour slip implies).

Examples
--------
>>> from slipreflex.sim import BOTTLES
>>> from slipreflex.sim.calibration import first_slip_ml
>>> 185 < first_slip_ml(BOTTLES["TR"]) < 215
True
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, fields, replace
from typing import Any

import numpy as np

from ..core import hardware as hw
from ..core.errors import ParameterError
from ..core.registry import EntryPoint
from . import kernel as K
from .contacts import static_capacity
from .objects import PAPER_DROP, PAPER_POUR, WATER_DENSITY, Bottle, Drop, Pour
from .rig import Rig

__all__ = ["PAPER_FIRST_SLIP_ML", "CALIBRATION_SEEDS", "LANDING_S", "OBSERVED_ONSET", "FirstSlip", "first_slip",
           "first_slip_ml",
           "calibrate_bottle", "Calibration",
           "drop_falls", "drop_fall_capacity", "GraspFailed", "check_grasp", "plant_lines", "pinned"]

#: The paper's open-loop first pour slip (ml): "the first slip occurred at about 200 ml" (Fig. 15).
PAPER_FIRST_SLIP_ML: float = 200.0
#: Rig seeds whose open-loop first slips are averaged (the grasp stops at a slightly different force per seed).
CALIBRATION_SEEDS: tuple[int, ...] = (0, 1, 2)
_REST_S = 0.5


class GraspFailed(ParameterError):
    """The grasp does not hold the bottle before any perturbation.

    Examples
    --------
    >>> issubclass(GraspFailed, ParameterError)
    True
    """


def _holds(bottle: Bottle, force: float, rig_kwargs: dict[str, Any] | None, seed: int):

    rig = Rig(bottle, seed=seed, **(rig_kwargs or {}))
    return rig, rig.grasp(force)


def check_grasp(bottle: Bottle, force: float = hw.CONTACT_FORCE_N, *, rig_kwargs: dict[str, Any] | None = None,
                seed: int = 0) -> None:
    """Raise :class:`GraspFailed` at once if a ``force`` grasp cannot hold the empty ``bottle``.

    One grasp on the simulated rig (about 0.1 s of computing). If it fails,
    a few more grasps find what would hold the bottle (the support is taken
    away at once, so the grasp must hold more than the static weight), and
    the message says what to change: the grasp force or the pads' friction.

    Examples
    --------
    >>> from slipreflex.sim import BOTTLES
    >>> check_grasp(BOTTLES["TR"])
    >>> from dataclasses import replace
    >>> check_grasp(replace(BOTTLES["TR"], name="JAR", mass_kg=0.25, mu_s=0.4, mu_k=0.3))
    Traceback (most recent call last):
    ...
    slipreflex.sim.calibration.GraspFailed: bottle JAR: the 0.8 N grasp cannot hold it (250 g ...
    """
    rig, g = _holds(bottle, force, rig_kwargs, seed)
    if g.stable:
        return
    h = rig.daq_history()
    reached = float(h.normal_force[h.t <= g.t_release][-1])   # per contact, when the support went
    weight = bottle.mass_kg * hw.GRAVITY
    need_force = next((force * 1.25 ** k for k in range(1, 13)
                       if _holds(bottle, force * 1.25 ** k, rig_kwargs, seed)[1].stable), None)
    ratio = bottle.mu_k / bottle.mu_s

    def gripping(k: int) -> Bottle:
        m = bottle.mu_s * 1.15 ** k
        return replace(bottle, mu_s=m, mu_k=m * ratio)

    need_mu = next((gripping(k).mu_s for k in range(1, 13)
                    if bottle.mu_s * 1.15 ** k <= 5.0 and _holds(gripping(k), force, rig_kwargs, seed)[1].stable),
                   None)
    force_txt = f"a grasp force of about {need_force:.1f} N" if need_force else "a much stronger grasp"
    mu_txt = f"mu_s {bottle.mu_s:g} -> about {need_mu:.2f}" if need_mu else "far more friction"
    raise GraspFailed(
        f"bottle {bottle.name}: the {force:g} N grasp cannot hold it ({bottle.mass_kg * 1e3:.0f} g weighs "
        f"{weight:.2f} N; the grasp's static capacity is {static_capacity(bottle, reached):.2f} N and the "
        f"support is taken away at once): use {force_txt} (--grasp-force), or pads that grip better ({mu_txt})")


def _rig(bottle: Bottle, seed: int, rig_kwargs: dict[str, Any] | None, grasp_force: float):

    rig = Rig(bottle, seed=seed, **(rig_kwargs or {}))
    rig.grasp(grasp_force)
    return rig


#: After the poured water lands, its knock is over by this time (s): the analysis of a pour trial
#: starts looking for slips this long after the jet lands (``slipreflex.reproduce.experiments.LANDING_S``, the
#: same value; a test keeps them equal).
LANDING_S: float = 0.1
#: After the bottle has fallen out, the open-loop recording goes on this long (s): the fall's
#: acceleration is in it, so the accelerometer recipe always has the slip it looks for.
_AFTER_FALL_S = 0.3


@dataclass(frozen=True)
class FirstSlip:
    """The open-loop first pour slip of one bottle: the simulator's truth and what the paper's instruments see.

    Attributes
    ----------
    true_ml : float
        Water in the bottle (ml, the water that has landed) when every contact first slides
        (the simulator's true onset, creep included), mean over the seeds.
    observed_ml : float
        The flow sensor's volume (ml) at the slip onset that the accelerometer recipe finds
        (:func:`slipreflex.analysis.onset.detect_onset`'s steps, segmented as a pour trial is:
        :func:`slipreflex.analysis.events.segment_events`), mean over the seeds: the paper's
        "first slip at about 200 ml" is this number.
    delay_s : float
        Mean time (s) from the true onset to the observed one.
    per_seed : tuple of (float, float)
        ``(true_ml, observed_ml)`` of every seed.

    Examples
    --------
    >>> FirstSlip(190.0, 200.0, 0.5, ()).observed_ml
    200.0
    """

    true_ml: float
    observed_ml: float
    delay_s: float
    per_seed: tuple = ()


#: The paper's accelerometer-onset recipe for the first slip of a pour recording, named by entry point:
#: it sits above the simulator (``slipreflex.analysis``), which must not be imported from here.
OBSERVED_ONSET = EntryPoint("slipreflex.analysis.events:first_pour_slip")


def _observed_onset(rig, t_rec: float, t0: float, pour: Pour) -> tuple[float, float]:
    """(onset time, flow-sensor ml at it) of the first slip the accelerometer recipe finds (NaN, NaN if none)."""
    rows, _ = rig.daq_rows(since=t_rec)   # the three columns read, as rig.daq_history would give them
    t, accel = rows[:, K.O_T].copy(), rows[:, K.O_AX:K.O_AZ + 1].copy()
    lo = t0 + math.sqrt(2.0 * pour.fall_height_m / hw.GRAVITY) + LANDING_S
    ml = rows[:, K.O_PULSES].astype(np.int64) / hw.FLOW_PULSES_PER_LITRE * 1000.0
    return OBSERVED_ONSET(t, accel, ml, (lo, float(t[-1]) if t.size else lo))


def first_slip(bottle: Bottle, *, rig_kwargs: dict[str, Any] | None = None, seeds=CALIBRATION_SEEDS,
               pour: Pour = PAPER_POUR, grasp_force: float = hw.CONTACT_FORCE_N,
               memo: dict | None = None) -> FirstSlip:
    """The open-loop first pour slip, true and as the accelerometer recipe observes it.

    The grasp closes to ``grasp_force``, the rig records from there, the pour
    starts 0.5 s later and no reflex acts. The run goes on until the bottle
    has fallen out (and 0.3 s more) or 1 s after the pour. The true onset is
    the simulator's first gross slip of the contacts; the observed one is
    what the paper's recipe finds in the recording's accelerometer (the
    same steps and episode rules that analyse a pour trial), and its volume
    is the flow sensor's (as in the paper's Fig. 15A). A slow rate-and-state
    slip creeps before its acceleration shows, so the observed volume is the
    larger.

    ``memo``: a dict of single pours by every input but the bottle's name and surface (see
    :func:`calibrate_bottle`): a pour of the same plant, seed and friction is not run again (a
    search with one seed and a later one with three share their first seed's pours).

    Returns
    -------
    FirstSlip
        ``nan`` volumes if the bottle does not slip during the pour (or the
        recipe finds no slip), ``0.0`` if the grasp does not hold the empty
        bottle.

    Examples
    --------
    >>> from slipreflex.sim import BOTTLES
    >>> s = first_slip(BOTTLES["DK"], seeds=(0,))
    >>> s.observed_ml >= s.true_ml > 100
    True
    """
    trues, obs, delays = [], [], []
    for seed in seeds:
        key = (_mechanics(bottle), repr(rig_kwargs), repr(seed), repr(pour), repr(grasp_force))
        one = memo.get(key) if memo is not None else None
        if one is None:
            one = _pour_once(bottle, seed, rig_kwargs, pour, grasp_force)
            if memo is not None:
                memo[key] = one
        if one is _HELD_NOTHING:
            return FirstSlip(0.0, 0.0, math.nan, ((0.0, 0.0),))
        if one is _NO_SLIP:
            return FirstSlip(math.nan, math.nan, math.nan, ((math.nan, math.nan),))
        trues.append(one[0])
        obs.append(one[1])
        delays.append(one[2])
    return FirstSlip(float(np.mean(trues)), float(np.mean(obs)), float(np.mean(delays)), tuple(zip(trues, obs)))


#: What :func:`_pour_once` returns when the grasp does not hold the empty bottle, and when it does not slip.
_HELD_NOTHING, _NO_SLIP = ("grasp does not hold",), ("no slip",)


def _pour_once(bottle: Bottle, seed, rig_kwargs: dict[str, Any] | None, pour: Pour,
               grasp_force: float) -> tuple:
    """One seed's open-loop pour: ``(true ml, observed ml, delay s)``, or :data:`_HELD_NOTHING`, :data:`_NO_SLIP`."""
    rig = _rig(bottle, seed, rig_kwargs, grasp_force)
    if rig.fallen or rig.slipping:
        return _HELD_NOTHING
    t_rec = rig.t
    t0 = rig.t + _REST_S
    rig.perturb(pour, at=t0)
    end = t0 + pour.duration_s + 1.0
    n0 = rig.onsets.size
    stop, last = end, -1.0
    while rig.t < stop and rig.t > last:      # (the rig stops on its own time grid, at or before `stop`)
        last = rig.t
        rig.run_to(min(stop, rig.t + 0.5))
        fell = rig.fall_time
        if fell is not None:
            stop = min(stop, float(fell) + _AFTER_FALL_S)
    if rig.onsets.size == n0:
        return _NO_SLIP
    t_on = float(rig.onsets[n0])
    t_obs, ml = _observed_onset(rig, t_rec, t0, pour)
    return _water_kg(pour, t0, t_on) / WATER_DENSITY * 1e6, ml, t_obs - t_on


def first_slip_ml(bottle: Bottle, *, rig_kwargs: dict[str, Any] | None = None, seeds=CALIBRATION_SEEDS,
                  pour: Pour = PAPER_POUR, grasp_force: float = hw.CONTACT_FORCE_N, observed: bool = True) -> float:
    """Water in the bottle (ml) at the first slip of an open-loop pour, averaged over ``seeds``.

    As the paper's instruments see it (``observed=True``, the default: the
    accelerometer recipe's onset and the flow sensor's volume), or the
    simulator's true onset (``observed=False``). See :func:`first_slip`.

    Returns
    -------
    float
        ml; ``nan`` if the bottle does not slip during the pour, ``0.0`` if
        the grasp does not hold the empty bottle.

    Examples
    --------
    >>> from slipreflex.sim import BOTTLES
    >>> first_slip_ml(BOTTLES["DK"], seeds=(0,)) > first_slip_ml(BOTTLES["DK"], seeds=(0,), observed=False)
    True
    """
    s = first_slip(bottle, rig_kwargs=rig_kwargs, seeds=seeds, pour=pour, grasp_force=grasp_force)
    return s.observed_ml if observed else s.true_ml


def _water_kg(pour: Pour, t0: float, t: float) -> float:
    delay = math.sqrt(2.0 * pour.fall_height_m / hw.GRAVITY)
    flow = min(max(t - t0 - delay, 0.0), pour.duration_s)
    return pour.rate_l_min / 60.0 * flow * 1e-3 * WATER_DENSITY


@dataclass(frozen=True)
class Calibration:
    """Result of :func:`calibrate_bottle`.

    Attributes
    ----------
    bottle : Bottle
        The bottle with the calibrated pad friction.
    first_slip_ml : float
        Its open-loop first slip (ml) after calibration.
    target_ml : float
    mu_s, mu_k : float
        The calibrated pad friction.
    capacity_n : float
        Static capacity (N) of the grasp at the nominal 1 N per contact.
    note : str
        ``""``, or why the first slip is not at the target (a jump of the first
        slip over the target: the nearest reachable volume in ``band_ml`` was taken).
    true_first_slip_ml : float
        The simulator's true first slip (ml) at the calibrated friction
        (``first_slip_ml`` is the observed one, the one calibrated).

    Examples
    --------
    >>> from slipreflex.sim import BOTTLES
    >>> Calibration(BOTTLES["TR"], 200.0, 200.0, 1.0, 0.75, 2.3).mu_s
    1.0
    """

    bottle: Bottle
    first_slip_ml: float
    target_ml: float
    mu_s: float
    mu_k: float
    capacity_n: float
    note: str = ""
    true_first_slip_ml: float = math.nan


#: Relative width (of ``mu_s``) under which a bracket of the first slip that still straddles the
#: target is a jump of the first slip, not a slope: the search stops there.
_JUMP_REL_MU = 1e-4


def _bracket(f, mu: float, target: float, name: str) -> tuple[tuple[float, float], tuple[float, float]]:
    """``((mu_lo, ml_lo), (mu_hi, ml_hi))`` with ``ml_lo < target <= ml_hi``, growing or shrinking ``mu`` by 1.5x."""
    v = f(mu)
    step = 1.5 if v < target else 1.0 / 1.5
    a = (mu, v)
    for _ in range(12):
        m = a[0] * step
        if m > 5.0:
            break
        b = (m, f(m))
        if (b[1] < target) != (a[1] < target):
            return (a, b) if a[1] < target else (b, a)
        a = b
    end = "at most" if a[1] < target else "already"
    raise ParameterError(f"calibration: no pad mu_s in (0, 5] puts the open-loop first slip of bottle {name} at "
                         f"{target:g} ml (mu_s {a[0]:.3g}: {end} {a[1]:.0f} ml): the grasp's capacity is outside "
                         "the range searched")


def _search(f, lo, hi, target: float, tol: float):
    """Illinois regula falsi inside the bracket ``lo``, ``hi`` (``(mu, ml)`` pairs).

    Returns the best point and the final bracket; the bracket narrows onto a
    jump of the first slip when the target lies inside one.
    """
    best = min(lo, hi, key=lambda p: abs(p[1] - target))
    g_lo, g_hi, side = lo[1] - target, hi[1] - target, 0
    for _ in range(40):
        if abs(best[1] - target) <= tol or hi[0] - lo[0] <= _JUMP_REL_MU * hi[0]:
            break
        m = hi[0] - g_hi * (hi[0] - lo[0]) / (g_hi - g_lo)
        p = (m, f(m))
        best = min(best, p, key=lambda q: abs(q[1] - target))
        if p[1] < target:
            lo, g_lo = p, p[1] - target
            g_hi, side = (g_hi / 2 if side == -1 else g_hi), -1
        else:
            hi, g_hi = p, p[1] - target
            g_lo, side = (g_lo / 2 if side == 1 else g_lo), 1
    return best, lo, hi


def calibrate_bottle(bottle: Bottle, target_ml: float = PAPER_FIRST_SLIP_ML, *,
                     rig_kwargs: dict[str, Any] | None = None, seeds=CALIBRATION_SEEDS, pour: Pour = PAPER_POUR,
                     grasp_force: float = hw.CONTACT_FORCE_N, tol_ml: float = 1.0,
                     band_ml: tuple[float, float] | None = None, observed: bool = True,
                     memo: dict | None = None) -> Calibration:
    """Calibrate the pads' static friction so that the observed open-loop first pour slip comes at ``target_ml``.

    The first slip calibrated is the one the paper's instruments saw
    (:func:`first_slip`: the accelerometer recipe's onset, the flow sensor's
    volume), not the simulator's earlier true onset (``observed=False``
    calibrates that one instead: :attr:`Calibration.first_slip_ml` is then the
    true volume). On a plant whose middle-finger cuff sticks and slips, the
    accelerometer sees the cuff's first slip: the observed first slip stays
    there whatever the pads' friction, and no pad friction meets a later target.
    The search stops as soon as two frictions show it (every seed observed
    before its true onset, below the volumes accepted, at the same volume).

    The first slip grows with ``mu_s`` (``mu_k / mu_s`` kept), but in steps:
    the bottle slips grossly only when all three contacts slide, and the
    middle finger's cuff sticks and slips in its own cycle as the water comes
    in, so the first gross slip can only start at one of the cuff's slips
    (steps of a few ml to about 45 ml, depending on the plant). The search
    brackets the target, then narrows the bracket by Illinois regula falsi
    until a point is within ``max(tol_ml, 2 % of the target)`` or the
    bracket has closed onto a step's jump over the target. In that case no
    pad friction reaches the target: with ``band_ml`` (the volumes that
    still meet the paper's fact, e.g. its "about 200 ml" read as 170-230 ml)
    the edge of the jump nearest the target within the band is taken, a
    little inside its step, and :attr:`Calibration.note` says so.

    ``memo``: a dict shared by the calibrations of one plant's bottles. An open-loop pour's first
    slip does not depend on the bottle's name or surface (the surface only feeds the slip
    sensor's track, which no state and no accelerometer or flow reading depends on), so bottles
    that differ only there (TR and DK: one polymer, one finish) share their pours: the same
    numbers, one computation. Its entries are single pours (one seed each), so a search with
    several seeds after a one-seed search does not run the first seed's pours again.

    Raises
    ------
    ParameterError
        If the target is outside the capacities ``mu_s`` in (0, 5] reach, or
        lies inside a jump of the first slip with neither edge in ``band_ml``
        (the message gives the jump).

    Examples
    --------
    >>> from slipreflex.sim import BOTTLES
    >>> c = calibrate_bottle(BOTTLES["TR"], 150.0, seeds=(0,))
    >>> abs(c.first_slip_ml - 150.0) <= 3.0 and c.mu_s < BOTTLES["TR"].mu_s, c.note
    (True, '')
    """
    if not (isinstance(target_ml, (int, float)) and 0 < target_ml < pour.volume_ml):
        raise ParameterError(f"first-slip volume must be in (0, {pour.volume_ml:g}) ml, got {target_ml!r}")
    if band_ml is not None and not (len(band_ml) == 2 and 0 < band_ml[0] <= band_ml[1] < pour.volume_ml):
        raise ParameterError(f"band_ml must be (low, high) with 0 < low <= high < {pour.volume_ml:g} ml, "
                             f"got {band_ml!r}")
    ratio = bottle.mu_k / bottle.mu_s

    def with_mu(mu: float) -> Bottle:
        return replace(bottle, mu_s=mu, mu_k=mu * ratio)

    seen: dict[float, FirstSlip] = {}
    tol = max(tol_ml, 0.02 * target_ml)
    lowest = target_ml - tol if band_ml is None else min(target_ml - tol, band_ml[0])

    def f(mu: float) -> float:   # a bottle that does not slip during the pour counts as twice its volume
        s = seen[mu] = first_slip(with_mu(mu), rig_kwargs=rig_kwargs, seeds=seeds, pour=pour,
                                  grasp_force=grasp_force, memo=memo)
        if observed:
            _stop_if_pinned(seen, mu, lowest, target_ml, band_ml, bottle.name)
        v = s.observed_ml if observed else s.true_ml
        return pour.volume_ml * 2 if math.isnan(v) else v

    best, lo, hi = _search(f, *_bracket(f, bottle.mu_s, target_ml, bottle.name), target_ml, tol)
    note = ""
    if abs(best[1] - target_ml) > tol:
        best, note = _across_jump(f, lo, hi, target_ml, band_ml, bottle.name)
    b = with_mu(best[0])
    return Calibration(b, best[1], float(target_ml), b.mu_s, b.mu_k, static_capacity(b, 1.0), note,
                       seen[best[0]].true_ml)


#: The words of a calibration error that only a first slip pinned at the cuff's slip says (:func:`pinned`).
_PINNED = "alike, before its true onsets"


def pinned(why: str) -> bool:
    """Whether a calibration's error (or a study plant's ``rejected`` text) is a first slip pinned at the cuff's.

    Examples
    --------
    >>> pinned("... observed at 4.4 ml at pad mu_s 0.84 and 1.26 alike, before its true onsets (224 and 345 ml) ...")
    True
    >>> pinned("observed first slip outside the paper's 170-230 ml: TR 240 ml")
    False
    """
    return _PINNED in why


def _early(s: FirstSlip, lowest: float) -> tuple[float, ...] | None:
    """The observed volumes of ``s``'s seeds if every one comes before its seed's true onset and below ``lowest``."""
    if not s.per_seed or not all(o < t and o < lowest for t, o in s.per_seed):   # (NaN compares false)
        return None
    return tuple(o for _, o in s.per_seed)


def _stop_if_pinned(seen: dict[float, FirstSlip], mu: float, lowest: float, target: float, band_ml,
                    name: str) -> None:
    """Raise :class:`ParameterError` if the observed first slip at ``mu`` is pinned at the cuff's slip.

    Pinned: at ``mu`` and at another friction already tried, every seed's observed onset comes before
    its true onset, below the lowest volume accepted, at the same volume at both frictions. The
    accelerometer then sees a slip of the middle finger's cuff, which the pads' friction does not move
    (while the pads stick they share the load by stiffness, not friction), and the gross slip, which
    does move, can only be observed later than that: no pad friction brings the observed first slip up
    to the target. The search would otherwise narrow onto the friction at which the gross slip leaves
    the pour, a jump to "no slip" that is no answer either.
    """
    here = _early(seen[mu], lowest)
    if here is None:
        return
    other = next((m for m, s in seen.items() if m != mu and _early(s, lowest) == here), None)
    if other is None:
        return
    within = "" if band_ml is None else f", nor in {band_ml[0]:g}-{band_ml[1]:g} ml"
    trues = " and ".join(f"{seen[m].true_ml:.0f}" for m in sorted((other, mu)))
    raise ParameterError(
        f"calibration: the open-loop first slip of bottle {name} is observed at {seen[mu].observed_ml:.1f} ml "
        f"at pad mu_s {min(other, mu):.4g} and {max(other, mu):.4g} {_PINNED} ({trues} ml): "
        f"the accelerometer sees a slip of the middle finger's cuff, which the pads' friction does not move, "
        f"so no pad mu_s puts it at {target:g} ml{within}")


def _mechanics(bottle: Bottle) -> str:
    """Every field of ``bottle`` an open-loop pour's first slip depends on (all but its name and surface)."""
    return repr([(f.name, getattr(bottle, f.name)) for f in fields(bottle) if f.name not in ("name", "surface")])


def _across_jump(f, lo, hi, target: float, band_ml, name: str) -> tuple[tuple[float, float], str]:
    """The edge of the jump ``lo`` -> ``hi`` nearest ``target`` within ``band_ml``, 1 % of mu_s inside its step."""
    jump = (f"the open-loop first slip of bottle {name} jumps from {lo[1]:.1f} to {hi[1]:.1f} ml at pad mu_s "
            f"{hi[0]:.4g} (a gross slip starts only at a slip of the middle finger's cuff)")
    inside = [p for p in (lo, hi) if band_ml is not None and band_ml[0] <= p[1] <= band_ml[1]]
    if not inside or band_ml is None:
        within = "" if band_ml is None else f", nor in {band_ml[0]:g}-{band_ml[1]:g} ml"
        raise ParameterError(f"calibration: {jump}: no pad mu_s puts it at {target:g} ml{within}")
    edge = min(inside, key=lambda p: abs(p[1] - target))
    nudged = edge[0] * (1.01 if edge is hi else 1.0 / 1.01)
    v = f(nudged)
    if abs(v - edge[1]) <= 0.5:   # still on the edge's step: keep away from the jump
        edge = (nudged, v)
    return edge, f"{jump}: calibrated to the nearest edge in {band_ml[0]:g}-{band_ml[1]:g} ml, {edge[1]:.1f} ml"


def drop_falls(bottle: Bottle, *, rig_kwargs: dict[str, Any] | None = None, seed: int = 0,
               drop: Drop = PAPER_DROP, grasp_force: float = hw.CONTACT_FORCE_N, after_s: float = 2.0) -> bool:
    """Whether an open-loop drop ends in complete slippage (the bottle falls out).

    Examples
    --------
    >>> from slipreflex.sim import BOTTLES
    >>> drop_falls(BOTTLES["TR"])
    False
    """
    rig = _rig(bottle, seed, rig_kwargs, grasp_force)
    if rig.fallen:
        return True
    rig.perturb(drop, at=rig.t + _REST_S)
    rig.advance_block(rig.t + _REST_S + after_s)
    return rig.fallen


def drop_fall_capacity(bottle: Bottle, *, rig_kwargs: dict[str, Any] | None = None, seed: int = 0,
                       drop: Drop = PAPER_DROP, grasp_force: float = hw.CONTACT_FORCE_N,
                       iterations: int = 12) -> dict[str, float]:
    """The largest static capacity at which an open-loop drop still ends in complete slippage.

    Bisection on the pads' ``mu_s`` (``mu_k / mu_s`` kept) between a grasp
    that barely holds the empty bottle and ``bottle.mu_s``.

    Returns
    -------
    dict
        ``capacity_n`` (static capacity at the grasp's normal force, N),
        ``capacity_g`` (the same as a mass, g), ``mu_s`` (pads), and
        ``bottle_capacity_g``: the capacity ``bottle`` itself has. NaN
        values when even the weakest grasp that holds the empty bottle
        survives the drop.

    Examples
    --------
    >>> from slipreflex.sim import BOTTLES
    >>> r = drop_fall_capacity(BOTTLES["TR"], iterations=6)
    >>> r["capacity_g"] < r["bottle_capacity_g"]
    True
    """
    ratio = bottle.mu_k / bottle.mu_s
    rig = _rig(bottle, seed, rig_kwargs, grasp_force)
    nc = rig.normal_force
    g = hw.GRAVITY
    mu_hold = (1.02 * bottle.mass_kg * g / nc - bottle.cuff_mu_s) / 2.0
    lo = max(mu_hold, bottle.mu_k * 0 + 1e-3)
    hi = bottle.mu_s

    def falls(mu: float) -> bool:
        b = replace(bottle, mu_s=mu, mu_k=min(mu * ratio, mu))
        return drop_falls(b, rig_kwargs=rig_kwargs, seed=seed, drop=drop, grasp_force=grasp_force)

    own = static_capacity(bottle, nc)
    if falls(hi):
        mu = hi
    elif not falls(lo):
        nan = float("nan")
        return {"capacity_n": nan, "capacity_g": nan, "mu_s": nan, "bottle_capacity_g": own / g * 1e3}
    else:
        for _ in range(iterations):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if falls(mid) else (lo, mid)
        mu = lo
    cap = static_capacity(replace(bottle, mu_s=mu, mu_k=min(mu * ratio, mu)), nc)
    return {"capacity_n": cap, "capacity_g": cap / g * 1e3, "mu_s": mu, "bottle_capacity_g": own / g * 1e3}


def plant_lines(bottles: Sequence[Bottle], grasp_force: float = hw.CONTACT_FORCE_N, *,
                rig_kwargs: dict[str, Any] | None = None) -> list[str]:
    """Report lines on the plant of a run: each bottle's open-loop first pour slip and its calibrated friction.

    Computed (one open-loop pour per bottle, seed 0), not quoted, so a run with
    another plant states its own values.

    Examples
    --------
    >>> from slipreflex.sim import BOTTLES
    >>> print(plant_lines([BOTTLES["TR"]])[0][:60])
    open-loop first pour slip (0.8 N grasp, no reflex, seed 0):
    """
    slips = ", ".join(f"{b.name} {first_slip_ml(b, rig_kwargs=rig_kwargs, seeds=(0,), grasp_force=grasp_force):.0f} ml"
                      for b in bottles)
    fr = "; ".join(f"{b.name} pads mu_s {b.mu_s:g} / mu_k {b.mu_k:g}, cuff {b.cuff_mu_s:g} / {b.cuff_mu_k:g} "
                   f"({b.friction_law})" for b in bottles)
    return [f"open-loop first pour slip ({grasp_force:g} N grasp, no reflex, seed 0): {slips} (paper: about "
            f"{PAPER_FIRST_SLIP_ML:g} ml; the paper's bottles' pad mu_s is calibrated to it, `slipreflex calibrate`)",
            f"contact friction: {fr}"]

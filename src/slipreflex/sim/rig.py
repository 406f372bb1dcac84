"""The simulated rig: a bottle in the i-Limb's tripod grasp, with the paper's sensors.

:class:`Rig` owns the physics, the hand (:class:`SimHand`, a
:class:`slipreflex.core.interfaces.Hand`) and the sensors. It is advanced from
outside in increments of any size (``rig.advance_to(t)`` /
``rig.advance(dt)``), which return the new DAQ samples
(:class:`slipreflex.core.interfaces.DaqSample`, 333.33 Hz: slip-sensor volts,
latest accelerometer reading in g, cumulative flow pulses); tactile frames
come from samplers at any rate (``rig.tactile_sampler(260.0)``). The whole
run is deterministic under ``seed`` and does not depend on how it is cut
into calls.

Timeline of a trial::

    rig = Rig("TR", seed=1)          # t = 0: fingers open, bottle on its support
    rig.grasp()                      # close to 0.8 N, settle, remove the support, settle
    rig.perturb(Drop(), at=rig.t + 1)
    trace = run_closed_loop(rig, reflex, 3.0)

Truth (what no real sensor gives): :attr:`Rig.displacement` (bottle
position below its grasp position, pad shear included), :attr:`Rig.slip`
(sliding distance at the contacts), :attr:`Rig.velocity`,
:attr:`Rig.slipping`, :attr:`Rig.onsets` (every stick -> slip transition),
:meth:`Rig.slip_events`, :attr:`Rig.fallen` / :attr:`Rig.fall_time`.

**Fallen out** means the bottle has slid ``Bottle.grip_travel_m`` (3 cm by
default) below where it was grasped: the fingertips reach the shoulder of
the bottle, the contacts are lost and the bottle drops.

Examples
--------
>>> from slipreflex.sim import Rig
>>> rig = Rig("TX", seed=0)
>>> g = rig.grasp()
>>> g.stable, round(g.force_n, 1) >= 0.8
(True, True)
>>> samples = rig.advance(0.03)
>>> len(samples), samples[0].accel_g is not None
(10, True)
"""

from __future__ import annotations

import copy
import math
import operator
from typing import Any

import numpy as np

from ..core import hardware as hw
from ..core._slots import slot
from ..core.errors import ParameterError
from ..core.hardware import Finger
from ..core.interfaces import DaqSample, GraspResult
from . import kernel as K
from .closing_memo import CLOSINGS, close, closing_key_of, closing_of, restore_closing
from .loads import kind_of
from .objects import BOTTLES, Bottle, Surface
from .params import (
    FlowParams,
    HandParams,
    ImuParams,
    PhysicsParams,
    SlipSensorParams,
    TactileParams,
    WaterParams,
)
from .rig_data import DaqBlock, KernelArrays, SlipEvent, slip_episodes
from .rig_params import fill_slip_sensor_params, rig_params
from .sensors import Track
from .sim_hand import SimHand
from .stepping import COARSE_STEP_S, STEPPING_ENV, STEPPINGS, default_stepping, seed_sequence, stepping
from .stepping import STEP_ROUND as _ROUND
from .tactile_sampler import TactileSampler

__all__ = ["Rig", "SimHand", "TactileSampler", "GraspResult", "DaqBlock", "SlipEvent", "KernelArrays",
           "seed_sequence", "fill_slip_sensor_params", "STEPPINGS", "STEPPING_ENV", "COARSE_STEP_S",
           "default_stepping", "stepping"]

_CHUNK_S = 0.25  # longest stretch one kernel call covers (bounds the buffers)
_SPLASH_GRID_S = 1e-3  # the splash noise is drawn every 1 ms (independent of dt) and interpolated

class Rig:
    """A bottle in the i-Limb's tripod grasp, with slip sensor, IMU, tactile arrays and flow sensor.

    Parameters
    ----------
    bottle : Bottle or str
        A :class:`Bottle` or a key of :data:`BOTTLES` ("TR", "DK", "TX").
    seed : int, SeedSequence or Generator, optional
        Seeds the surface texture and every noise stream (default 0). Same
        seed, bit-identical traces.
    hand, slip_sensor, imu, tactile, flow, physics, water : parameter dataclasses, optional
        See :mod:`slipreflex.sim.params`.
    history : bool
        Keep every DAQ row for :meth:`daq_history` (needed by
        :func:`~slipreflex.sim.run_closed_loop`; about 50 kB per simulated
        second). A long real-time session that only streams samples can
        turn it off.
    stepping : {"adaptive", "fixed"}, optional
        How the kernel steps (:data:`STEPPINGS`; default :func:`default_stepping`):
        coarse steps while nothing needs the fine one, or every ``physics.dt``
        (the reference).

    Examples
    --------
    >>> rig = Rig("DK", seed=5)
    >>> rig.t, rig.fallen, rig.slipping
    (0.0, False, False)
    >>> rig.displacement, rig.slip, rig.velocity, rig.normal_force, Rig("TR").load_mass, rig.tilt
    (0.0, 0.0, 0.0, 0.0, 0.04, 0.0)
    """

    def __init__(self, bottle: Bottle | str = "TR", seed: int | np.random.SeedSequence | np.random.Generator
                 | None = 0, *, hand: HandParams | None = None, slip_sensor: SlipSensorParams | None = None,
                 imu: ImuParams | None = None, tactile: TactileParams | None = None, flow: FlowParams | None = None,
                 physics: PhysicsParams | None = None, water: WaterParams | None = None,
                 history: bool = True, stepping: str | None = None) -> None:
        stepping = default_stepping() if stepping is None else stepping
        if stepping not in STEPPINGS:
            raise ParameterError(f"stepping: unknown {stepping!r} (known: {', '.join(STEPPINGS)})")
        self.stepping = stepping
        if isinstance(bottle, str):
            if bottle not in BOTTLES:
                raise ParameterError(f"bottle: unknown bottle {bottle!r} (known: {', '.join(BOTTLES)})")
            bottle = BOTTLES[bottle]
        if not isinstance(bottle, Bottle):
            raise ParameterError(f"bottle must be a Bottle or a name, got {bottle!r}")
        self.bottle = bottle
        self.hand_params = hand or HandParams()
        self.slip_sensor = slip_sensor or SlipSensorParams()
        self.imu = imu or ImuParams()
        self.tactile_params = tactile or TactileParams()
        self.flow = flow or FlowParams()
        self.physics = physics or PhysicsParams()
        self.water = water or WaterParams()
        if self.water.jet_offset_m >= bottle.diameter_m / 2.0:
            raise ParameterError(f"WaterParams.jet_offset_m {self.water.jet_offset_m!r} m must be inside bottle "
                                 f"{bottle.name}'s radius {bottle.diameter_m / 2.0!r} m")
        ss = seed_sequence(seed)
        self.seed = ss
        tex_ss, key_ss, flow_ss = ss.spawn(3)
        self._keys = key_ss.generate_state(8, dtype=np.uint64)
        frng = np.random.default_rng(flow_ss)
        flow_k = hw.FLOW_PULSES_PER_LITRE * (1.0 + self.flow.k_factor_sd * frng.standard_normal())
        flow_phase = frng.random()
        surf: Surface = bottle.surface  # type: ignore[assignment]
        self.track = Track.build([(surf, self.physics.track_length_m)], np.random.default_rng(tex_ss),
                                 lead=0.01, sensor=self.slip_sensor)
        self._P = self._params(flow_k, flow_phase)
        self._S = K.STATE.new()   # the layout's initial values; NaN in the slots set here
        for i in range(3):
            self._S[K.S_C0 + i * K.SC_SIZE:K.S_C0 + (i + 1) * K.SC_SIZE] = K.CONTACT.new()
        self._S[K.S_MASS] = bottle.mass_kg
        self._S[K.S_SPD0:K.S_SPD0 + 3] = self.hand_params.speed_units_s
        # the splash noise starts stationary on its 1 ms grid (stream keys[5])
        self._S[K.S_SPL0] = K.normal(self._keys[5], 0)
        P = self._P
        self._S[K.S_SPL1] = P[K.P_SPL_RHO] * self._S[K.S_SPL0] + P[K.P_SPL_SIG] * K.normal(self._keys[5], 1)
        # the digit motors turn with unrelated phases (stream keys[7])
        for i in range(3):
            self._S[K.S_MPH0 + i] = 2.0 * math.pi * float(K.uniform(self._keys[7], i))
        K.STATE.check(self._S)
        self._C = np.zeros(K.C_SIZE, dtype=np.int64)
        self._D = np.zeros((0, K.D_SIZE))
        self._W = np.zeros((0, K.W_SIZE))
        self.hand = SimHand(self, self.hand_params)
        self._samplers: list[TactileSampler] = []
        self._tac_rates = np.zeros(0)
        self._tac_next = np.zeros(0, dtype=np.int64)
        self._tac_contact = np.zeros(0, dtype=np.int64)
        self._n_samplers_made = 0
        self._oneoff = 0
        self._daq_chunks: list[np.ndarray] = []
        self.history = bool(history)
        self._events: list[np.ndarray] = []
        self.perturbations: list[tuple[float, Any]] = []
        cap_steps = int(math.ceil(_CHUNK_S / self.physics.dt)) + 2
        self._daq_buf = np.empty((int(_CHUNK_S * 2 * hw.DAQ_FS) + 8, K.O_SIZE))
        self._ev_buf = np.empty((3 * cap_steps + 8, 3))
        self._counts = np.zeros(3, dtype=np.int64)
        self._no_tac = np.empty((0, K.T_SIZE))
        self._grasp: GraspResult | None = None

    def __deepcopy__(self, memo: dict) -> Rig:
        """A copy that runs exactly as this rig runs (same state, same random streams); it shares the slip
        sensor's track (read-only, as every rig built from the same inputs shares it) and gets its own
        scratch buffers (they carry nothing from one kernel call to the next) instead of copies of them.

        Examples
        --------
        >>> import copy
        >>> rig = Rig("TR"); _ = rig.advance(0.01); twin = copy.deepcopy(rig)
        >>> twin.track is rig.track, twin.hand.positions() == rig.hand.positions(), twin.t == rig.t
        (True, True, True)
        """
        twin = type(self).__new__(type(self))
        memo[id(self)] = twin
        memo[id(self.track)] = self.track
        for scratch in (self._daq_buf, self._ev_buf, self._counts):
            memo[id(scratch)] = np.empty_like(scratch)
        for name, value in self.__dict__.items():
            twin.__dict__[name] = copy.deepcopy(value, memo)
        return twin

    # ------------------------------------------------------------------ setup
    def _params(self, flow_k: float, flow_phase: float) -> np.ndarray:
        return rig_params(self, flow_k, flow_phase)

    def coarse_steps(self, P: np.ndarray | None = None) -> int:
        """Fine steps one coarse step of the adaptive stepping spans at most: ``omega h <= 1`` for the stiffest
        mode of the held bottle (empty: its highest frequencies), and at most :data:`COARSE_STEP_S`. As water
        comes in the kernel lets it grow to :data:`COARSE_STEP_S` (:func:`slipreflex.sim.kernel.mass_cap`).

        Examples
        --------
        >>> Rig("TR").coarse_steps()
        16
        """
        par: np.ndarray = self._P if P is None else P
        m, dt = self.bottle.mass_kg, self.physics.dt
        inertia, _ = K.tilt_inertia(0.0, par)
        # the contacts' summed shear and tilt stiffness, as rig_params writes them for the kernel's mass_cap
        omega = max(math.sqrt(float(par[K.P_KT_SUM]) / m), math.sqrt(float(par[K.P_KLAT]) / m),
                    math.sqrt(float(par[K.P_TILT_K]) / inertia))
        return max(1, min(int(COARSE_STEP_S / dt + 1e-9), int(1.0 / (omega * dt))))

    # ------------------------------------------------------------------ time
    @property
    def _n(self) -> int:
        return int(self._C[K.C_N])

    @property
    def step_index(self) -> int:
        """Physics steps done since the rig started (``t = step_index * physics.dt``).

        Examples
        --------
        >>> Rig("TR").step_index
        0
        """
        return self._n

    @property
    def steps_taken(self) -> int:
        """Kernel steps taken so far: every ``physics.dt`` with fixed steps, fewer with adaptive ones
        (a coarse step counts once).

        Examples
        --------
        >>> rig = Rig("TR", stepping="fixed")
        >>> _ = rig.advance(0.01)
        >>> rig.steps_taken == rig.step_index
        True
        """
        return int(self._C[K.C_STEPS])

    @property
    def finger_q(self) -> np.ndarray:
        """Unrounded positions of thumb, index and middle (a copy; the hand reports them rounded).

        Examples
        --------
        >>> Rig("TR").finger_q.tolist()
        [0.0, 0.0, 0.0]
        """
        return self._S[K.S_Q0:K.S_Q0 + 3].copy()

    @property
    def samplers(self) -> tuple[TactileSampler, ...]:
        """The tactile samplers now running.

        Examples
        --------
        >>> rig = Rig("TR"); s = rig.tactile_sampler(100.0); rig.samplers == (s,)
        True
        """
        return tuple(self._samplers)

    def detach_sampler(self, sampler: TactileSampler) -> None:
        """Stop feeding ``sampler`` (what :meth:`TactileSampler.close` calls).

        Examples
        --------
        >>> rig = Rig("TR"); s = rig.tactile_sampler(100.0); rig.detach_sampler(s); rig.samplers
        ()
        """
        if sampler in self._samplers:
            self._samplers.remove(sampler)
            self._sync_samplers()

    @property
    def t(self) -> float:
        """Rig time (s).

        Examples
        --------
        >>> Rig("TR").t
        0.0
        """
        return self._n * self.physics.dt

    @property
    def next_daq_time(self) -> float:
        """Time (s) of the next DAQ sample not produced yet.

        Examples
        --------
        >>> rig = Rig("TR"); _ = rig.advance(0.01)
        >>> round(rig.t, 6), round(rig.next_daq_time, 6)    # samples every 3 ms: 0, 3, 6, 9 ms made
        (0.01, 0.012)
        """
        return int(self._C[K.C_DAQ]) * hw.DAQ_PERIOD_S

    @property
    def next_daq_index(self) -> int:
        """Index of the next DAQ sample not produced yet (its time ``index * DAQ_PERIOD_S``): ``Rig("TR")``
        after ``advance(0.01)`` has made samples 0-3, so 4."""
        return int(self._C[K.C_DAQ])

    def advance(self, duration: float) -> list[DaqSample]:
        """Advance by ``duration`` seconds; return the new DAQ samples.

        Examples
        --------
        >>> len(Rig("TR").advance(0.1))
        34
        """
        return self.advance_to(self.t + duration)

    def advance_to(self, t: float) -> list[DaqSample]:
        """Advance to time ``t`` (s); return the DAQ samples with times in (previous t, t].

        Examples
        --------
        >>> [round(s.t, 3) for s in Rig("TR").advance_to(0.007)]
        [0.0, 0.003, 0.006]
        """
        return self.advance_block(t).samples()

    def advance_block(self, t: float) -> DaqBlock:
        """Like :meth:`advance_to`, but the samples (and truth) come as arrays.

        Examples
        --------
        >>> Rig("TR").advance_block(1.0).volts.size
        334
        """
        seq0 = int(self._C[K.C_DAQ])
        return DaqBlock.from_rows(self._advance_rows(t), seq0)

    def run_to(self, t: float) -> int:
        """Like :meth:`advance_to`, but nothing is handed back (the history keeps the samples): the number of
        new DAQ samples.

        Examples
        --------
        >>> rig = Rig("TR"); rig.run_to(1.0), rig.daq_history().t.size
        (334, 334)
        """
        return int(self._advance_rows(t).shape[0])

    def advance_slip(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Advance to ``t``; return the new DAQ samples' times, slip volts and middle-finger positions.

        The fast path of the closed loop (arrays, no per-sample objects); the
        same samples :meth:`advance_to` would return.

        Examples
        --------
        >>> t, volts, middle = Rig("TR").advance_slip(0.01)
        >>> t.size == volts.size == middle.size == 4
        True
        """
        rows = self._advance_rows(t)
        return rows[:, K.O_T].copy(), rows[:, K.O_VOLTS].copy(), rows[:, K.O_Q2].copy()

    def finger_position_at(self, t: float, finger: Finger = Finger.MIDDLE) -> float:
        """Unrounded position of a tripod finger at the latest DAQ sample at or before ``t``.

        Needs the DAQ history (``history=True``); before the first sample, the current position.

        Examples
        --------
        >>> rig = Rig("TR"); rig.hand.set_positions({Finger.MIDDLE: 100}); _ = rig.advance(0.5)
        >>> rig.finger_position_at(0.0), rig.finger_position_at(0.5) > 90
        (0.0, True)
        """
        col = K.O_Q0 + hw.TRIPOD.index(Finger(finger))
        for rows in reversed(self._daq_chunks):
            if rows.shape[0] and rows[0, K.O_T] <= t + 1e-12:
                i = int(np.searchsorted(rows[:, K.O_T], t + 1e-12, side="right")) - 1
                return float(rows[i, col])
        return float(self._S[K.S_Q0 + hw.TRIPOD.index(Finger(finger))])

    def last_daq_position(self, finger: Finger = Finger.MIDDLE) -> float:
        """Unrounded position of a tripod finger at the latest DAQ sample so far (NaN if none is kept).

        Examples
        --------
        >>> rig = Rig("TR"); math.isnan(rig.last_daq_position())
        True
        >>> _ = rig.advance(0.01); rig.last_daq_position()
        0.0
        """
        for rows in reversed(self._daq_chunks):
            if rows.shape[0]:
                return float(rows[-1, K.O_Q0 + hw.TRIPOD.index(Finger(finger))])
        return math.nan

    def kernel_arrays(self) -> KernelArrays:
        """The live arrays of the physics and the hand's servo targets, for a compiled loop.

        A loop that advances them with :func:`slipreflex.sim.kernel.step_until`
        hands back what it produced with :meth:`record` and the hand's queue with
        :meth:`SimHand.restore_queue` (see :mod:`slipreflex.sim.closed`).

        Examples
        --------
        >>> a = Rig("TR").kernel_arrays()
        >>> a.S.shape == (K.S_SIZE,), a.targets is a.targets
        (True, True)
        """
        return KernelArrays(S=self._S, C=self._C, P=self._P, keys=self._keys, D=self._D, W=self._W,
                            track=self.track.rho, tac_rates=self._tac_rates, tac_next=self._tac_next,
                            tac_contact=self._tac_contact, targets=self.hand.targets, speeds=self.hand.speeds)

    def record(self, daq_rows: np.ndarray, events: np.ndarray, snapshots: np.ndarray,
               built: tuple[TactileSampler, np.ndarray, np.ndarray] | None = None) -> None:
        """Take what a compiled loop produced on :meth:`kernel_arrays`: DAQ rows (kept as
        history), physics events and tactile snapshots (turned into frames by each sampler,
        except ``built = (sampler, frames, filter state)``: the frames the loop built from
        that sampler's snapshots, see :meth:`TactileSampler.take`).

        Examples
        --------
        >>> rig = Rig("TR"); rig.record(np.zeros((0, K.O_SIZE)), np.zeros((0, 3)), np.zeros((0, K.T_SIZE)))
        >>> rig.daq_history().t.size
        0
        """
        if daq_rows.shape[0] and self.history:
            self._daq_chunks.append(daq_rows)
        if events.shape[0]:
            self._events.append(events)
        self._emit_tactile(snapshots, built)

    def _advance_rows(self, t: float) -> np.ndarray:
        """Advance to ``t``; return the new DAQ rows in the kernel's layout (fast path)."""
        if not math.isfinite(t):
            raise ParameterError(f"t must be finite, got {t!r}")
        dt = self.physics.dt
        n_end = int(math.ceil(t / dt - _ROUND))
        rows: list[np.ndarray] = []
        chunk = int(_CHUNK_S / dt)
        hand = self.hand
        C = self._C
        while True:
            n = int(C[K.C_N])
            if hand.apply_due(n):
                self._S[K.S_TGT0:K.S_TGT0 + 3] = hand.targets
                self._S[K.S_SPD0:K.S_SPD0 + 3] = hand.speeds
            if n >= n_end:
                break
            due = hand.next_due_step()
            nxt = n_end if due is None else due
            # chunks end on a grid of absolute steps: where a run is cut must not depend on where it started
            stop = min(n_end, (n // chunk + 1) * chunk, nxt if nxt > n else n_end)
            rows.append(self._run(stop))
        if not rows:
            return np.zeros((0, K.O_SIZE))
        daq = rows[0] if len(rows) == 1 else np.concatenate(rows)
        if daq.shape[0] and self.history:
            self._daq_chunks.append(daq)
        return daq

    def _run(self, stop: int) -> np.ndarray:
        C = self._C
        span = (stop - int(C[K.C_N])) * self.physics.dt
        if self._samplers:
            tac = np.empty((sum(int(span * s.fs) + 2 for s in self._samplers), K.T_SIZE))
        else:
            tac = self._no_tac
        out: list[np.ndarray] = []
        tacs: list[np.ndarray] = []
        counts = self._counts
        while C[K.C_N] < stop:
            K.step_until(self._S, C, self._P, self._keys, self._D, self._W, self.track.rho,
                         self._tac_rates, self._tac_next, self._tac_contact, stop, self._daq_buf, tac,
                         self._ev_buf, counts)
            nd, nt, ne = int(counts[0]), int(counts[1]), int(counts[2])
            out.append(self._daq_buf[:nd].copy())
            if nt:
                tacs.append(tac[:nt].copy())
            if ne:
                self._events.append(self._ev_buf[:ne].copy())
        if tacs:
            self._emit_tactile(tacs[0] if len(tacs) == 1 else np.concatenate(tacs))
        return out[0] if len(out) == 1 else np.concatenate(out)

    # ------------------------------------------------------------------ tactile
    def _sync_samplers(self) -> None:
        self._tac_rates = np.array([s.fs for s in self._samplers], dtype=float)
        self._tac_next = np.array([s.next_index for s in self._samplers], dtype=np.int64)
        self._tac_contact = np.array([hw.TRIPOD.index(s.finger) for s in self._samplers], dtype=np.int64)

    def _emit_tactile(self, snap: np.ndarray, built: tuple | None = None) -> None:
        for i, s in enumerate(self._samplers):
            rows = snap[snap[:, K.T_ID] == i]
            s.next_index = int(self._tac_next[i])
            if built is not None and s is built[0]:
                s.take(rows[:, K.T_T].copy(), built[1], built[2])
            else:
                s.feed(rows, self.tactile_params)

    def tactile_sampler(self, fs: float, finger: Finger = Finger.INDEX, *, keep: bool = False) -> TactileSampler:
        """Start sampling a finger's 4 x 4 tactile array at ``fs`` Hz from now on.

        Frames fall on the grid ``k / fs`` (from the first one at or after
        the current time). The index finger and the thumb carry arrays.

        Parameters
        ----------
        fs : float
            Sampling rate (Hz), e.g. ``hardware.NMSD_FS`` (260) or ``hardware.SWT_FS`` (380).
        finger : Finger
            INDEX (default) or THUMB.
        keep : bool
            Also keep every frame for :attr:`TactileSampler.history`.

        Returns
        -------
        TactileSampler

        Examples
        --------
        >>> Rig("TR").tactile_sampler(380.0).fs
        380.0
        """
        if not (isinstance(fs, (int, float)) and math.isfinite(fs) and 0 < fs <= 10000):
            raise ParameterError(f"fs must be in (0, 10000] Hz, got {fs!r}")
        finger = Finger(finger)
        if finger not in (Finger.INDEX, Finger.THUMB):
            raise ParameterError(f"finger: only INDEX and THUMB carry tactile arrays, got {finger.name}")
        self._n_samplers_made += 1
        key = K.derive_key(self._keys[2], self._n_samplers_made * 1000 + int(finger))
        s = TactileSampler(self, fs, finger, np.uint64(key), keep)
        self._samplers.append(s)
        self._sync_samplers()
        return s

    def tactile_gain(self, finger: Finger) -> float:
        """Sensitivity of ``finger``'s tactile array (part-to-part spread drawn from the seed).

        Examples
        --------
        >>> g = Rig("TR", seed=1).tactile_gain(Finger.THUMB)
        >>> 0.7 < g < 1.3
        True
        """
        return 1.0 + self.tactile_params.gain_sd * float(K.normal(self._keys[4], int(Finger(finger))))

    def tactile(self, finger: Finger = Finger.INDEX) -> np.ndarray:
        """One tactile frame ``(4, 4)`` (N) of ``finger`` at the current time.

        Examples
        --------
        >>> Rig("TR").tactile().shape
        (4, 4)
        """
        S = self._S
        c = K.S_C0 + hw.TRIPOD.index(Finger(finger)) * K.SC_SIZE
        w = S[c + K.SC_W] if S[c + K.SC_STUCK] == 0.0 else 0.0
        i = hw.TRIPOD.index(Finger(finger))
        events = float(self._C[K.C_MS0 + i]) if i < 2 else 0.0
        snap = np.array([[0, self._oneoff, self.t, S[K.S_NC], S[c + K.SC_FT], S[c + K.SC_S], S[K.S_FALLEN], w,
                          events]])
        self._oneoff += 1
        tp = self.tactile_params
        out = np.empty((1,) + hw.TACTILE_SHAPE)
        K.tactile_frames(snap, np.uint64(K.derive_key(self._keys[3], int(finger))), self.tactile_gain(finger),
                         tp.patch_sigma_taxels,
                         tp.shear_shift_taxels, tp.noise_n, tp.resolution_n, 1.0, 0.0, tp.drift_per_decade,
                         np.full((2,) + hw.TACTILE_SHAPE, np.nan), out)
        return out[0]

    # ------------------------------------------------------------------ grasp & perturbations
    def grasp(self, force: float = hw.CONTACT_FORCE_N, *, speed: float | None = None,
              settle: float | None = None) -> GraspResult:
        """Close the tripod until the index and thumb tactile arrays read ``force``, then hold.

        The fingers close at ``speed`` (units/s, default
        ``HandParams.grasp_speed_units_s``); the index and thumb arrays are
        read at ``HandParams.grasp_poll_fs``; a finger whose array reads at
        least ``force`` (sum of its taxels) gets a STOP command (the middle
        finger stops with the index, as it has no tactile array). After
        ``settle`` seconds the bottle's support is removed, and after
        another ``settle`` seconds the grasp is checked.

        Returns
        -------
        GraspResult
            Where the fingers stopped, the contact force after settling, and whether the
            bottle hangs still once its support is gone.

        Raises
        ------
        ParameterError
            If the fingers close fully without reaching ``force``.

        Examples
        --------
        >>> r = Rig("TR").grasp()
        >>> r.stable
        True
        """
        hp = self.hand_params
        speed = hp.grasp_speed_units_s if speed is None else float(speed)
        settle = hp.settle_s if settle is None else float(settle)
        if not (0 < speed <= hp.speed_units_s):
            raise ParameterError(f"speed must be in (0, {hp.speed_units_s}] units/s, got {speed!r}")
        # the closing phase does not depend on the contacts' friction: kept once per its other inputs
        key = closing_key_of(self, force, speed, settle)
        kept = CLOSINGS.get(key)
        if kept is None:
            t_contact = close(self, force, speed, settle)
            if key is not None:
                CLOSINGS.put(key, closing_of(self, t_contact))
        else:
            t_contact = restore_closing(self, kept)
        self._S[K.S_SUPPORTED] = 0.0
        t_release = self.t
        self._advance_rows(self.t + settle)
        S = self._S
        stable = bool(S[K.S_FALLEN] == 0.0 and S[K.S_STUCK] > 0.0 and abs(S[K.S_V]) < 1e-3)
        pos = self.hand.positions()
        self._grasp = GraspResult(position=pos[hw.SLIP_FINGER], force_n=float(S[K.S_NC]),
                                  positions={f: pos[f] for f in hw.TRIPOD}, contact=True, stable=stable, t=self.t,
                                  t_contact=t_contact, t_release=t_release)
        return self._grasp

    def release_support(self) -> None:
        """Remove the bottle's support without the grasp routine (the bottle hangs in the fingers).

        Examples
        --------
        >>> rig = Rig("TR"); rig.release_support(); _ = rig.advance(0.5)
        >>> rig.fallen
        True
        """
        self._S[K.S_SUPPORTED] = 0.0

    def perturb(self, what: Any, at: float | None = None) -> None:
        """Schedule a load change at ``at`` (s): a :class:`Drop` released, a :class:`Pour` started, or any
        registered load kind's object (:mod:`slipreflex.sim.loads` says how the rig applies each).

        Parameters
        ----------
        what : Drop, Pour or a registered load kind's object
        at : float, optional
            Rig time of the release / start (default: now). Not in the past.

        Examples
        --------
        >>> from slipreflex.sim import Pour
        >>> rig = Rig("TR"); _ = rig.grasp()
        >>> rig.perturb(Pour(rate_l_min=1.0, volume_ml=50), at=rig.t)
        >>> _ = rig.advance(4.0)
        >>> round(rig.load_mass - rig.bottle.mass_kg, 3)
        0.05
        """
        at = self.t if at is None else float(at)
        if not math.isfinite(at) or at < self.t - 1e-12:
            raise ParameterError(f"at must be >= the rig time {self.t:.4f} s, got {at!r}")
        kind = kind_of(what)
        row = kind.layout.check(np.asarray(kind.row(what, at, self), dtype=float))
        if kind.table == "drops":
            self._D = np.vstack([self._D, row])
        else:
            self._W = np.vstack([self._W, row])
        self.perturbations.append((at, what))

    # ------------------------------------------------------------------ truth
    # One slot of the state vector each (the class example reads them).
    displacement = slot(K.S_X, float, "Bottle position below where it was grasped (m), pad shear included.")
    slip = slot(K.S_S, float, "Sliding distance at the contacts (m).")
    velocity = slot(K.S_V, float, "Bottle velocity (m/s, down positive).")
    normal_force = slot(K.S_NC, float, "Normal force per contact (N).")
    load_mass = slot(K.S_MASS, float, "Bottle + water + landed masses (kg).")
    slipping = slot(K.S_STUCK, operator.not_, "True while the contacts slide (or the bottle has fallen).")
    fallen = slot(K.S_FALLEN, bool, "Whether the bottle has slid out of the grasp (see the module notes).")
    tilt = slot(K.S_TH, float, "The bottle's tilt in the grasp (rad; about the axis through the grasp's centre "
                               "and the middle finger's cuff, the thumb's side down positive).")

    @property
    def fall_time(self) -> float | None:
        """When the bottle fell out (s), or None.

        Examples
        --------
        >>> Rig("TR").fall_time is None
        True
        """
        return float(self._S[K.S_TFALL]) if self.fallen else None

    @property
    def solver_stats(self) -> tuple[int, int]:
        """(failed, most iterations) of the implicit friction solves so far (rate-state contacts).

        Examples
        --------
        >>> Rig("TR").solver_stats
        (0, 0)
        """
        return int(self._C[K.C_NFAIL]), int(self._C[K.C_NITER])

    def events(self) -> np.ndarray:
        """All physics events so far: rows (time, kind, displacement).

        Kinds: 1 stick -> slip, 2 slip -> stick, 3 fallen out, 4 dropped mass landed.

        Examples
        --------
        >>> Rig("TR").events().shape
        (0, 3)
        """
        return np.concatenate(self._events) if self._events else np.zeros((0, 3))

    @property
    def onsets(self) -> np.ndarray:
        """Times (s) of every stick -> slip transition.

        Examples
        --------
        >>> Rig("TR").onsets.size
        0
        """
        ev = self.events()
        return ev[ev[:, 1] == K.E_ONSET, 0]

    def slip_events(self, quiet: float = 0.1) -> list[SlipEvent]:
        """Group stick/slip transitions into episodes separated by ``quiet`` seconds of sticking.

        Parameters
        ----------
        quiet : float
            Minimum stuck time (s) that separates two episodes.

        Returns
        -------
        list of SlipEvent

        Examples
        --------
        >>> Rig("TR").slip_events()
        []
        """
        return slip_episodes(self.events(), quiet, self.slipping or self.fallen, self.displacement)

    def daq_history(self, since: float | None = None) -> DaqBlock:
        """Every DAQ sample (and truth) produced since the rig started (empty with ``history=False``),
        or only those at or after ``since`` (s).

        Examples
        --------
        >>> rig = Rig("TR"); _ = rig.advance(0.03)
        >>> rig.daq_history().t.size   # 0, 3, ..., 30 ms
        11
        >>> b = rig.daq_history(since=0.02); b.seq.tolist(), b.t.size
        ([7, 8, 9, 10], 4)
        """
        rows, skip = self.daq_rows(since)
        return DaqBlock.from_rows(rows, skip)

    def daq_rows(self, since: float | None = None) -> tuple[np.ndarray, int]:
        """The rows :meth:`daq_history` is made of, in the kernel's layout (columns ``kernel.O_*``), and the
        sample number of the first: for a reader that needs a few columns (read them, never write them).

        Examples
        --------
        >>> rig = Rig("TR"); _ = rig.advance(0.03)
        >>> rows, first = rig.daq_rows(since=0.02)
        >>> rows[:, K.O_T].size, first
        (4, 7)
        """
        chunks = self._daq_chunks
        skip = 0
        if since is not None:
            first = next((i for i, c in enumerate(chunks) if c[-1, K.O_T] >= since - 1e-12), len(chunks))
            skip = sum(c.shape[0] for c in chunks[:first])
            chunks = chunks[first:]
        rows = (chunks[0] if len(chunks) == 1 else np.concatenate(chunks)) if chunks else np.zeros((0, K.O_SIZE))
        if since is not None:
            i = int(np.searchsorted(rows[:, K.O_T], since - 1e-12, side="left"))
            rows, skip = rows[i:], skip + i
        return rows, skip

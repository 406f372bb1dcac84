"""The closed loop in one compiled function, for reflexes with a compiled step.

:func:`slipreflex.sim.run_closed_loop` runs here when the reflex implements
:class:`slipreflex.core.interfaces.CompiledReflex` (every method built on
:class:`~slipreflex.methods.chain.SlipReflex`, NMSD and SWT-SD). The numba kernels below do what the Python loop in
:mod:`slipreflex.sim.loop` does, in the same order and with the same arithmetic:

* advance the physics (:func:`slipreflex.sim.kernel.step_until`) in the same
  stretches (to the next input time plus the hand's latency), applying each queued
  hand command at its due step exactly as :meth:`SimHand.apply_due` does;
* feed every new input to the reflex's compiled step on the reflex's own state
  vector: a DAQ row's volts with the rounded middle-finger position, or a tactile
  frame (built by :func:`~slipreflex.sim.kernel.tactile_frames` with the
  sampler's key, gain and filter state, which the sampler then takes back) with
  the middle-finger position of the latest DAQ row at or before the frame
  (:meth:`Rig.finger_position_at`'s rule);
* turn every rise of a command into a CLOSE and a STOP per finger group (the
  grip-only rule, :func:`slipreflex.core.grip.Grip.rise` and :func:`slipreflex.core.grip.span`,
  with the groups of :func:`~slipreflex.sim.loop.grip_groups`) and queue each with
  the due step :meth:`SimHand.command` gives it
  (``max(ceil((t + latency) / dt - 1e-9), step now)``).

Afterwards :func:`run_compiled` hands back to the rig and the hand what their
Python objects own (DAQ history, events, tactile snapshots for every open
sampler, the pending commands), so the rig continues as if the Python loop had
run; ``tests/sim/test_closed_loop.py`` checks every trace array bit for bit.

The kernels have one numba signature each (the reflex's step arrives as a
first-class function of a fixed type), so they compile once (about 8 s, then
loaded from the disk cache in about 0.3 s) and a new method does not recompile
the loop. Their cache is stamped with the kernel's files too, whose physics they
compile into themselves (:func:`slipreflex.core._numba_cache.stamped_cache`).
What is left of their cost over the physics alone (about 10 % on a held pour,
``benchmarks/bench_closed_loop.py``) is mostly one
:func:`~slipreflex.sim.kernel.step_until` call per stretch and the hand's queue.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numba import njit, types

from ..core import hardware as hw
from ..core._numba_cache import stamped_cache
from ..core.errors import ParameterError
from ..core.hardware import Finger, HandCommand
from . import kernel as K

__all__ = ["SLIP_STEP", "TACTILE_STEP", "run_compiled", "compilable", "stretch_end"]

#: numba signature of a slip reflex's compiled step: ``step(S, P, volts, position) -> command or NaN``.
SLIP_STEP = types.float64(types.float64[::1], types.float64[::1], types.float64, types.float64)
#: numba signature of a tactile reflex's compiled step: ``step(S, P, frame, position)``, frame 1-D.
TACTILE_STEP = types.float64(types.float64[::1], types.float64[::1], types.float64[::1], types.float64)

_ROUND = 1e-9   # SimHand.command's and Rig._advance_rows' rounding guard
_EPS = 1e-12    # the loop's time comparisons (sim/loop.py)

# cfg: float64 configuration vector
(CF_TEND, CF_LAT, CF_DT, CF_DAQ_T, CF_SPEED, CF_PREPOS, CF_SI, CF_CHUNK, CF_GAIN, CF_SIGMA, CF_SHIFT,
 CF_NOISE, CF_RES, CF_ALPHA, CF_HYST, CF_DRIFT, CF_GSPEED) = range(17)
CF_SIZE = 17
# cnt: int64 fill counters and loop state
(N_DAQ, N_EV, N_TAC, N_CMD, N_QHEAD, N_QLEN, N_COUNT, N_FRAMES, N_POSPTR) = range(9)
N_SIZE = 9
# q_i columns: due step, sequence number, HandCommand, finger group
Q_STEP, Q_COUNT, Q_KIND, Q_GROUP = range(4)
_POS, _CLOSE, _OPEN = int(HandCommand.POSITION), int(HandCommand.CLOSE), int(HandCommand.OPEN)
_STOP = int(HandCommand.STOP)
_FMIN, _FMAX, _PWM = float(hw.FINGER_MIN), float(hw.FINGER_MAX), float(hw.PWM_MAX)
_GROW, _DONE, _BAD_COMMAND = 1, 0, 2



#: the loop kernels compile step_until and tactile_frames (and the hardware constants) into themselves: their cache
#: is stamped with those files too, or an edited physics would run from a stale cache. The reflex's step is not
#: compiled in (a first-class function), so its file is not listed.
_CACHE = stamped_cache(__file__, K.__file__, hw.__file__)

_f1, _i1, _u1 = types.float64[::1], types.int64[::1], types.uint64[::1]
_f2, _i2, _f3 = types.float64[:, ::1], types.int64[:, ::1], types.float64[:, :, ::1]
#: the DAQ rows go to a column-major buffer: the rig keeps it as history and a trace's columns are views of it
_f2c = types.float64[::1, :]
# the arguments every kernel shares: physics, hand, queue, outputs, scratch
_COMMON = (_f1, _f1, _f1, _i1, _f1, _u1, _f2, _f2, _f1, _f1, _i1, _i1,  # RS RP | S C P keys D W track rates next cont
           _f1, _f1, _i2, _f1, _i1, _i1, _f1, _f1, _f1,  # tgt spd q_i q_v masks cmd_g cmd_off g_level g_until
           _f1, _i1, _f2c, _f2, _f2, _f1, _f1, _f2, _f2, _f2, _i1)  # cfg cnt daq ev tac cmd_t cmd_v s_* (scratch)


@njit(cache=_CACHE)
def stretch_end(index, rate, latency, daq_t):
    """Where the loop's next stretch of physics ends, waiting for input ``index`` of a stream at ``rate`` Hz
    (the DAQ's rows: ``rate`` 0, their times ``index * daq_t``; a sampler's frames: ``index / rate``).

    The commands the inputs of a stretch produce are due ``latency`` after the earliest of them, so the
    stretch may run that far. It ends on the last instant there of the stream's grid or the DAQ's, where
    the kernel ends a step anyway: a cut between two of them would split a coarse step of the adaptive
    stepping for nothing. The Python loop (:mod:`slipreflex.sim.loop`) ends its stretches here too.

    Examples
    --------
    >>> round(stretch_end(2, 0.0, 0.010, 0.003), 6)        # DAQ rows at 6, 9, 12, 15 ms: to the one at 15 ms
    0.015
    >>> round(stretch_end(1, 260.0, 0.010, 0.003), 6)      # a 260 Hz frame at 3.85 ms: to the DAQ row at 12 ms
    0.012
    >>> stretch_end(2, 0.0, 0.0, 0.003) == 2 * 0.003       # no latency: the input's own instant
    True
    """
    if rate == 0.0:
        return (index + np.floor(latency / daq_t)) * daq_t
    t = index / rate
    own = (index + np.floor(latency * rate)) / rate
    daq = np.floor((t + latency) / daq_t) * daq_t
    return max(own, daq) if daq <= t + latency else own


@njit(cache=_CACHE, inline="always")
def _apply_due(n, S, tgt, spd, q_i, q_v, masks, cnt, speed):
    """SimHand.apply_due(n) on the array queue, then the rig's copy into S."""
    head = cnt[N_QHEAD]
    end = cnt[N_QLEN]
    if head >= end or q_i[head, Q_STEP] > n:
        return
    while head < end and q_i[head, Q_STEP] <= n:
        kind = q_i[head, Q_KIND]
        mask = masks[q_i[head, Q_GROUP]]
        value = q_v[head]
        for i in range(3):
            if mask & (1 << i):
                if kind == _POS:
                    v = np.rint(value)
                    tgt[i] = min(max(v, _FMIN), _FMAX)
                    spd[i] = speed
                elif kind == _CLOSE or kind == _OPEN:
                    tgt[i] = _FMAX if kind == _CLOSE else _FMIN
                    spd[i] = speed * min(max(value, 0.0), _PWM) / _PWM
                else:
                    tgt[i] = np.rint(S[K.S_Q0 + i])
                    spd[i] = speed
        head += 1
    cnt[N_QHEAD] = head
    for i in range(3):
        S[K.S_TGT0 + i] = tgt[i]
        S[K.S_SPD0 + i] = spd[i]


@njit(cache=_CACHE, inline="always")
def _enqueue(q_i, q_v, cnt, step, kind, group, value):
    """bisect.insort by (due step, sequence number), as SimHand.command queues."""
    count = cnt[N_COUNT]
    cnt[N_COUNT] = count + 1
    pos = cnt[N_QLEN]
    head = cnt[N_QHEAD]
    while pos > head and q_i[pos - 1, Q_STEP] > step:
        for j in range(4):
            q_i[pos, j] = q_i[pos - 1, j]
        q_v[pos] = q_v[pos - 1]
        pos -= 1
    q_i[pos, Q_STEP] = step
    q_i[pos, Q_COUNT] = count
    q_i[pos, Q_KIND] = kind
    q_i[pos, Q_GROUP] = group
    q_v[pos] = value
    cnt[N_QLEN] += 1


@njit(cache=_CACHE, inline="always")
def _due(at, n, cfg):
    """SimHand.command's due step for a command sent at ``at``."""
    step = np.int64(np.ceil((at + cfg[CF_LAT]) / cfg[CF_DT] - _ROUND))
    return n if step < n else step


@njit(cache=_CACHE, inline="always")
def _command(c, ts, n, cfg, q_i, q_v, cnt, cmd_g, cmd_off, g_level, g_until, cmd_t, cmd_v):
    """The loop's grip sender for command ``c`` at ``ts`` (sim/loop.py's ``_grip_sender``: per finger
    group, a rise becomes CLOSE at ``max(ts, until)`` and STOP ``rise / speed`` later) and its record."""
    for g in range(cmd_g.shape[0]):
        want = c + cmd_off[g]
        rise = want - g_level[g] if want > g_level[g] else 0.0
        if rise > 0.0:
            g_level[g] = want
            begin = ts if ts > g_until[g] else g_until[g]
            end = begin + rise / cfg[CF_GSPEED]
            g_until[g] = end
            _enqueue(q_i, q_v, cnt, _due(begin, n, cfg), _CLOSE, cmd_g[g], _PWM)
            _enqueue(q_i, q_v, cnt, _due(end, n, cfg), _STOP, cmd_g[g], 0.0)
    k = cnt[N_CMD]
    cmd_t[k] = ts
    cmd_v[k] = c
    cnt[N_CMD] = k + 1


#: DAQ rows the slip loop checks its outputs' room for at once (each check takes eleven arrays: a reference count each).
_ROOM_ROWS = 8


@njit(cache=_CACHE, inline="always")
def _room(C, D, tac_rates, cfg, cnt, q_i, q_v, daq, ev, tac, cmd_t, n_groups, horizon, fs_in):
    """Whether every output can take what advancing to ``horizon`` may produce (else the caller grows them)."""
    dt = cfg[CF_DT]
    steps = np.ceil(horizon / dt - _ROUND) - C[K.C_N] + 1.0
    span = steps * dt
    inputs = span * fs_in + 2.0
    n_tac = 0.0
    for s in range(tac_rates.shape[0]):
        n_tac += span * tac_rates[s] + 2.0
    head = cnt[N_QHEAD]
    if head > 0 and cnt[N_QLEN] + 2.0 * inputs * n_groups > q_i.shape[0]:
        m = cnt[N_QLEN] - head
        for r in range(m):
            for j in range(4):
                q_i[r, j] = q_i[head + r, j]
            q_v[r] = q_v[head + r]
        cnt[N_QHEAD] = 0
        cnt[N_QLEN] = m
    return (cnt[N_DAQ] + span / cfg[CF_DAQ_T] + 4.0 <= daq.shape[0]
            and cnt[N_EV] + steps * (3.0 + D.shape[0]) + 8.0 <= ev.shape[0]
            and cnt[N_TAC] + n_tac <= tac.shape[0]
            and cnt[N_CMD] + inputs <= cmd_t.shape[0]
            and cnt[N_QLEN] + 2.0 * inputs * n_groups <= q_i.shape[0])


@njit(cache=_CACHE, inline="always")
def _append(out, filled, rows, n):
    """Copy the first ``n`` rows of ``rows`` after the ``filled`` rows of ``out``; the new fill."""
    for r in range(n):
        for j in range(rows.shape[1]):
            out[filled + r, j] = rows[r, j]
    return filled + n


@njit(cache=_CACHE, inline="always")
def _advance(horizon, S, C, P, keys, D, W, track, tac_rates, tac_next, tac_contact, tgt, spd, q_i, q_v,
             masks, cfg, cnt, daq, ev, tac, s_daq, s_ev, s_tac, s_n):
    """Rig._advance_rows(horizon): apply due commands, run the physics to the next due step or the end."""
    dt = cfg[CF_DT]
    n_end = np.int64(np.ceil(horizon / dt - _ROUND))
    chunk = np.int64(cfg[CF_CHUNK])
    while True:
        n = C[K.C_N]
        # (checked here, not only inside: an inlined helper taking arrays costs an atomic reference count per
        # array and call, and most rows have no command due)
        if cnt[N_QHEAD] < cnt[N_QLEN] and q_i[cnt[N_QHEAD], Q_STEP] <= n:
            _apply_due(n, S, tgt, spd, q_i, q_v, masks, cnt, cfg[CF_SPEED])
        if n >= n_end:
            break
        stop = n_end
        if cnt[N_QHEAD] < cnt[N_QLEN]:
            due = q_i[cnt[N_QHEAD], Q_STEP]
            if n < due < stop:
                stop = due
        while C[K.C_N] < stop:
            part = min(stop, (C[K.C_N] // chunk + 1) * chunk)   # an absolute grid, as Rig._advance_rows
            K.step_until(S, C, P, keys, D, W, track, tac_rates, tac_next, tac_contact, part, s_daq, s_tac,
                         s_ev, s_n)
            if s_n[0] > 0:
                cnt[N_DAQ] = _append(daq, cnt[N_DAQ], s_daq, s_n[0])
            if s_n[1] > 0:
                cnt[N_TAC] = _append(tac, cnt[N_TAC], s_tac, s_n[1])
            if s_n[2] > 0:
                cnt[N_EV] = _append(ev, cnt[N_EV], s_ev, s_n[2])


@njit(cache=_CACHE)
def _closed_slip(step, RS, RP, S, C, P, keys, D, W, track, tac_rates, tac_next, tac_contact, tgt, spd, q_i, q_v,
                 masks, cmd_g, cmd_off, g_level, g_until, cfg, cnt, daq, ev, tac, cmd_t, cmd_v, s_daq, s_ev, s_tac,
                 s_n, probe, rec):
    """The slip-sensor closed loop: one compiled step per DAQ row. Returns _DONE, _GROW or _BAD_COMMAND.

    After each step, row k of ``rec`` gets the sample's time and the reflex's state slots
    ``RS[probe]`` (what it computed: spike, threshold, window count; :func:`run_compiled`)."""
    t_end = cfg[CF_TEND]
    dt = cfg[CF_DT]
    daq_t = cfg[CF_DAQ_T]
    chunk = np.int64(cfg[CF_CHUNK])
    roomy = -np.inf   # the outputs have room for everything advancing to this time may produce
    while C[K.C_DAQ] * daq_t <= t_end + _EPS:
        t = C[K.C_N] * dt
        horizon = min(t_end, max(t + dt, stretch_end(C[K.C_DAQ], 0.0, cfg[CF_LAT], daq_t)))
        if np.ceil(horizon / dt - _ROUND) <= C[K.C_N]:
            return _DONE   # no step left before t_end (a zero-length run from t = 0)
        if horizon > roomy:
            # the room for the next _ROOM_ROWS rows at once (each term grows with the horizon, so room for a
            # later one is room for every earlier one, commands and events included)
            ahead = min(t_end, horizon + _ROOM_ROWS * daq_t)
            if not _room(C, D, tac_rates, cfg, cnt, q_i, q_v, daq, ev, tac, cmd_t, cmd_g.shape[0], ahead,
                         1.0 / daq_t):
                return _GROW
            roomy = ahead
        k0 = cnt[N_DAQ]
        # _advance(horizon, ...) written out: the inlined helper takes 24 arrays, an atomic reference count
        # each per row (the tactile loop, at a frame per several rows, keeps the call)
        n_end = np.int64(np.ceil(horizon / dt - _ROUND))
        while True:
            n = C[K.C_N]
            if cnt[N_QHEAD] < cnt[N_QLEN] and q_i[cnt[N_QHEAD], Q_STEP] <= n:
                _apply_due(n, S, tgt, spd, q_i, q_v, masks, cnt, cfg[CF_SPEED])
            if n >= n_end:
                break
            stop = n_end
            if cnt[N_QHEAD] < cnt[N_QLEN]:
                due = q_i[cnt[N_QHEAD], Q_STEP]
                if n < due < stop:
                    stop = due
            while C[K.C_N] < stop:
                part = min(stop, (C[K.C_N] // chunk + 1) * chunk)   # an absolute grid, as Rig._advance_rows
                K.step_until(S, C, P, keys, D, W, track, tac_rates, tac_next, tac_contact, part, s_daq, s_tac,
                             s_ev, s_n)
                if s_n[0] > 0:
                    cnt[N_DAQ] = _append(daq, cnt[N_DAQ], s_daq, s_n[0])
                if s_n[1] > 0:
                    cnt[N_TAC] = _append(tac, cnt[N_TAC], s_tac, s_n[1])
                if s_n[2] > 0:
                    cnt[N_EV] = _append(ev, cnt[N_EV], s_ev, s_n[2])
        n = C[K.C_N]
        for k in range(k0, cnt[N_DAQ]):
            c = step(RS, RP, daq[k, K.O_VOLTS], np.rint(daq[k, K.O_Q2]))
            if rec.shape[1]:
                rec[k, 0] = daq[k, K.O_T]
                for j in range(probe.size):
                    rec[k, j + 1] = RS[probe[j]]
            if c == c:
                if not np.isfinite(c):
                    cmd_v[cnt[N_CMD]] = c
                    return _BAD_COMMAND
                _command(c, daq[k, K.O_T], n, cfg, q_i, q_v, cnt, cmd_g, cmd_off, g_level, g_until, cmd_t, cmd_v)
    return _DONE


@njit(cache=_CACHE)
def _closed_tactile(step, RS, RP, S, C, P, keys, D, W, track, tac_rates, tac_next, tac_contact, tgt, spd, q_i,
                    q_v, masks, cmd_g, cmd_off, g_level, g_until, cfg, cnt, daq, ev, tac, cmd_t, cmd_v, s_daq, s_ev,
                    s_tac, s_n, tkey, tstate, frames3, frames2, probe, rec):
    """The tactile closed loop: one compiled step per frame of sampler ``cfg[CF_SI]`` (``rec`` as
    in :func:`_closed_slip`, one row per frame)."""
    t_end = cfg[CF_TEND]
    dt = cfg[CF_DT]
    si = np.int64(cfg[CF_SI])
    fs = tac_rates[si]
    while tac_next[si] / fs <= t_end + _EPS:
        t = C[K.C_N] * dt
        horizon = min(t_end, max(t + dt, stretch_end(tac_next[si], fs, cfg[CF_LAT], cfg[CF_DAQ_T])))
        if np.ceil(horizon / dt - _ROUND) <= C[K.C_N]:
            return _DONE
        if not (_room(C, D, tac_rates, cfg, cnt, q_i, q_v, daq, ev, tac, cmd_t, cmd_g.shape[0], horizon, fs)
                and cnt[N_FRAMES] + (horizon - t) * fs + 4.0 <= frames2.shape[0]):
            return _GROW
        r0 = cnt[N_TAC]
        _advance(horizon, S, C, P, keys, D, W, track, tac_rates, tac_next, tac_contact, tgt, spd, q_i, q_v,
                 masks, cfg, cnt, daq, ev, tac, s_daq, s_ev, s_tac, s_n)
        n = C[K.C_N]
        r1 = cnt[N_TAC]
        f0 = cnt[N_FRAMES]
        if tac_rates.shape[0] == 1 and r1 > r0:   # the reflex's sampler alone: its frames in one call
            K.tactile_frames(tac[r0:r1], tkey, cfg[CF_GAIN], cfg[CF_SIGMA], cfg[CF_SHIFT], cfg[CF_NOISE],
                             cfg[CF_RES], cfg[CF_ALPHA], cfg[CF_HYST], cfg[CF_DRIFT], tstate, frames3[f0:f0 + r1 - r0])
        for r in range(r0, r1):
            if tac[r, K.T_ID] != si:
                continue
            f = cnt[N_FRAMES]
            if tac_rates.shape[0] > 1:
                K.tactile_frames(tac[r:r + 1], tkey, cfg[CF_GAIN], cfg[CF_SIGMA], cfg[CF_SHIFT], cfg[CF_NOISE],
                                 cfg[CF_RES], cfg[CF_ALPHA], cfg[CF_HYST], cfg[CF_DRIFT], tstate, frames3[f:f + 1])
            cnt[N_FRAMES] = f + 1
            ts = tac[r, K.T_T]
            p = cnt[N_POSPTR]
            while p + 1 < cnt[N_DAQ] and daq[p + 1, K.O_T] <= ts + 1e-12:
                p += 1
            cnt[N_POSPTR] = p
            if p >= 0:
                pos = daq[p, K.O_Q2]
            elif cfg[CF_PREPOS] == cfg[CF_PREPOS]:
                pos = cfg[CF_PREPOS]
            else:
                pos = S[K.S_Q0 + 2]
            c = step(RS, RP, frames2[f], np.rint(pos))
            if rec.shape[1]:
                rec[f, 0] = ts
                for j in range(probe.size):
                    rec[f, j + 1] = RS[probe[j]]
            if c == c:
                if not np.isfinite(c):
                    cmd_v[cnt[N_CMD]] = c
                    return _BAD_COMMAND
                _command(c, ts, n, cfg, q_i, q_v, cnt, cmd_g, cmd_off, g_level, g_until, cmd_t, cmd_v)
    return _DONE


_SIGNATURES = {
    "slip": (types.FunctionType(SLIP_STEP), *_COMMON, _i1, _f2),
    "tactile": (types.FunctionType(TACTILE_STEP), *_COMMON, types.uint64, _f3, _f3, _f2, _i1, _f2),
}


def _kernel(kind: str) -> Any:
    """The loop kernel for ``kind``, compiled (or loaded from the cache) for its one signature.

    Its compilation is then disabled, so every reflex's step is passed as a
    first-class function of that signature: one machine code for every method.
    """
    disp = _READY.get(kind)
    if disp is None:
        disp = _closed_slip if kind == "slip" else _closed_tactile
        if not disp.signatures:
            disp.compile(_SIGNATURES[kind])
            disp.disable_compile()
        _READY[kind] = disp
    return disp


_READY: dict = {}   # kind -> its kernel, compiled


@dataclass
class _Buffers:
    """The kernels' growable outputs (rows filled: the counters in ``cnt``)."""

    daq: np.ndarray
    ev: np.ndarray
    tac: np.ndarray
    cmd_t: np.ndarray
    cmd_v: np.ndarray
    q_i: np.ndarray
    q_v: np.ndarray
    frames: np.ndarray
    rec: np.ndarray

    def grow(self) -> None:
        """Double every buffer (their filled parts kept, in their memory order)."""
        for name, a in vars(self).items():
            b = np.empty((2 * a.shape[0] + 16,) + a.shape[1:], dtype=a.dtype, order="F" if name == "daq" else "C")
            b[:a.shape[0]] = a
            setattr(self, name, b)


def compilable(rig, reflex, fingers: tuple[Finger, ...]) -> bool:
    """Whether the compiled loop can run ``reflex`` on ``rig`` (else the Python loop does).

    It needs a reflex with ``compiled()``, commands for tripod fingers only, no
    queued hand command for a finger outside the tripod, and for a tactile reflex
    that declares ``params.shape``, the rig's 4 x 4 frames.

    Examples
    --------
    >>> from slipreflex.sim import Rig
    >>> from slipreflex.methods.chain import SlipReflex
    >>> compilable(Rig("TR"), SlipReflex(), hw.TRIPOD), compilable(Rig("TR"), object(), hw.TRIPOD)
    (True, False)
    """
    if not callable(getattr(reflex, "compiled", None)):
        return False
    if not all(f in hw.TRIPOD for f in fingers):
        return False
    shape = getattr(getattr(reflex, "params", None), "shape", hw.TACTILE_SHAPE)
    if getattr(reflex, "input_kind", None) == "tactile" and tuple(shape) != hw.TACTILE_SHAPE:
        return False   # frames of another shape: the Python loop reports the mismatch as the reflex does
    pending, _ = rig.hand.queue()
    return all(f in hw.TRIPOD for entry in pending for f in entry[3])


def _typed_step(reflex, kind: str):
    step, RS, RP = reflex.compiled()
    sig = SLIP_STEP if kind == "slip" else TACTILE_STEP
    if not hasattr(step, "compile"):
        raise ParameterError(f"{type(reflex).__name__}.compiled() must return a numba @njit step, got {step!r}")
    if sig.args not in getattr(step, "overloads", {}):
        step.compile(sig.args)
    for name, a in (("S", RS), ("P", RP)):
        if not (isinstance(a, np.ndarray) and a.dtype == np.float64 and a.ndim == 1 and a.flags.c_contiguous):
            raise ParameterError(f"{type(reflex).__name__}.compiled(): {name} must be a 1-D C-contiguous "
                                 f"float64 array")
    return step, RS, RP


def _queue_arrays(rig, groups: list[tuple[Finger, ...]], cap: int):
    """The hand's pending commands as arrays; ``groups`` gains their finger tuples."""
    pending, count = rig.hand.queue()
    q_i = np.zeros((cap + len(pending), 4), dtype=np.int64)
    q_v = np.zeros(cap + len(pending))
    for r, (step, cnt, kind, fingers, value) in enumerate(pending):
        if fingers not in groups:
            groups.append(fingers)
        q_i[r] = (step, cnt, int(kind), groups.index(fingers))
        q_v[r] = value
    return q_i, q_v, len(pending), count


def _cfg(rig, t_end: float, sampler) -> np.ndarray:
    cfg = np.zeros(CF_SIZE)
    cfg[CF_TEND] = t_end
    cfg[CF_LAT] = rig.hand.params.latency_s
    cfg[CF_DT] = rig.physics.dt
    cfg[CF_DAQ_T] = hw.DAQ_PERIOD_S
    cfg[CF_SPEED] = rig.hand.params.speed_units_s
    cfg[CF_PREPOS] = rig.last_daq_position(Finger.MIDDLE)
    cfg[CF_CHUNK] = max(1, int(0.25 / rig.physics.dt))
    cfg[CF_GSPEED] = rig.hand.params.speed_units_s   # sim/loop.py's _grip_sender: the hand's own speed
    if sampler is not None:
        tp = rig.tactile_params
        cfg[CF_SI] = rig.samplers.index(sampler)
        cfg[CF_GAIN] = sampler.gain
        cfg[CF_SIGMA], cfg[CF_SHIFT], cfg[CF_NOISE] = tp.patch_sigma_taxels, tp.shear_shift_taxels, tp.noise_n
        cfg[CF_RES], cfg[CF_HYST], cfg[CF_DRIFT] = tp.resolution_n, tp.hysteresis_n, tp.drift_per_decade
        cfg[CF_ALPHA] = 1.0 - math.exp(-2.0 * math.pi * tp.bandwidth_hz / sampler.fs)
    return cfg


def run_compiled(rig, reflex, t_end: float, split: list[tuple[tuple[Finger, ...], float]],
                 sampler, start: float, record: list | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Run the closed loop to ``t_end`` in the compiled kernels; return (command times, values).

    ``split`` is how a command's rises go to the tripod fingers
    (:func:`~slipreflex.sim.loop.grip_groups`: finger groups and offsets), ``start``
    the level from which they count (:func:`~slipreflex.sim.loop.grip_start`);
    ``sampler`` is the tactile reflex's :class:`TactileSampler` (None for a slip
    reflex). The rig, its hand and samplers are left as the Python loop leaves
    them (before its last open-loop stretch to ``t_end``, which the caller runs).
    With ``record`` (a list) and a reflex with ``probe_slots`` (name -> slot of its
    state), ``record`` gets one array: per input the reflex took, its time and those
    slots after the step (:func:`slipreflex.sim.loop.reflex_log`).
    :func:`~slipreflex.sim.run_closed_loop` calls it; call that instead.

    Examples
    --------
    >>> from slipreflex.sim import Rig
    >>> from slipreflex.methods.chain import SlipReflex
    >>> from slipreflex.sim.loop import grip_groups
    >>> rig = Rig("TR", seed=1); g = rig.grasp()
    >>> split = grip_groups(hw.TRIPOD, None)
    >>> t, c = run_compiled(rig, SlipReflex(p0=g.position), rig.t + 0.2, split, None, g.position)
    >>> t.size, bool((c == g.position).all())    # a command per 16-sample window, no slip
    (4, True)
    """
    kind = "tactile" if sampler is not None else "slip"
    step, RS, RP = _typed_step(reflex, kind)
    groups = [g for g, _ in split]
    A = rig.kernel_arrays()
    span = max(t_end - rig.t, 0.0) + 0.05
    n_in = int(span * (hw.DAQ_FS if sampler is None else sampler.fs)) + 16
    q_i, q_v, q_len, count = _queue_arrays(rig, groups, 8 * len(split) + 64)
    masks = np.array([sum(1 << hw.TRIPOD.index(f) for f in g) for g in groups], dtype=np.int64)
    cmd_g = np.arange(len(split), dtype=np.int64)
    cmd_off = np.array([off for _, off in split], dtype=np.float64)
    g_level = np.full(len(split), float(start))
    g_until = np.array([max((rig.hand.closing_until.get(f, -math.inf) for f in g), default=-math.inf)
                        for g, _ in split], dtype=np.float64)
    n_tac = int(sum(span * fs + 4 for fs in A.tac_rates))
    slots = dict(getattr(reflex, "probe_slots", {}) or {}) if record is not None else {}
    probe = np.array(list(slots.values()), dtype=np.int64)
    n_rec = int(span * hw.DAQ_FS) + 16 if sampler is None else n_in
    buf = _Buffers(daq=np.empty((int(span * hw.DAQ_FS) + 16, K.O_SIZE), order="F"), ev=np.empty((4096, 3)),
                   tac=np.empty((n_tac + 16, K.T_SIZE)), cmd_t=np.empty(n_in), cmd_v=np.empty(n_in),
                   q_i=q_i, q_v=q_v, frames=np.empty((n_in if sampler is not None else 0,) + hw.TACTILE_SHAPE),
                   rec=np.empty((n_rec if slots else 0, len(slots) + 1 if slots else 0)))
    cnt = np.zeros(N_SIZE, dtype=np.int64)
    cnt[N_QLEN], cnt[N_COUNT], cnt[N_POSPTR] = q_len, count, -1
    cfg = _cfg(rig, t_end, sampler)
    chunk_steps = int(cfg[CF_CHUNK])
    s_daq = np.zeros((int(chunk_steps * rig.physics.dt * 2 * hw.DAQ_FS) + 8, K.O_SIZE))
    s_ev = np.zeros((3 * (chunk_steps + 2) + 8 + A.D.shape[0], 3))
    s_tac = np.zeros((sum(int(chunk_steps * rig.physics.dt * fs) + 2 for fs in A.tac_rates) + 1, K.T_SIZE))
    s_n = np.zeros(3, dtype=np.int64)
    tstate = sampler.filter_state.copy() if sampler is not None else None
    key = np.uint64(sampler.key) if sampler is not None else None
    status = _GROW
    try:
        while status == _GROW:
            common = (RS, RP, A.S, A.C, A.P, A.keys, A.D, A.W, A.track, A.tac_rates, A.tac_next, A.tac_contact,
                      A.targets, A.speeds, buf.q_i, buf.q_v, masks, cmd_g, cmd_off, g_level, g_until, cfg, cnt, buf.daq,
                      buf.ev, buf.tac, buf.cmd_t, buf.cmd_v, s_daq, s_ev, s_tac, s_n)
            if sampler is None:
                status = _kernel(kind)(step, *common, probe, buf.rec)
            else:
                status = _kernel(kind)(step, *common, key, tstate, buf.frames,
                                       buf.frames.reshape(buf.frames.shape[0], -1), probe, buf.rec)
            if status == _GROW:
                buf.grow()
    finally:   # also when the reflex's step raised: the rig then stands where the Python loop's would
        _hand_back(rig, buf, cnt, groups, None if sampler is None else (sampler, tstate))
        for (g, _), until in zip(split, g_until.tolist()):
            if until > -math.inf:
                rig.hand.closing_until.update({f: until for f in g})
    nc = int(cnt[N_CMD])
    if slots and record is not None:
        n_fed = int(cnt[N_DAQ] if sampler is None else cnt[N_FRAMES])
        record.append((tuple(slots), buf.rec[:n_fed].copy()))
    if status == _BAD_COMMAND:
        raise ParameterError(f"hand command value must be finite, got {buf.cmd_v[nc]!r}")
    return buf.cmd_t[:nc].copy(), buf.cmd_v[:nc].copy()


def _hand_back(rig, buf: _Buffers, cnt: np.ndarray, groups: list, built) -> None:
    """Give the hand its pending commands and the rig what the kernels produced."""
    head, end = int(cnt[N_QHEAD]), int(cnt[N_QLEN])
    pending = [(int(s), int(c), HandCommand(int(k)), groups[int(g)], float(v))
               for (s, c, k, g), v in zip(buf.q_i[head:end], buf.q_v[head:end])]
    rig.hand.restore_queue(pending, int(cnt[N_COUNT]))
    if built is not None:
        built = (built[0], buf.frames[:cnt[N_FRAMES]], built[1])
    rig.record(buf.daq[:cnt[N_DAQ]], buf.ev[:cnt[N_EV]].copy(), buf.tac[:cnt[N_TAC]], built)   # views: kept

"""Digests of every trace the closed-loop benchmark runs, both kernels: the check that a speed change kept the bits.

For the fixed-step reference and the adaptive kernel, the held pour (closed by a
compiled reflex that never commands and open loop, alone and with a 260 Hz tactile
stream) and the default reproduction's drop and pour for every registered method on
the bottles TR and DK (set up as ``reproduce`` sets them up), prints one line per
trace: a SHA-256 over every recorded column, the commands, the tactile frames, the
onsets, the slip episodes and the rig's final state and counters. Run it on two checkouts and
compare: ``python benchmarks/trace_digest.py > after.txt`` then ``diff before.txt after.txt``
(no output: the same bits). A speed figure lives in ``bench_closed_loop.py``; this
script times nothing.
"""

from __future__ import annotations

import dataclasses
import hashlib

import numpy as np
from bench_closed_loop import Never

from slipreflex import methods
from slipreflex.core import hardware as hw
from slipreflex.reproduce.experiments import ReproduceConfig, calibrate, method_context, trial_seed
from slipreflex.sim import PAPER_POUR, Rig, run_closed_loop, simulate_open_loop
from slipreflex.sim import kernel as K
from slipreflex.sim.variations import trial_rig

_RECORDED_COUNTERS = ("N", "DAQ", "ACC", "NFAIL", "NITER", "SPL", "MS0", "MS1", "STEPS", "RECHECK")


def digest(trace, rig) -> str:
    """A SHA-256 (first 16 hex digits) of everything ``trace`` recorded and the rig's state after it."""
    h = hashlib.sha256()
    frame = trace.to_frame()
    for name in sorted(frame):
        h.update(name.encode())
        h.update(np.ascontiguousarray(np.asarray(frame[name])).tobytes())
    for a in (trace.cmd_t, trace.cmd_value, trace.tactile_t, trace.tactile, trace.onsets):
        h.update(np.ascontiguousarray(np.asarray(a, dtype=float)).tobytes())
    h.update(repr((trace.fallen, trace.fall_time, trace.slip_events)).encode())
    h.update(rig._S.tobytes())
    # the counters that record the run (not the adaptive stepping's caches of its next sample's step)
    h.update(np.array([rig._C[getattr(K, f"C_{name}")] for name in _RECORDED_COUNTERS], dtype=np.int64).tobytes())
    return h.hexdigest()[:16]


def main() -> None:
    config = ReproduceConfig(trials=1)
    thresholds = calibrate(config)
    for stepping in ("fixed", "adaptive"):
        for closed in (True, False):
            for fs in (None, hw.NMSD_FS):
                rig = Rig("TR", seed=1, stepping=stepping)
                g = rig.grasp()
                rig.hand.set_positions({f: g.positions[f] + 40 for f in hw.TRIPOD})
                rig.perturb(PAPER_POUR, at=rig.t + 0.5)
                tr = (run_closed_loop(rig, Never(), 8.0, tactile_fs=fs) if closed
                      else simulate_open_loop(rig, 8.0, tactile_fs=fs))
                print(f"held pour {stepping} {'closed' if closed else 'open'} tactile={fs} {digest(tr, rig)}")
        for method in methods.names():
            spec = methods.get(method)
            for experiment in ("drop", "pour"):
                for bottle in ("TR", "DK"):
                    seed = trial_seed(config.seed, experiment, bottle, 0)
                    rig = trial_rig(bottle, seed, spread=None, rig_kwargs={"stepping": stepping})
                    g = rig.grasp(config.grasp_force_n)
                    reflex = spec.build(float(round(g.positions[hw.SLIP_FINGER])),
                                        dataclasses.replace(method_context(config, thresholds), method=spec.name))
                    rig.perturb(config.pour if experiment == "pour" else config.drop, at=rig.t + config.rest_s)
                    tr = run_closed_loop(rig, reflex, config.duration(experiment))
                    print(f"trial {stepping} {method} {experiment} {bottle} {digest(tr, rig)}")


if __name__ == "__main__":
    main()

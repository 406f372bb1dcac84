"""How the board's fixed-point chain differs from the float chain on the reproduction's signals.

Two comparisons, both over the trial grid of ``slipreflex reproduce`` (same master seed,
same trial seeds, so trial k of a bottle and experiment is the same rig for every method):

1. Same input (open loop): for every drop and pour trial, the slip-sensor volts the
   float DATH (and fixed) chain saw in its closed-loop run are fed again, offline, to the
   float chain (``run_chain`` at the DAQ's 333.33 Hz) and to the board's twin
   (``slipreflex.methods.board.run_board_chain`` on the ADC counts those volts are). Reported:
   samples whose spike differs, total spikes, windows whose command differs, and the
   first command increase after the perturbation (time difference, board - float).
2. Closed loop: ``reproduce`` with the methods dath, dath-board, fixed and fixed-board;
   per trial and slip event the response and total times of the board chain minus the
   float chain's, and the success of both.

Run: python benchmarks/board_vs_float.py [--trials N] [--jobs J]   (docs/firmware.md
quotes its output; deterministic: the same numbers on every machine).
"""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np


def _open_loop_trial(cell, config, dath: bool):
    """The volts a float chain saw in its closed-loop trial, and the perturbation time."""
    from slipreflex import methods
    from slipreflex.core import hardware as hw
    from slipreflex.reproduce.experiments import method_context
    from slipreflex.sim import Rig, run_closed_loop

    rig = Rig(cell.bottle, seed=cell.seed)
    grasp = rig.grasp()
    p0 = float(round(grasp.positions[hw.SLIP_FINGER]))
    reflex = methods.make("dath" if dath else "fixed", p0=p0, context=method_context(config, {}))
    t_pert = rig.t + config.rest_s
    rig.perturb(config.pour if cell.experiment == "pour" else config.drop, at=t_pert)
    tr = run_closed_loop(rig, reflex, config.duration(cell.experiment))
    return tr.t, tr.volts, p0, t_pert


def _first_rise_ms(t_end: np.ndarray, commands: np.ndarray, p0: float, t_pert: float) -> float:
    after = (t_end >= t_pert) & (commands > p0)
    return float((t_end[after][0] - t_pert) * 1e3) if after.any() else math.nan


def open_loop(config) -> dict[str, dict[str, float]]:
    """Comparison 1 for DATH and fixed: totals over the grid."""
    from slipreflex import run_chain
    from slipreflex.core import hardware as hw
    from slipreflex.methods import board
    from slipreflex.reproduce.experiments import Cell, trial_seed

    out = {}
    for dath in (True, False):
        acc = dict(trials=0, samples=0, spike_diff=0, spikes_float=0, spikes_board=0, windows=0,
                   command_diff=0, rise_same=0, rise_both=0, rise_only_one=0)
        rise_d = []
        for exp in config.experiments:
            for bottle in config.bottles:
                for k in range(config.trials):
                    cell = Cell(exp, bottle, "dath" if dath else "fixed", k,
                                trial_seed(config.seed, exp, bottle, k))
                    t, volts, p0, t_pert = _open_loop_trial(cell, config, dath)
                    f = run_chain(volts, fs=hw.DAQ_FS, dath=dath, p0=p0)
                    b = board.run_board_chain([board.adc_counts(v) for v in volts.tolist()],
                                              dath=dath, p0=int(p0))
                    acc["trials"] += 1
                    acc["samples"] += volts.size
                    acc["spike_diff"] += int(np.sum(f.events != b.events))
                    acc["spikes_float"] += int(f.events.sum())
                    acc["spikes_board"] += int(b.events.sum())
                    acc["windows"] += f.commands.size
                    acc["command_diff"] += int(np.sum(f.commands != b.commands))
                    t_end = t[f.window_end_index()]
                    rf = _first_rise_ms(t_end, f.commands, p0, t_pert)
                    rb = _first_rise_ms(t_end, b.commands.astype(float), p0, t_pert)
                    if math.isnan(rf) and math.isnan(rb):
                        continue
                    if math.isnan(rf) or math.isnan(rb):
                        acc["rise_only_one"] += 1
                        continue
                    acc["rise_both"] += 1
                    acc["rise_same"] += int(rf == rb)
                    rise_d.append(rb - rf)
        acc["rise_diff_ms_max"] = float(np.max(np.abs(rise_d))) if rise_d else 0.0
        acc["rise_diff_ms_mean"] = float(np.mean(rise_d)) if rise_d else 0.0
        out["dath" if dath else "fixed"] = acc
    return out


def closed_loop(config, jobs: int) -> dict[str, dict[str, float]]:
    """Comparison 2: per method pair, paired differences of response and total times."""
    import dataclasses

    from slipreflex.reproduce.experiments import run_reproduce

    cfg = dataclasses.replace(config, methods=("dath", "dath-board", "fixed", "fixed-board"))
    rows = run_reproduce(cfg, jobs=jobs, progress=False, plots=False).rows
    key = {(r["experiment"], r["bottle"], int(r["trial"]), int(r["event"]), r["method"]): r for r in rows}
    out = {}
    for base in ("dath", "fixed"):
        d_resp, d_total, same_resp, pairs, succ_f, succ_b, unmatched = [], [], 0, 0, 0, 0, 0
        for (e, b, k, ev, m), rf in key.items():
            if m != base:
                continue
            rb = key.get((e, b, k, ev, f"{base}-board"))
            if rb is None:
                unmatched += 1
                continue
            pairs += 1
            succ_f += bool(rf["success"])
            succ_b += bool(rb["success"])
            for name, lst in (("response_ms", d_resp), ("total_ms", d_total)):
                x, y = rf[name], rb[name]
                if x is not None and y is not None and np.isfinite(x) and np.isfinite(y):
                    lst.append(y - x)
            x, y = rf["response_ms"], rb["response_ms"]
            if x == y or (x is not None and y is not None and np.isnan(x) and np.isnan(y)):
                same_resp += 1      # equal, or neither responded
        unmatched += sum(1 for (e, b, k, ev, m) in key if m == f"{base}-board"
                         and (e, b, k, ev, base) not in key)
        out[base] = dict(pairs=pairs, unmatched=unmatched, same_response=same_resp,
                         response_diff_mean=float(np.mean(d_resp)) if d_resp else math.nan,
                         response_diff_maxabs=float(np.max(np.abs(d_resp))) if d_resp else math.nan,
                         total_diff_mean=float(np.mean(d_total)) if d_total else math.nan,
                         total_diff_maxabs=float(np.max(np.abs(d_total))) if d_total else math.nan,
                         success_float=succ_f, success_board=succ_b)
    return out


def main() -> int:
    from slipreflex.reproduce.experiments import ReproduceConfig

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=10, help="trials per bottle and experiment (10)")
    ap.add_argument("--jobs", type=int, default=1, help="worker processes for the closed loop (1)")
    args = ap.parse_args()
    config = ReproduceConfig(trials=args.trials, methods=("dath",))
    print(f"grid: {args.trials} trials x bottles {','.join(config.bottles)} x "
          f"{','.join(config.experiments)}, master seed {config.seed}")
    print("\n1. same input (the volts each float chain saw in closed loop), offline:")
    for m, a in open_loop(config).items():
        print(f"  {m:5s}: {a['trials']} trials, {a['samples']} samples: spike differs on "
              f"{a['spike_diff']} samples ({100 * a['spike_diff'] / a['samples']:.3f} %); spikes float "
              f"{a['spikes_float']}, board {a['spikes_board']}; command differs in "
              f"{a['command_diff']} of {a['windows']} windows")
        print(f"         first command rise after the perturbation: same time in {a['rise_same']} of "
              f"{a['rise_both']} trials where both rose (mean board - float "
              f"{a['rise_diff_ms_mean']:+.1f} ms, max |diff| {a['rise_diff_ms_max']:.1f} ms); "
              f"only one rose in {a['rise_only_one']}")
    print("\n2. closed loop (reproduce: dath vs dath-board, fixed vs fixed-board, paired by trial):")
    for m, c in closed_loop(config, args.jobs).items():
        print(f"  {m:5s}: {c['pairs']} slip events paired ({c['unmatched']} without a partner); "
              f"identical response time in {c['same_response']}; board - float response "
              f"{c['response_diff_mean']:+.1f} ms mean, max |diff| {c['response_diff_maxabs']:.1f} ms; "
              f"total {c['total_diff_mean']:+.1f} ms mean, max |diff| {c['total_diff_maxabs']:.1f} ms; "
              f"success float {c['success_float']}, board {c['success_board']} of {c['pairs']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""``slipreflex benchmark``: every registered detector on a folder of recorded, labelled trials.

Examples (shell)::

    slipreflex benchmark                               # the shipped set (imanlab-slip)
    slipreflex benchmark my_trials/ --methods dath nmsd --rates data --out out/mine
    slipreflex benchmark --vs-sim                      # also the simulated array held against the data
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from ..baselines.calibration import REST_K
from ..benchmark import BenchmarkConfig, read_folder, shipped_dataset
from ..benchmark.report import format_table, plot_trial_runs, summarize, write_runs, write_summary
from ..benchmark.run import RATES, REDUCTIONS, plan, run_trial
from ..benchmark.vs_sim import compare, format_comparison, plot_comparison, write_comparison
from ..paths import output_dir

NAME = "benchmark"
HELP = "score every detection method on recorded labelled slip trials (default: the shipped real data set)"
ORDER = 35


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of ``slipreflex benchmark``."""

    p.add_argument("folder", type=Path, nargs="?", default=None,
                   help="folder of trial CSV files (docs/benchmark.md; default: the shipped imanlab-slip set)")
    p.add_argument("--methods", nargs="+", default=None,
                   help="registered methods to run, space- or comma-separated, any case (default: every "
                        "one that applies to the data)")
    p.add_argument("--rates", nargs="+", default=list(RATES), choices=RATES,
                   help="run each method at the data's rate, resampled to its own, or both (default: both)")
    p.add_argument("--reduction", choices=REDUCTIONS, default="z-sum",
                   help="the chain methods' channel from a tactile layout (default z-sum: normal force "
                        "summed over every taxel)")
    p.add_argument("--calibration-s", type=float, default=1.0,
                   help="span at the start of each trial whose data set the thresholds; must end before "
                        "the labelled onset (default 1.0 s)")
    p.add_argument("--rest-k", type=float, default=REST_K,
                   help=f"standard deviations of each method's statistic in that span (default {REST_K:g})")
    p.add_argument("--no-figures", action="store_true", help="write the tables only")
    p.add_argument("--vs-sim", action="store_true",
                   help="also hold the simulated tactile array against the data (vs_sim.csv, vs_sim.png)")
    p.add_argument("--seed", type=int, default=1, help="seed of the simulated trials of --vs-sim (default 1)")
    p.add_argument("--out", type=Path, default=Path("out/benchmark"), help="output folder (default out/benchmark)")


def run(args: argparse.Namespace) -> int:
    """Read and check every trial, run the methods, write and print the results."""
    names = [m for item in args.methods or () for m in item.split(",") if m.strip()]
    cfg = BenchmarkConfig(methods=tuple(names) if names else None,
                          calibration_s=args.calibration_s, rest_k=args.rest_k,
                          reduction=args.reduction, rates=tuple(dict.fromkeys(args.rates)))
    folder = args.folder if args.folder is not None else shipped_dataset()
    trials = read_folder(folder)
    names, skipped = plan(trials, cfg)
    out = output_dir(args.out, "--out")

    fs = [tr.fs for tr in trials]
    steps = np.concatenate([np.diff(tr.t) for tr in trials]) * 1e3
    print(f"benchmark: {len(trials)} trial(s) in {folder} ({sum(tr.slips for tr in trials)} with labelled slip), "
          f"{min(fs):.1f}-{max(fs):.1f} Hz (time steps {steps.min():.0f}-{steps.max():.0f} ms), "
          f"{len(names)} method(s) at rate(s) {', '.join(cfg.rates)}")
    for s in skipped:
        print(f"  not run: {s.method}: {s.reason}")
    runs = []
    try:
        for tr in trials:
            got = run_trial(tr, cfg, names)
            runs.extend(got)
            if not args.no_figures:
                plot_trial_runs(tr, got, out / f"{tr.name}.png", calibration_s=cfg.calibration_s,
                                reduction=cfg.reduction)
    except KeyboardInterrupt:
        if runs:
            write_runs(runs, out / "benchmark.csv")
        print(f"benchmark: interrupted; {len({r.trial for r in runs})} finished trial(s) kept in {out}")
        return 130
    write_runs(runs, out / "benchmark.csv")
    summary = summarize(runs)
    write_summary(summary, out / "summary.csv")
    print(format_table(summary))
    print(f"wrote {out / 'benchmark.csv'}, {out / 'summary.csv'}"
          + ("" if args.no_figures else f" and {len(trials)} figure(s)"))
    if args.vs_sim:

        cmp = compare(trials, calibration_s=cfg.calibration_s, seed=args.seed)
        write_comparison(cmp, out / "vs_sim.csv")
        plot_comparison(cmp, out / "vs_sim.png")
        print(format_comparison(cmp))
        print(f"wrote {out / 'vs_sim.csv'} and {out / 'vs_sim.png'}")
    return 0

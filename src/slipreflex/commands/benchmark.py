"""``slipreflex benchmark``: every detector on a folder of recorded, labelled trials.

By default each method's threshold is chosen on training trials for a target false-alarm
rate and scored on held-out ones (docs/benchmark.md, "Protocol"); ``--protocol rest-k`` runs
the earlier per-trial rule (k sd of the first second of every trial).

Examples (shell)::

    slipreflex benchmark                               # the shipped set (imanlab-slip)
    slipreflex benchmark --fa-per-min 5 --test-trials 2022-02-22-15-15-00
    slipreflex benchmark optical/ --threshold fixed=0.008 dath=0.008
    slipreflex benchmark my_trials/ --channels a b c --aggregate magnitude --out out/mine
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from .. import methods as registry
from ..benchmark import BenchmarkConfig, read_folder, read_trial, shipped_dataset
from ..benchmark.evaluate import evaluate, method_names, rest_thresholds, select_channels
from ..benchmark.optable import format_points, plot_curves, write_points
from ..benchmark.protocol import ProtocolConfig
from ..benchmark.report import format_table, plot_trial_runs, summarize, write_runs, write_summary
from ..benchmark.run import RATES, REDUCTIONS, plan, run_trial
from ..benchmark.sweep import AGGREGATIONS, GRID_POINTS
from ..benchmark.vs_sim import compare, format_comparison, plot_comparison, write_comparison
from ..core.errors import ParameterError
from ..core.validation import within
from ..files.paths import OutputSet
from ..files.progress import format_duration
from ..methods.baselines.calibration import REST_K

NAME = "benchmark"
HELP = "score every detection method on recorded labelled slip trials (default: the shipped real data set)"
ORDER = 35
PROTOCOLS = ("operating", "rest-k")
#: For the estimate before the work: seconds per run of one method on one trial at one threshold
#: (the call's own cost, 1-2.5 ms measured on the shipped set, rounded up), per sample of it
#: (SWT-SD's, the dearest: 4.4 us), and per trial figure of ``--protocol rest-k``.
_RUN_S, _SAMPLE_S, _FIGURE_S = 3e-3, 6e-6, 0.5
#: An estimate above this is printed before the work starts (s).
_SAY_ESTIMATE_S = 5.0


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of ``slipreflex benchmark``."""

    p.add_argument("folder", type=Path, nargs="?", default=None,
                   help="folder of trial CSV files (docs/benchmark.md; default: the shipped imanlab-slip set)")
    p.add_argument("--protocol", choices=PROTOCOLS, default="operating",
                   help="operating (default): thresholds chosen on training trials for --fa-per-min, scored on "
                        "held-out trials; rest-k: k sd of each trial's first --calibration-s (the earlier rule)")
    p.add_argument("--methods", nargs="+", default=None,
                   help="methods to run, space- or comma-separated (registered ones, energy, learned; default: "
                        "every one that applies to the data)")
    p.add_argument("--fa-per-min", type=float, default=10.0,
                   help="target false alarms per minute on the training trials (default 10: docs/benchmark.md)")
    p.add_argument("--refractory-s", type=float, default=0.25,
                   help="detections closer than this are one alarm episode (default 0.25 s)")
    p.add_argument("--tolerance-s", type=float, default=0.1,
                   help="the label may lead or lag the sensor by this much (default 0.1 s)")
    p.add_argument("--test-trials", nargs="+", default=None,
                   help="trial names held out as the test set (default: leave-one-trial-out)")
    p.add_argument("--threshold", nargs="+", default=None, metavar="METHOD=VALUE",
                   help="a method's threshold in the data's units, used in every fold (the paper's 8 mV: fixed=0.008)")
    p.add_argument("--rest", type=Path, default=None,
                   help="a separate rest recording (same format): thresholds of --rest-k sd of each method's "
                        "statistic on it")
    p.add_argument("--channels", nargs="+", default=None,
                   help="channel columns to read (the layout is then ignored; default: every channel)")
    p.add_argument("--aggregate", choices=AGGREGATIONS, default="any",
                   help="without a layout, what a chain method reads: any (each channel, an alarm on any counts; "
                        "default), sum or magnitude of the channels' changes")
    p.add_argument("--bootstrap", type=int, default=1000, help="bootstrap resamples for the curve areas (default 1000)")
    p.add_argument("--rates", nargs="+", default=None, choices=RATES,
                   help="run each method at the data's rate and/or resampled to its own (default: data for "
                        "operating, both for rest-k)")
    p.add_argument("--reduction", choices=REDUCTIONS, default="z-sum",
                   help="the chain methods' channel from a tactile layout (default z-sum: normal force "
                        "summed over every taxel)")
    p.add_argument("--calibration-s", type=float, default=1.0,
                   help="rest-k: span at the start of each trial whose data set the thresholds (default 1.0 s)")
    p.add_argument("--rest-k", type=float, default=REST_K,
                   help=f"rest-k and --rest: standard deviations of each method's statistic (default {REST_K:g})")
    p.add_argument("--no-figures", action="store_true", help="write the tables only")
    p.add_argument("--vs-sim", action="store_true",
                   help="also hold the simulated tactile array against the data (vs_sim.csv, vs_sim.png)")
    p.add_argument("--seed", type=int, default=1,
                   help="seed of the bootstrap, the learned baseline and --vs-sim (default 1)")
    p.add_argument("--out", type=Path, default=Path("out/benchmark"), help="output folder (default out/benchmark)")


def _thresholds(items) -> dict[str, float]:
    out = {}
    for item in items or ():
        name, sep, value = item.partition("=")
        try:
            v = float(value)
        except ValueError:
            v = float("nan")
        if not sep or not np.isfinite(v) or v <= 0:
            raise ParameterError(f"--threshold: expected METHOD=VALUE with a positive number, got {item!r}")
        key = name.strip().lower()
        out[key if key in ("energy", "learned") else registry.canonical(key)] = v
    return out


def _split(items) -> list[str]:
    return [m.strip() for item in items or () for m in item.split(",") if m.strip()]


def run(args: argparse.Namespace) -> int:
    """Check the options and every trial, then run the chosen protocol into a new output set."""
    within("calibration_s", args.calibration_s, "--calibration-s")
    within("rest_k", args.rest_k, "--rest-k")
    folder = args.folder if args.folder is not None else shipped_dataset()
    if args.protocol == "rest-k":
        return _rest_k(args, folder)
    protocol = ProtocolConfig(fa_per_min=args.fa_per_min, refractory_s=args.refractory_s,
                              tolerance_s=args.tolerance_s, test=tuple(args.test_trials) if args.test_trials else None,
                              bootstrap=args.bootstrap, seed=args.seed)
    fixed = _thresholds(args.threshold)
    names = _split(args.methods)
    names = [n.lower() if n.lower() in ("energy", "learned") else registry.canonical(n) for n in names]
    trials = select_channels(read_folder(folder), args.channels)
    run_names, _ = method_names(trials, names or None)
    rates = tuple(dict.fromkeys(args.rates or ("data",)))
    if args.rest is not None:
        rest = select_channels([read_trial(args.rest)], args.channels)[0]
        fixed = {**rest_thresholds(rest, run_names, rates[0], args.rest_k, reduction=args.reduction,
                                   aggregate=args.aggregate), **fixed}
    outputs = OutputSet(args.out, NAME)
    wanted = ["operating_points.csv"] + ([] if args.no_figures else ["curves.png"])
    wanted += ["vs_sim.csv", "vs_sim.png"] if args.vs_sim else []
    outputs.check(wanted)
    _estimate(trials, len(run_names), rates, GRID_POINTS, figures=False)
    staged = outputs.stage()
    try:
        ev = evaluate(trials, methods=run_names, rates=rates, reduction=args.reduction, aggregate=args.aggregate,
                      protocol=protocol, thresholds=fixed, channels_chosen=bool(args.channels))
        print(f"benchmark: {len(trials)} trial(s) in {folder} ({ev.positives} slip), "
              f"{ev.rates_hz[0]:.1f}-{ev.rates_hz[1]:.1f} Hz")
        if args.rest is not None:
            print(f"thresholds given below: {args.rest_k:g} sd of each method's statistic on the rest recording "
                  f"{args.rest}, except those given by --threshold")
        print(format_points(ev))
        write_points(ev, staged / "operating_points.csv")
        if ev.interrupted:
            done = outputs.commit(staged)
            print(f"benchmark: interrupted; {len(ev.points)} finished method(s) kept in {outputs.folder} "
                  f"({', '.join(done)})")
            return 130
        if not args.no_figures:
            plot_curves(ev, staged / "curves.png", title=Path(folder).name)
        if args.vs_sim:
            _vs_sim(trials, staged, args.seed)
    except BaseException:
        outputs.abort(staged)
        raise
    done = outputs.commit(staged)
    print(f"wrote {', '.join(done)} in {outputs.folder}")
    return 0


def _estimate(trials, methods: int, rates, thresholds: int, *, figures: bool) -> None:
    """Print how long the work will take, when that is more than a few seconds (before it starts)."""
    samples = sum(len(tr.t) for tr in trials)
    runs = len(trials) * methods * len(rates) * thresholds
    factor = sum(1.0 if r == "data" else 6.0 for r in rates)         # resampled: about 6 times the samples
    est = runs * _RUN_S + samples * methods * thresholds * factor * _SAMPLE_S + figures * len(trials) * _FIGURE_S
    if est > _SAY_ESTIMATE_S:
        print(f"benchmark: {len(trials)} trial(s), {samples} samples, {methods} method(s): about "
              f"{format_duration(est)} (fewer --methods or trials shorten it)", file=sys.stderr, flush=True)


def _vs_sim(trials, out: Path, seed: int) -> None:
    cmp = compare(trials, seed=seed)
    write_comparison(cmp, out / "vs_sim.csv")
    plot_comparison(cmp, out / "vs_sim.png")
    print(format_comparison(cmp))


def _rest_k(args: argparse.Namespace, folder: Path) -> int:
    """The earlier rule: k sd of each trial's first span; one table row per method and rate."""
    names = _split(args.methods)
    cfg = BenchmarkConfig(methods=tuple(names) if names else None,
                          calibration_s=args.calibration_s, rest_k=args.rest_k,
                          reduction=args.reduction, rates=tuple(dict.fromkeys(args.rates or RATES)))
    trials = read_folder(folder)
    names, skipped = plan(trials, cfg)
    outputs = OutputSet(args.out, NAME)
    wanted = ["benchmark.csv", "summary.csv"] + ([] if args.no_figures else [f"{tr.name}.png" for tr in trials])
    outputs.check(wanted + (["vs_sim.csv", "vs_sim.png"] if args.vs_sim else []))
    _estimate(trials, len(names), cfg.rates, 1, figures=not args.no_figures)
    fs = [tr.fs for tr in trials]
    print(f"benchmark: {len(trials)} trial(s) in {folder} ({sum(tr.slips for tr in trials)} with labelled slip), "
          f"{min(fs):.1f}-{max(fs):.1f} Hz, {len(names)} method(s) at rate(s) {', '.join(cfg.rates)}, "
          f"thresholds {cfg.rest_k:g} sd of each trial's first {cfg.calibration_s:g} s")
    for s in skipped:
        print(f"  not run: {s.method}: {s.reason}")
    staged = outputs.stage()
    runs = []
    try:
        for tr in trials:
            got = run_trial(tr, cfg, names)
            runs.extend(got)
            if not args.no_figures:
                plot_trial_runs(tr, got, staged / f"{tr.name}.png", calibration_s=cfg.calibration_s,
                                reduction=cfg.reduction)
    except KeyboardInterrupt:
        if runs:
            write_runs(runs, staged / "benchmark.csv")
            outputs.commit(staged)
        else:
            outputs.abort(staged)
        print(f"benchmark: interrupted; {len({r.trial for r in runs})} finished trial(s) kept in {outputs.folder}")
        return 130
    except BaseException:
        outputs.abort(staged)
        raise
    write_runs(runs, staged / "benchmark.csv")
    summary = summarize(runs)
    write_summary(summary, staged / "summary.csv")
    print(format_table(summary))
    if args.vs_sim:
        _vs_sim(trials, staged, args.seed)
    done = outputs.commit(staged)
    print(f"wrote {', '.join(done)} in {outputs.folder}")
    return 0

"""What each physics term, switched on alone, lets the tactile statistics and the IMU see in an open-loop pour
and drop.

For the paper's pour and 10 g drop on TR and TX (nominal plant, seed 0, no reflex), the plant runs with every
term of the physics that the verdicts hinge on at its "absent" value (the base), then with one term at its
nominal value, then with all of them. Per run it prints, from the perturbation to fall-out (or 3 s after a drop):

* NMSD: the largest ``|s_k|`` over its threshold (``baselines.rest_threshold``, 5 sd of the same rig's statistic
  at rest, 260 Hz frames of the index finger) and how many detections it makes;
* SWT-SD: the largest ``|c_k|`` over its threshold (380 Hz) and how many samples its ON signal is on;
* IMU: the largest deviation of the accelerometer's y axis (along the bottle), and of its x axis (sideways: the
  slosh, the motors and the tilt), from its rest mean, in sd of its rest noise (5 is the noise-floor rule the
  tactile thresholds use), from the perturbation to 0.1 s after the first slip (so that the run-away and
  fall-out do not dominate);
* when the bottle first slips and whether it falls.

The terms and their "absent" values are :mod:`slipreflex.sim.terms`' table (its ``VERDICT_SWITCHES``).
Terms: ``grip`` (the bounded grip: wall softening and the motor's torque-speed line), ``roll`` (the fingertip's
roll and the gap's opening), ``events`` (the pads' micro-slip events), ``incipient`` (the Cattaneo-Mindlin
redistribution of incipient slip), ``motor`` (the digits' motor vibration; in an open loop the digits move only
in the grasp, before the rest recording), ``shoulder`` (the bottle's shoulder taper), ``tilt`` (the bottle's tilt
in the grasp, rocked by a drop landing off the axis; nothing tilts it in a pour). A figure
(``--figure PATH``) shows the index array's NMSD and SWT-SD ratios
over time for the base and each term, pour and drop on TR.

Run: ``python -m scripts.docs.physics_terms [--figure physics_terms.png] [--bottles TR,TX]``.
"""

from __future__ import annotations

import argparse

import numpy as np

from slipreflex.core import hardware as hw
from slipreflex.methods.baselines import rest_threshold
from slipreflex.methods.baselines.nmsd import nmsd_detections, nmsd_statistic
from slipreflex.methods.baselines.swt import swt_on, swt_statistic
from slipreflex.sim import PAPER_DROP, PAPER_POUR
from slipreflex.sim.terms import VERDICT_SWITCHES, absent_values
from slipreflex.sim.uncertain import plant_from_values

REST_S = 4.0


def plants() -> dict[str, dict[str, float]]:
    """Uncertain-constant values per run (:mod:`slipreflex.sim.terms`): the base (every term absent), each
    term alone, all terms (the nominal plant)."""
    base = absent_values()
    out: dict[str, dict[str, float]] = {"base": base}
    for name in VERDICT_SWITCHES:
        on = absent_values(name)
        out[name] = {k: v for k, v in base.items() if k not in on}
    out["all"] = {}
    return out


def run(bottle: str, what: str, values: dict[str, float], seed: int = 0) -> dict:
    rig = plant_from_values(values).rig(bottle, seed=seed)
    rig.grasp()
    sn = rig.tactile_sampler(hw.NMSD_FS, keep=True)
    ss = rig.tactile_sampler(hw.SWT_FS, keep=True)
    t_rest = rig.t
    t_pert = t_rest + REST_S
    pert = PAPER_POUR if what == "pour" else PAPER_DROP
    rig.perturb(pert, at=t_pert)
    rig.advance_block(t_pert + (PAPER_POUR.duration_s + 2.0 if what == "pour" else 3.0))
    end = rig.fall_time if rig.fallen else rig.t
    out = {"fallen": rig.fallen, "onset": (rig.onsets[0] - t_pert) if rig.onsets.size else np.nan}
    for name, s, fs, stat in (("nmsd", sn, hw.NMSD_FS, lambda f: nmsd_statistic(f, hw.NMSD_FS)),
                              ("swt", ss, hw.SWT_FS, swt_statistic)):
        t, f = s.history
        rest = (t > t_rest + 0.5) & (t < t_pert)
        thr = rest_threshold(f[rest], name, fs=fs)
        act = (t >= t_pert) & (t < end)
        st = np.abs(stat(f))
        out[name + "_ratio"] = float(st[act].max() / thr)
        out[name + "_t"] = t
        out[name + "_trace"] = st.reshape(len(t), -1).max(axis=1) / thr
        fa = f[act]
        if name == "nmsd":
            out["nmsd_n"] = int(nmsd_detections(fa, hw.NMSD_FS, threshold=thr).sum())
        else:
            out["swt_on"] = int(swt_on(fa, threshold=thr).sum())
    h = rig.daq_history()
    ay = h.accel[:, 1]
    rest = (h.t > t_rest + 0.5) & (h.t < t_pert)
    stop = min(end, t_pert + out["onset"] + 0.1) if np.isfinite(out["onset"]) else end
    act = (h.t >= t_pert) & (h.t < stop)
    sd = float(np.std(ay[rest]))
    out["imu_sd"] = float(np.max(np.abs(ay[act] - ay[rest].mean())) / sd) if sd > 0 else np.inf
    ax = h.accel[:, 0]
    sdx = float(np.std(ax[rest]))
    out["imu_x_sd"] = float(np.max(np.abs(ax[act] - ax[rest].mean())) / sdx) if sdx > 0 else np.inf
    out["t_pert"] = t_pert
    out["t_end"] = end
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--figure", default=None, help="write the figure here (PNG)")
    ap.add_argument("--bottles", default="TR,TX")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--write", action="store_true", help="put the table between docs/simulator.md's markers")
    args = ap.parse_args()
    ps = plants()
    traces = {}
    lines = [f"{'bottle':6} {'run':5} {'term':10} {'onset s':>8} {'fallen':>6} {'NMSD/thr':>9} {'NMSD det':>8} "
             f"{'SWT/thr':>8} {'SWT on':>7} {'IMU sd':>7} {'IMU x sd':>8}"]
    print(lines[0])
    for b in args.bottles.split(","):
        for what in ("pour", "drop"):
            for name, values in ps.items():
                r = run(b, what, values, args.seed)
                traces[(b, what, name)] = r
                lines.append(f"{b:6} {what:5} {name:10} {r['onset']:8.3f} {str(r['fallen']):>6} "
                             f"{r['nmsd_ratio']:9.2f} {r['nmsd_n']:8d} {r['swt_ratio']:8.2f} {r['swt_on']:7d} "
                             f"{r['imu_sd']:7.1f} {r['imu_x_sd']:8.1f}")
                print(lines[-1], flush=True)
    if args.figure:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        b0 = args.bottles.split(",")[0]
        fig, axes = plt.subplots(2, 2, figsize=(11, 6.5), sharey="row")
        for j, what in enumerate(("pour", "drop")):
            for i, stat in enumerate(("nmsd", "swt")):
                ax = axes[i, j]
                for name in ps:
                    r = traces[(b0, what, name)]
                    t = r[stat + "_t"] - r["t_pert"]
                    if what == "drop":
                        keep = (t > -0.1) & (t < 0.8)
                    else:   # the last 1.5 s before the first slip, to just after fall-out
                        keep = (t > r["onset"] - 1.5) & (t < r["t_end"] - r["t_pert"] + 0.05)
                    ax.plot(t[keep], r[stat + "_trace"][keep], lw=0.8, label=name,
                            ls="-" if name in ("base", "all") else "--")
                ax.axhline(1.0, color="k", ls="--", lw=0.8)
                ax.set_yscale("log")
                ax.set_title(f"{b0} open-loop {what}: {stat.upper()} statistic / threshold")
                ax.set_xlabel("s after the perturbation starts")
        axes[0, 0].legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(args.figure, dpi=110)
        print(f"figure: {args.figure}")
    if args.write:
        from scripts.docs.splice_report import write_section

        return write_section("physics_terms", "docs/simulator.md", "physics terms table",
                             "\n".join("    " + x for x in lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

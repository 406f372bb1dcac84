"""Convert the imanlab proactive-slip-control ``data_set/`` into slipreflex's recorded-trial format.

Run once; its output is the shipped data set
``src/slipreflex/data/datasets/imanlab-slip/`` (docs/benchmark.md, "The data shipped").

The source (MIT licence, Intelligent Manipulation Lab, University of Lincoln):
https://github.com/imanlab/proactive-slip-control, folder ``data_set/``: one folder per
trial with ``xela_sensor1.csv`` / ``xela_sensor2.csv`` (two XELA uSkin 4 x 4 patches,
48 columns ``txl1_x .. txl16_z`` each, raw counts), ``robot_state.csv`` (its ``time``
column, s, and the end effector's commanded ``v_x``, ``v_y``), ``slip_label.csv``
(``slip``, ``fail`` per sample) and ``meta_data.csv`` (``dropped``, ``frequency_hz``, ...).
All files of a trial have one row per sample (the authors' synchronised topic).

What the conversion does, and nothing else:

* ``t`` = ``robot_state.time`` (s; strictly increasing in every trial, checked);
* the 96 tactile columns, renamed ``s1_txl1_x .. s2_txl16_z``, values as integers (counts);
* ``slip`` = ``slip_label.slip`` as 0/1 (the authors' label from the ArUco marker's motion);
* header lines: the layout ``2x4x4x3``, the components, which one is normal, the source,
  its commit, the rate the authors logged, whether the object was dropped, the robot's peak
  commanded speed (the controls were moved more slowly than the slip trials).

Marker poses, joint states and the ``fail`` flag are left out (not channels of a detector).

Usage::

    git clone https://github.com/imanlab/proactive-slip-control src-repo
    python -m scripts.dev.convert_imanlab src-repo/data_set src/slipreflex/data/datasets/imanlab-slip \\
        --commit "$(git -C src-repo rev-parse HEAD)"
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

import numpy as np

SOURCE = "https://github.com/imanlab/proactive-slip-control (data_set/, MIT licence)"
SENSOR = "XELA uSkin 4x4 magnetic tactile patch, one per gripper finger, raw counts"


def _read(path: Path) -> tuple[list[str], np.ndarray]:
    with path.open(newline="") as fh:
        rows = list(csv.reader(fh))
    if not rows:
        raise SystemExit(f"{path}: empty")
    return rows[0], np.array([[float(c) for c in r] for r in rows[1:] if r], dtype=float)


def convert_trial(folder: Path, out: Path, commit: str) -> dict[str, object]:
    """Convert one trial folder; returns a summary line's facts."""
    rs_head, rs = _read(folder / "robot_state.csv")
    sl_head, sl = _read(folder / "slip_label.csv")
    with (folder / "meta_data.csv").open(newline="") as fh:
        meta_rows = list(csv.DictReader(fh))
    meta = meta_rows[0]
    t = rs[:, rs_head.index("time")]
    if not np.all(np.diff(t) > 0):
        raise SystemExit(f"{folder}: robot_state time is not strictly increasing")
    slip = sl[:, sl_head.index("slip")]
    if not np.isin(slip, (0.0, 1.0)).all():
        raise SystemExit(f"{folder}: slip_label.slip is not 0/1")
    columns: dict[str, np.ndarray] = {"t": np.round(t, 6)}
    for s in (1, 2):
        head, xs = _read(folder / f"xela_sensor{s}.csv")
        if len(head) != 48 or len(xs) != len(t):
            raise SystemExit(f"{folder}: xela_sensor{s}.csv has {len(head)} columns and {len(xs)} rows "
                             f"(expected 48 and {len(t)})")
        if not np.array_equal(xs, np.round(xs)):
            raise SystemExit(f"{folder}: xela_sensor{s}.csv holds non-integer counts")
        for j, name in enumerate(head):
            columns[f"s{s}_{name}"] = xs[:, j].astype(np.int64)
    if len(slip) != len(t):
        raise SystemExit(f"{folder}: slip_label has {len(slip)} rows, robot_state {len(t)}")
    columns["slip"] = slip.astype(np.int64)
    speed = float(np.max(np.hypot(rs[:, rs_head.index("v_x")], rs[:, rs_head.index("v_y")])))
    name = folder.name.removeprefix("data_sample_")
    preamble = {
        "layout": "2x4x4x3",
        "components": "x,y,z",
        "normal": "z",
        "unit": "counts",
        "sensor": SENSOR,
        "source": SOURCE,
        "source_commit": commit,
        "source_trial": f"data_set/{folder.name}",
        "logged_rate_hz": f"{float(meta['frequency_hz']):.4f}",
        "dropped": str(int(float(meta["dropped"]))),
        "peak_speed_m_s": f"{speed:.3f}",
    }
    from slipreflex.files.csvfiles import write_columns

    write_columns(out / f"{name}.csv", columns, preamble=preamble)
    v = np.hypot(rs[:, rs_head.index("v_x")], rs[:, rs_head.index("v_y")])
    moving = float(t[np.argmax(v > 0.005)])                # first commanded speed above 5 mm/s
    return {"trial": name, "samples": len(t), "slip_samples": int(slip.sum()), "peak_speed_m_s": speed,
            "moving_from_s": moving}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("source", type=Path, help="the source repository's data_set/ folder")
    ap.add_argument("out", type=Path, help="output folder (one CSV per trial)")
    ap.add_argument("--commit", required=True, help="the source repository's commit hash (for the record)")
    args = ap.parse_args(argv)
    folders = sorted(p for p in args.source.iterdir() if p.is_dir() and p.name.startswith("data_sample_"))
    if not folders:
        print(f"{args.source}: no data_sample_* folders", file=sys.stderr)
        return 2
    args.out.mkdir(parents=True, exist_ok=True)
    for folder in folders:
        info = convert_trial(folder, args.out, args.commit)
        print(f"{info['trial']}: {info['samples']} samples, {info['slip_samples']} labelled slip, "
              f"peak speed {info['peak_speed_m_s']:.3f} m/s, moving from {info['moving_from_s']:.2f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

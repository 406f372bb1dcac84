"""Study plants' calibrations with and without the stop at a cuff-pinned first slip: the same decisions?

The calibration (``slipreflex.sim.calibration.calibrate_bottle``) stops as soon as two pad frictions show
an observed first slip pinned at the middle finger's cuff (every seed observed before its true onset,
below the volumes accepted, at the same volume at both), and the plant is rejected. Without the stop the
search goes on until it has narrowed onto the friction at which the gross slip leaves the pour, and the
plant is rejected there. This script calibrates every ``--step``-th plant of the ``slipreflex study
--plants 1000`` design both ways (the study's calibration, ``slipreflex.study.runner._calibrated``, with
its three-seed fallback) and prints the plants whose decision or calibrated ``mu_s`` differ, the
rejections of each kind and the CPU seconds of each. docs/study.md ("Plants whose accelerometer sees the
cuff's slip") quotes the output.

Run: ``python -m scripts.research.calibration_stops --step 8`` (125 plants; about 3 CPU-minutes, most of
it without the stop).

Examples
--------
>>> decision({"rejected": "", "calibrated_mu_s_TR": 0.5})
('accepted', (('calibrated_mu_s_TR', 0.5),))
"""

from __future__ import annotations

import argparse
import time
from contextlib import contextmanager


def decision(extra: dict) -> tuple[str, tuple]:
    """``(kind, calibrated mu_s)`` of a plant's calibration: kind is accepted, pinned or rejected."""
    from slipreflex.sim.calibration import pinned  # deferred: heavy (numba kernels)

    why = extra.get("rejected", "")
    kind = "accepted" if not why else "pinned" if pinned(why) else "rejected"
    return kind, tuple(sorted((k, v) for k, v in extra.items() if k.startswith("calibrated_mu_s_")))


@contextmanager
def _without_stop():
    import slipreflex.sim.calibration as cal

    kept = cal._stop_if_pinned
    cal._stop_if_pinned = lambda *a, **k: None
    try:
        yield
    finally:
        cal._stop_if_pinned = kept


def _calibrate(index: int, values, config) -> tuple[tuple, float]:
    from slipreflex.sim.uncertain import plant_from_values
    from slipreflex.study.runner import _calibrated

    t0 = time.process_time()
    plant = plant_from_values({k: float(v) for k, v in values.items()}, table=config.table)
    _, extra = _calibrated(plant, config.table)
    return decision(extra), time.process_time() - t0


def main() -> None:
    from slipreflex.study.runner import StudyConfig

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--step", type=int, default=8, help="every STEP-th plant of the 1000-plant design (default 8)")
    args = ap.parse_args()
    if not 1 <= args.step <= 1000:
        ap.error(f"--step must be 1-1000, got {args.step}")
    config = StudyConfig(plants=1000)
    values = config.plant_values()
    _calibrate(0, values[0], config)          # imports and compiled kernels, outside the timing
    kinds: dict[str, dict[str, int]] = {"with": {}, "without": {}}
    cpu = {"with": 0.0, "without": 0.0}
    differ = 0
    for i in range(0, len(values), args.step):
        got = {}
        for how in ("with", "without"):
            if how == "with":
                got[how], c = _calibrate(i, values[i], config)
            else:
                with _without_stop():
                    got[how], c = _calibrate(i, values[i], config)
            cpu[how] += c
            kinds[how][got[how][0]] = kinds[how].get(got[how][0], 0) + 1
        same_kind = (got["with"][0] == "accepted") == (got["without"][0] == "accepted")
        if not same_kind or (got["with"][0] == "accepted" and got["with"][1] != got["without"][1]):
            differ += 1
            print(f"plant {i}: with the stop {got['with']}, without {got['without']}")
    n = len(range(0, len(values), args.step))
    print(f"{n} plants; decisions or calibrated mu_s that differ: {differ}")
    for how in ("with", "without"):
        print(f"{how} the stop: {kinds[how]}, {cpu[how]:.1f} CPU-s")


if __name__ == "__main__":
    main()

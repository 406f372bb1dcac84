"""Regenerate tests/data/board/vectors.txt, the reflex chain's shared test vectors.

Run from the repository root:
    python3 firmware/test/gen_board_vectors.py > tests/data/board/vectors.txt
    python3 firmware/test/gen_board_vectors.py --config > firmware/reflex/reflex_config.h
(the second writes the firmware's chain constants: filter coefficients at the board's
333.33 Hz and theta0, from the same quantisation).

The outputs come from the Python twin (slipreflex.methods.board). The C host test
(firmware/test/test_board_vectors.c, built by firmware/Makefile) runs the firmware's
own core (firmware/reflex/reflex.c) on the same inputs and must reproduce every
filtered sample, event, fault, window count and command; tests/test_board.py checks
the twin against the committed file. Regenerate only when the chain changes on purpose.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

import numpy as np

from slipreflex.methods import board

HEADER = """\
# Fixed-point reflex chain test vectors (docs/firmware.md, "The reflex on the board").
# Read by tests/test_board.py (Python twin) and firmware/test/test_board_vectors.c (C core).
# A vector is seven lines, in this order, fields separated by single spaces:
#   V <name>
#   P <key>=<value> ...        struct reflex_params, integers; x0=- when not given
#   I <adc,adc,...>            ADC readings fed to reflex_step, one per sample
#   Q <pos,pos,...|->          per window: measured position passed to the MPI, '-' = NULL
#   X <x,x,...>                per sample: filtered sample in Q16 counts after the step
#   E <string>                 per sample: 0 no spike, 1 spike, f fault (sample skipped)
#   W <v:command,...|->        per completed window: spike count and command
"""

#: Order of the P fields (the C reader accepts any order but needs every key).
KEYS = ("g", "a1", "a2", "theta0", "filter", "dath", "dath_samples", "dath_floor", "x0", "n",
        "p0", "kp", "ki", "reset_after", "lo", "hi", "adc_min", "adc_max", "stuck_after")


def _csv(values) -> str:
    vals = [str(v) for v in values]
    return ",".join(vals) if vals else "-"


def vector(name: str, params: board.BoardParams, adc: Sequence[int],
           positions: Sequence[int | None] | None = None) -> str:
    """The seven lines of one vector, outputs computed by the twin."""
    res = board.run_board_chain(adc, params, positions=positions)
    nwin = res.counts.size
    pos = [None] * nwin if positions is None else list(positions)[:nwin]
    d = params.to_dict()
    pline = " ".join(f"{k}={'-' if d[k] is None else int(d[k])}" for k in KEYS)
    events = "".join("f" if f else ("1" if e else "0") for e, f in zip(res.events, res.faults))
    wins = _csv(f"{v}:{c}" for v, c in zip(res.counts.tolist(), res.commands.tolist()))
    qline = "-" if all(p is None for p in pos) or not pos else \
        ",".join("-" if p is None else str(p) for p in pos)
    return (f"V {name}\nP {pline}\nI {_csv(res.adc.tolist())}\nQ {qline}\n"
            f"X {_csv(res.filtered.tolist())}\nE {events or '-'}\nW {wins}\n")


def cases() -> list[tuple[str, board.BoardParams, np.ndarray, list | None]]:
    """The committed vectors: named cases exercising every rule of the chain."""
    bp = board.BoardParams.from_chain
    rng = np.random.default_rng(20261123)
    t = np.arange(400)
    sine = np.r_[np.full(32, 300), 300 + np.round(10 * np.sin(np.arange(64) / 3.0))].astype(int)
    walk = np.clip(np.round(300 + np.cumsum(rng.normal(0, 1.5, 3000))), 0, 1023).astype(int)
    noisy = np.clip(np.round(500 + 40 * np.sin(t / 5.0) + rng.normal(0, 3, t.size)), 0, 1023)
    rails = np.where((np.arange(600) // 7) % 2 == 0, 0, 1023)
    steps = np.repeat([300, 305, 295, 296, 298, 400, 120, 121], 40)
    faulty = walk[:800].copy()
    faulty[100:110] = 3                        # below adc_min
    faulty[300:305] = 1023                     # above adc_max
    faulty[500:520] = faulty[499]              # stuck for 20 samples
    out = [
        ("constant_fixed", bp(), np.full(64, 300), None),
        ("constant_dath_full_scale", bp(dath=True), np.full(48, 1023), None),
        ("sine_fixed", bp(), sine, None),
        ("sine_dath", bp(dath=True), sine, None),
        ("steps_fixed", bp(), steps, None),
        ("steps_dath_p0_125", bp(dath=True, p0=125), steps, None),
        ("walk_fixed", bp(), walk, None),
        ("walk_dath", bp(dath=True), walk, None),
        ("noisy_dath_saturates", bp(dath=True, p0=300), noisy.astype(int), None),
        ("rails_square_dath", bp(dath=True), rails, None),
        ("rails_square_no_filter", bp(filter=False, kp=255, ki=255, lo=-32768, hi=32767,
                                      p0=-32768, n=255), np.tile(rails, 3), None),
        ("paper_x0_zero", bp(dath=True, x0=0.0), sine, None),
        ("dath_floor_and_D4", bp(dath=True, dath_floor=0.02, dath_samples=4), walk[:600], None),
        ("window_9_reset_3", bp(dath=True, n=9, reset_after=3, kp=3, ki=1), steps, None),
        ("positions_at_reset", bp(dath=True, reset_after=2), steps,
         [None if z % 3 else 40 * z for z in range(steps.size // 16)]),
        ("faults_range_and_stuck", bp(dath=True, adc_min=8, adc_max=1015, stuck_after=10),
         faulty, None),
        ("empty", bp(), np.zeros(0, dtype=int), None),
    ]
    return out


def config_header() -> str:
    """firmware/reflex/reflex_config.h: the board's chain constants, from the twin."""
    p = board.BoardParams.from_chain()
    return f"""\
/* reflex_config.h -- the chain constants the firmware runs with. GENERATED by
 *   python3 firmware/test/gen_board_vectors.py --config > firmware/reflex/reflex_config.h
 * from slipreflex.methods.board.BoardParams.from_chain() (fs = 333.33 Hz, cutoff 10 Hz,
 * theta0 = 0.008 V), slipreflex.methods.board.FIRMWARE_* (fault rules) and the hand's grip-only
 * rule (slipreflex.methods.board.BoardHand: one unit of grip closes GRIP_PER_UNIT / GRIP_PER_SAMPLE
 * samples at full PWM); tests/test_board_firmware.py checks that they still agree. */
#ifndef SLIPREFLEX_REFLEX_CONFIG_H
#define SLIPREFLEX_REFLEX_CONFIG_H
#define REFLEX_CFG_G {p.g}L
#define REFLEX_CFG_A1 ({p.a1}L)
#define REFLEX_CFG_A2 {p.a2}L
#define REFLEX_CFG_THETA0 {p.theta0}L
#define REFLEX_CFG_DATH_SAMPLES {p.dath_samples}
#define REFLEX_CFG_N {p.n}
#define REFLEX_CFG_KP {p.kp}
#define REFLEX_CFG_KI {p.ki}
#define REFLEX_CFG_RESET_AFTER {p.reset_after}
#define REFLEX_CFG_LO {p.lo}
#define REFLEX_CFG_HI {p.hi}
#define REFLEX_CFG_ADC_MIN {board.FIRMWARE_ADC_MIN}u
#define REFLEX_CFG_ADC_MAX {board.FIRMWARE_ADC_MAX}u
#define REFLEX_CFG_STUCK_AFTER {board.FIRMWARE_STUCK_AFTER}u
#define REFLEX_CFG_GRIP_PER_UNIT {board.GRIP_PER_UNIT}
#define REFLEX_CFG_GRIP_PER_SAMPLE {board.GRIP_PER_SAMPLE}
#define REFLEX_CFG_HAND_PWM {board.HAND_PWM}u
#endif
"""


def main(out=sys.stdout) -> None:
    if "--config" in sys.argv[1:]:
        out.write(config_header())
        return
    out.write(HEADER)
    for name, params, adc, pos in cases():
        out.write(vector(name, params, adc, pos))


if __name__ == "__main__":
    main()

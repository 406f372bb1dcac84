"""The reflex as the microcontroller runs it: the Python twin of ``firmware/reflex/``.

The C99 core in ``firmware/reflex/reflex.c`` runs the chain of docs/method.md section 1
in integer fixed point on 10-bit ADC counts. This module does the same integer
operations, in the same order, so the two agree bit for bit on every sample; the
shared vectors in ``tests/data/board/vectors.txt`` and random signals check that
(tests/methods/test_board.py). docs/firmware.md states the formats:

* filter: 2nd-order Butterworth low-pass in direct form I, coefficients with
  :data:`COEF_Q` = 24 fractional bits (``b = g (1, 2, 1)``, ``a = (1, a1, a2)``,
  ``4 g = 2**24 + a1 + a2`` so the DC gain is exactly 1), output in counts with
  :data:`SIG_Q` = 16 fractional bits, rounded half up (add ``2**23``, arithmetic
  shift right by 24) -- the chain's only rounding;
* encoder: the float chain's rules on Q16 counts; theta0 = 0.008 V =
  1.6384 counts = 107374 in Q16; DATH's ``|x_k - x_(k-1)|`` is the exact difference
  of two Q16 samples;
* windows and MPI: integers (the MPI is exact, commands are whole positions).
* the standalone board's hand (``hand2560``): :class:`BoardHand`, grip only added --
  each rise of the command is CLOSE at full PWM and a STOP ``ceil(8 g / 15)`` samples
  later, a fault sends STOP, never OPEN or POSITION (:func:`board_hand` over a run).

Examples
--------
>>> import numpy as np
>>> adc = np.r_[np.full(32, 300), 300 + np.round(10 * np.sin(np.arange(64) / 3.0))].astype(int)
>>> res = run_board_chain(adc, dath=True)
>>> res.counts.tolist(), res.commands.tolist()
([0, 0, 5, 9, 7, 6], [0, 0, 50, 115, 140, 165])
>>> BoardParams.from_chain().theta0          # 0.008 V in Q16 counts
107374
"""

from __future__ import annotations

from .fixed import ADC_MAX as ADC_MAX  # public outside __all__, importable from here as before
from .fixed import (
    COEF_Q,
    FIRMWARE_ADC_MAX,
    FIRMWARE_ADC_MIN,
    FIRMWARE_STUCK_AFTER,
    H_MAX,
    SIG_Q,
    BoardChain,
    BoardParams,
    BoardResult,
    adc_counts,
    board_params_from_json,
    quantize_lowpass,
    run_board_chain,
    volts_to_q16,
)
from .hand import GRIP_PER_SAMPLE, GRIP_PER_UNIT, HAND_PWM, BoardHand, HandTrace, board_hand, grip_time_ratio
from .host import (
    BoardReflex,
    BoardSource,
    CheckedBoardReflex,
    board_detections,
    board_method_detections,
    build_board_method,
    read_adc_csv,
    write_board_outputs,
)

__all__ = [
    "COEF_Q", "SIG_Q", "H_MAX", "BoardParams", "BoardChain", "BoardReflex", "BoardResult",
    "run_board_chain", "adc_counts", "quantize_lowpass", "volts_to_q16", "board_detections",
    "FIRMWARE_ADC_MIN", "FIRMWARE_ADC_MAX", "FIRMWARE_STUCK_AFTER", "read_adc_csv",
    "write_board_outputs", "CheckedBoardReflex", "BoardSource", "board_params_from_json",
    "grip_time_ratio", "GRIP_PER_UNIT", "GRIP_PER_SAMPLE", "HAND_PWM", "BoardHand", "HandTrace",
    "board_hand", "build_board_method", "board_method_detections",
]

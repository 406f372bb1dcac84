"""Make examples/slip_example.csv: a small synthetic slip-sensor recording.

A dark surface at rest (about 3.33 V, ADC-quantized noise), a slip of 0.4 s in
which surface texture moves under the sensor, and rest again; 333.33 Hz for 3 s.
Deterministic (seed 7). Run: python examples/make_example.py
"""

from pathlib import Path

import numpy as np

from slipreflex.core.hardware import ADC_LSB, DAQ_FS
from slipreflex.files.csvfiles import write_columns


def main() -> None:
    rng = np.random.default_rng(7)
    k = np.arange(int(3 * DAQ_FS))
    t = k / DAQ_FS
    position_mm = np.clip((t - 1.2) / 0.4, 0, 1) ** 2 * 2.0  # 2 mm of slip from 1.2 s to 1.6 s
    texture = sum(a * np.sin(2 * np.pi * position_mm / w + p)
                  for a, w, p in zip([0.012, 0.008, 0.005], [0.7, 0.31, 0.13], rng.uniform(0, 6.3, 3)))
    volts = 3.335 + texture + rng.normal(0, 0.0015, k.size)
    volts = np.round(volts / ADC_LSB) * ADC_LSB
    write_columns(Path(__file__).with_name("slip_example.csv"), {"t": np.round(t, 6), "x": np.round(volts, 6)})


if __name__ == "__main__":
    main()

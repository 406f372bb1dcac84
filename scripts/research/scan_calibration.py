"""The test surface's calibration to the paper's scan, on ensemble statistics, recomputed.

For white and black: the reflectance and texture rms at which the median, over 200
texture seeds, of the filtered level range inside the region is the paper's (white
0.3-0.5 V, black 3.32-3.35 V; Fig. 6-9), with the texture blurred by the sensor's spot
(:func:`slipreflex.sim.scan.calibrate_surface`). Then the ensemble's central 90 % of
each level and of the fixed threshold's smallest spike spacing, on the built-in surfaces.

Run: ``python -m scripts.research.scan_calibration`` (about a minute).
"""

from __future__ import annotations


def main() -> None:
    from slipreflex.sim.scan import calibrate_surface, scan_ensemble

    for name, level in (("white", (0.3, 0.5)), ("black", (3.32, 3.35))):
        s = calibrate_surface(name, level)
        print(f"{name}: reflectance {s.reflectance:.4f}, texture {s.texture:.4f}")
    e = scan_ensemble()
    for k in ("white_lo", "white_hi", "black_lo", "black_hi", "fixed_gap", "dath_gap"):
        lo, hi = e.band(k)
        print(f"built-in surfaces, {len(e)} seeds: {k} central 90 % {lo:.4f} .. {hi:.4f}")


if __name__ == "__main__":
    main()

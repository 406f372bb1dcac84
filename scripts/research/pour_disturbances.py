"""The pour's disturbances in numbers (docs/simulator.md quotes this script's output).

Prints, for the paper's bottle (6.5 cm) and the default ``WaterParams``:

1. the first antisymmetric slosh mode at several fills: frequency, slosh mass,
   damping ratio and the jet's modal force factor (``kernel.slosh_mode``, the
   closed forms the kernel integrates);
2. the jet's mean push and its splash's rms for the paper's 1 L/min pour;
3. what one simulated pour (seed 1, grasp squeezed so that it holds all
   500 ml) gives: the splash's rms, the water's sideways force and the
   bottle's sideways acceleration (truth), and the accelerometer's x axis
   with and without the water's disturbances.

Run: ``python -m scripts.research.pour_disturbances``.
"""

from __future__ import annotations

import math

import numpy as np

from slipreflex.core import hardware as hw
from slipreflex.sim import BOTTLES, PAPER_POUR, Rig, WaterParams, simulate_open_loop
from slipreflex.sim import kernel as K
from slipreflex.sim.objects import WATER_DENSITY
from slipreflex.sim.params import WATER_KINEMATIC_VISCOSITY


def held_pour(water: WaterParams, seed: int = 1):
    """The paper's pour on TR with the grasp 40 units past the 0.8 N stop (it holds throughout)."""
    rig = Rig("TR", seed=seed, water=water)
    g = rig.grasp()
    rig.hand.set_positions({f: g.positions[f] + 40 for f in hw.TRIPOD})
    rig.perturb(PAPER_POUR, at=rig.t + 0.5)
    tr = simulate_open_loop(rig, PAPER_POUR.duration_s + 1.0)
    t_in = tr.t_start + 0.5 + math.sqrt(2.0 * PAPER_POUR.fall_height_m / hw.GRAVITY)
    flowing = (tr.t > t_in + 0.01) & (tr.t < t_in + PAPER_POUR.duration_s - 0.01)
    return tr, flowing


def main() -> None:
    w = WaterParams()
    r = BOTTLES["TR"].diameter_m / 2.0
    from scipy.special import j1

    phi = float(j1(1.8411837813406593 * w.jet_offset_m / r) / j1(1.8411837813406593))
    print(f"bottle radius {r * 1e3:.1f} mm, jet {w.jet_offset_m * 1e3:.1f} mm off the axis")
    print("  fill    f_slosh  slosh mass  zeta    jet factor beta")
    for ml in (30, 100, 200, 300, 500):
        mw = ml * 1e-6 * WATER_DENSITY
        zeta0 = K.slosh_zeta0(r, WATER_KINEMATIC_VISCOSITY, hw.GRAVITY, w.slosh_damping_factor)
        kth, m1, zeta, beta = K.slosh_mode(mw, r, WATER_DENSITY, zeta0, phi)
        f = math.sqrt(hw.GRAVITY * kth) / (2.0 * math.pi)
        print(f"  {ml:3d} ml  {f:5.2f} Hz  {m1 * 1e3:6.1f} g   {zeta * 100:5.2f} %  {beta:.3f}")
    q = PAPER_POUR.rate_l_min / 60.0 * 1e-3 * WATER_DENSITY
    jet = q * math.sqrt(2.0 * hw.GRAVITY * PAPER_POUR.fall_height_m)
    print(f"paper pour: jet push {jet * 1e3:.1f} mN, splash rms {w.splash_rms * jet * 1e3:.2f} mN "
          f"(one-pole, corner {w.splash_corner_hz:g} Hz)")
    tr, flowing = held_pour(w)
    d = tr.daq
    splash = d.load_force[flowing] - d.load_mass[flowing] * hw.GRAVITY - jet
    print(f"simulated (seed 1, held): splash rms {splash.std() * 1e3:.2f} mN; water's sideways force rms "
          f"{d.water_force_lateral[flowing].std() * 1e3:.2f} mN; bottle's sideways acceleration rms "
          f"{d.accel_lateral[flowing].std() / hw.GRAVITY * 1e3:.2f} mg, peak "
          f"{np.abs(d.accel_lateral[flowing]).max() / hw.GRAVITY * 1e3:.2f} mg")
    calm, _ = held_pour(WaterParams(splash_rms=0.0, jet_offset_m=0.0))
    print(f"accelerometer x axis while pouring: {d.accel[flowing, 0].std() * 1e3:.2f} mg rms "
          f"(without splash and slosh {calm.daq.accel[flowing, 0].std() * 1e3:.2f} mg: its noise)")
    print(f"accelerometer y axis (along the bottle) while pouring: {d.accel[flowing, 1].std() * 1e3:.2f} mg rms "
          f"(without {calm.daq.accel[flowing, 1].std() * 1e3:.2f} mg)")


if __name__ == "__main__":
    main()

"""The numba kernel: grasp physics, finger servos and the DAQ-side sensors.

Internal module: :class:`slipreflex.sim.Rig` is the public face. The state,
parameters and outputs are flat float64 arrays indexed by named constants, so
the jitted functions compile once (``cache=True``) and a call has few
arguments. This module gathers the kernel's names from the files that hold them:

* :mod:`~slipreflex.sim._kernel_layout`: every vector's slots (``S_X``, ``P_KN``, ...);
* :mod:`~slipreflex.sim.kernel_noise`: the counter-based noise;
* :mod:`~slipreflex.sim.kernel_contacts`: the grip's normal force, the friction laws, the tilt, the slosh mode;
* :mod:`~slipreflex.sim.kernel_sensors`: the slip sensor's volts, the IMU's quantization, the tactile frames;
* :mod:`~slipreflex.sim.kernel_calm`: the adaptive stepping's rules (when the rig is calm, where a coarse step ends);
* :mod:`~slipreflex.sim.kernel_step`: :func:`step_until`, the step itself.

numba stamps a cached kernel with its own file only; each of these modules
declares the files whose code it compiles in
(:func:`slipreflex.core._numba_cache.stamped_cache`), so an edit in any of them
recompiles what depends on it.

Model (one physics step of ``dt``, semi-implicit Euler):

* **Fingers** (thumb, index, middle): first-order position servo
  ``dq/dt = clip(K (target - q), -speed, speed)``; closing, the speed limit
  falls along the DC motor's torque-speed line, ``speed (1 - droop N_c /
  stall)``, and a finger does not advance while its contact force exceeds
  the stall force (non-back-drivable: it holds its position under load).
* **Normal force**: the three fingertips sit 120 degrees apart around the
  bottle, which is free to shift sideways; three radial forces at 120 degrees
  balance only when equal, so every contact carries the same normal force
  ``N_c = k_n * travel * max(0, mean(q) - q_contact)`` with ``k_n`` three
  over the sum of the contacts' compliances (each: pad or cuff, finger and
  bottle wall in series), up to the wall's linear range; beyond it the wall
  ovalizes (softer) and then, folded flat, is rigid
  (:func:`slipreflex.sim.contacts.grip_curve`, :func:`_grip_force`).
* **Friction, per contact** (thumb and index through their silicone pads,
  the middle finger through the rigid cuff of the slip sensor), each with
  its own law and constants. A contact's tangential compliance ``k_t``
  (damping ``c_t``) ties the bottle to an anchor ``s`` on its surface; the
  bottle slips grossly only when all three slide. Two laws:

  - *rate-state* (default): slip weakening over a distance ``D_c``, healing
    over ``t_heal`` and a logarithmic rate term,
    ``mu = mu_k + (mu_s - mu_k) phi + a ln(1 + w / v0)`` (``PC_A`` holds
    ``a`` in absolute units); see
    :func:`_rs_contact` (implicit return mapping, :func:`rs_slide_speed`);
  - *Coulomb-Stribeck*: ``mu(w) = mu_k + (mu_s - mu_k) exp(-(w / v_s)^2)``,
    explicit, with the massless pad relaxing exactly toward ``F / k_t``.

  No creep while stuck: ``s`` does not move at all.
* **Loads**: gravity on bottle + water (+ landed masses, through their
  contact springs); a dropped mass is a second body with a compliant,
  damped contact on the bottom; a pour adds water at a constant rate after
  the jet's fall time and pushes with the jet's momentum flux, plus its
  splash (a one-pole noise on a fixed 1 ms grid, stream ``keys[5]``).
* **Slosh** (sideways, ``WaterParams``): the first antisymmetric mode of the
  water as a spring-mass (:func:`slosh_mode`) on the bottle, which the grasp
  holds sideways; driven by the jet landing off the axis and by the bottle's
  own motion (its axial acceleration scales the mode's gravity). The
  accelerometer's x axis reads the bottle's sideways acceleration.
* **Tilt** (the second degree of freedom): the bottle turns by ``th`` about
  the horizontal axis through the grasp's centre and the middle finger's
  cuff; each contact's friction law sees its own slide ``x + lever th``, so
  the contacts' tangential forces carry the weight and the tilt together,
  each bounded by its friction (the friction couple); gravity acts on the
  centre of mass below the axis, and the tilted section's ellipse presses
  the off-axis fingertips in (second order). A dropped mass lands on the
  bottom ``P_DROP_E`` off the axis and rocks the bottle
  (:func:`tilt_inertia`). Nothing else tilts it: a bottle that is never
  pushed off the axis runs the one-degree-of-freedom arithmetic.
* **Fallen out**: once the bottle has moved ``grip_travel`` below the
  fingertips the contacts reach the shoulder (each contact at its own
  height when tilted) and are lost; the bottle then falls freely.
* **Sensors** sampled inside the loop on their own clocks: the OPR5005 slip
  sensor (track interpolation at the surface position under the sensor,
  which moves with the bottle and with the middle fingertip's own rolling as
  it advances into the wall, ``P_SPOT_K`` metres per position unit of the
  tip's advance (the cuff's compression and the wall's dent), the gap
  opening by ``P_DENT_FRAC`` of the dent, transfer curve, electrical noise, 10-bit ADC) and flow pulses at the DAQ's
  333.33 Hz; the MPU6050 at its own ODR through its DLPF. Tactile snapshots
  (normal and tangential force, slip distance) at each requested tactile
  rate; frames are built by :func:`tactile_frames`.

Noise is counter-based (splitmix64 of a per-channel key and the sample
index), so a trace does not depend on how the run is cut into calls.

Speed: the step is a sequence of pieces numba inlines into :func:`step_until`
(``inline="always"``: the fingers, the normal force, the loads, the splash, the
drops, the slosh, the held bottle's contacts and micro-slips, the IMU, the DAQ
rows, the tactile snapshots); each returns the scalars it changes, and the step
writes its output rows element by element. An inlined helper that takes an
array, or a row view ``daq_out[nd]``, costs numba an atomic incref/decref pair
per call that its reference-count pruning does not remove (with them a held
grasp took about 160 ns per step, without them about 50 ns,
``benchmarks/bench_sim.py``), so :func:`step_until` hands its pieces borrowed
arrays, which numba counts no references to.
"""

from __future__ import annotations

from ..core._numba_cache import stamped_cache
from . import _kernel_layout, kernel_calm, kernel_contacts, kernel_noise, kernel_sensors, kernel_step
from ._kernel_layout import *  # noqa: F403 (every slot constant and layout, bound once in _kernel_layout)
from .kernel_contacts import _rs_solve as _rs_solve
from .kernel_contacts import mass_cap as mass_cap
from .kernel_contacts import rs_slide_speed as rs_slide_speed
from .kernel_contacts import slosh_mode as slosh_mode
from .kernel_contacts import slosh_zeta0 as slosh_zeta0
from .kernel_contacts import tilt_inertia as tilt_inertia
from .kernel_noise import derive_key as derive_key
from .kernel_noise import normal as normal
from .kernel_noise import normal_pair as normal_pair
from .kernel_noise import uniform as uniform
from .kernel_sensors import tactile_frames as tactile_frames
from .kernel_sensors import volts_along as volts_along
from .kernel_step import step_until as step_until

__all__: list[str] = []

# a kernel elsewhere that calls these names through this module compiles in the files that hold them
stamped_cache(__file__, *(m.__file__ or "" for m in (_kernel_layout, kernel_noise, kernel_contacts, kernel_sensors,
                                                    kernel_calm, kernel_step)))

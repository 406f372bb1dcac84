"""The digits' motor vibration: what the tactile arrays and the IMU see while a digit turns, against closed forms."""

import numpy as np
import pytest

from slipreflex.core import hardware as hw
from slipreflex.core.hardware import HandCommand
from slipreflex.sim import HandParams, Rig
from slipreflex.sim import kernel as K

FS = 8000.0
PWM = 150


def _close(hand):
    rig = Rig("TR", seed=4, hand=hand)
    rig.grasp()
    s = rig.tactile_sampler(FS)
    rows = []
    s.feed = lambda snap, params: rows.append(snap.copy())
    t0 = rig.t
    rig.hand.command(HandCommand.CLOSE, hw.TRIPOD, PWM)
    rig.advance_block(t0 + 0.25)
    return rig, np.concatenate(rows), rig.daq_history(since=t0)


@pytest.fixture(scope="module")
def runs():
    base = dict(motor_droop=0.0)
    return _close(HandParams(motor_vibration_n=0.0, **base)), _close(HandParams(**base))


def test_the_pad_sees_its_digit_motor_at_the_speed_proportional_frequency_and_size(runs):
    (r0, a0, _), (r1, a1, _) = runs
    # the axial physics does not change: the normal force is the same, the vibration rides on it
    assert np.array_equal(a0[:, K.T_S], a1[:, K.T_S])
    y = a1[:, K.T_NC] - a0[:, K.T_NC]
    hp = HandParams()
    ratio = PWM / hw.PWM_MAX                      # the digits turn at this fraction of full speed
    moving = np.flatnonzero(y != 0)
    seg = y[moving[0]:moving[-1]]
    assert len(seg) > 0.15 * FS
    # closed form: F0 r sin(2 pi f0 r t + phase)
    assert np.max(np.abs(seg)) == pytest.approx(hp.motor_vibration_n * ratio, rel=0.01)
    spec = np.abs(np.fft.rfft(seg * np.hanning(len(seg))))
    f = np.fft.rfftfreq(len(seg), 1 / FS)
    assert f[np.argmax(spec)] == pytest.approx(hp.motor_vibration_hz * ratio, rel=0.03)
    assert np.all(y[: moving[0]] == 0)            # nothing before the digits move


def test_the_imu_sees_the_digits_through_the_grasp_sideways(runs):
    (_, _, h0), (r1, _, h1) = runs
    assert np.all(h0.accel_lateral == 0)          # no water, no motor: the bottle does not move sideways
    a = h1.accel_lateral
    hp = HandParams()
    ratio = PWM / hw.PWM_MAX
    # the three radial forces at 0, 120, 240 degrees with their motors' phases: amplitude of the net force
    ph = np.array([2 * np.pi * float(K.uniform(r1._keys[7], i)) for i in range(3)])
    net = abs(np.exp(1j * ph[0]) - 0.5 * np.exp(1j * ph[1]) - 0.5 * np.exp(1j * ph[2])) * hp.motor_vibration_n * ratio
    w = 2 * np.pi * hp.motor_vibration_hz * ratio
    P = r1._P
    k, c, m = P[K.P_KLAT], P[K.P_CLAT], r1.bottle.mass_kg
    steady = net * w * w / np.hypot(k - m * w * w, c * w)   # the driven oscillator's acceleration amplitude
    late = a[(h1.t > h1.t[0] + 0.15) & (h1.t < h1.t[0] + 0.24)]
    assert np.max(np.abs(late)) == pytest.approx(steady, rel=0.15)

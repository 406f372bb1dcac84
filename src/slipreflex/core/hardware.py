"""Facts about the paper's hardware, defined once (docs/method.md section 3).

Every module that needs a sampling rate, a finger range, a finger id or a
protocol byte imports it from here; no other module repeats these numbers.

Examples
--------
>>> from slipreflex import hardware as hw
>>> round(hw.DAQ_FS, 2)
333.33
>>> hw.Finger.MIDDLE.value, hw.FINGER_MAX
(2, 500)
"""

from __future__ import annotations

import enum

__all__ = [
    "FS_NOMINAL", "F_CPU", "DAQ_PERIOD_S", "DAQ_FS", "ADC_BITS", "ADC_VREF", "ADC_LSB",
    "PAPER_LSB", "WINDOW_N", "FINGER_MIN", "FINGER_MAX", "THUMB_ROTATOR_MAX", "PWM_MAX",
    "FINGER_SPEED_UNITS_S",
    "Finger", "HandCommand", "TRIPOD", "SLIP_FINGER", "ILIMB_START", "ILIMB_END",
    "ILIMB_BAUD", "FLOW_PULSES_PER_LITRE", "CONTACT_FORCE_N", "TACTILE_SHAPE",
    "NMSD_FS", "SWT_FS", "GRAVITY", "IMU_RANGE_G", "IMU_LSB_PER_G", "SLIP_SENSOR_GAP_M",
]

#: Nominal slip-sensor sampling rate the paper quotes (Hz); the DAQ really samples at DAQ_FS,
#: every default ``fs`` of the package.
FS_NOMINAL: float = 333.0
#: AVR clock (Hz) of the ATmega328P DAQ board.
F_CPU: int = 16_000_000
#: The firmware's timer period (s): 3 ms, i.e. 333.33 Hz.
DAQ_PERIOD_S: float = 0.003
#: The firmware's actual sampling rate (Hz).
DAQ_FS: float = 1.0 / DAQ_PERIOD_S
#: ADC resolution (bits) and reference (V) of the DAQ board.
ADC_BITS: int = 10
ADC_VREF: float = 5.0
#: One ADC step at a 5 V reference (V), about 4.9 mV.
ADC_LSB: float = ADC_VREF / (1 << ADC_BITS)
#: One LSB as the paper rounds it (V); the base threshold is twice this.
PAPER_LSB: float = 0.004
#: Samples per spike-count window (paper Eq. 3).
WINDOW_N: int = 16

#: i-Limb finger position range (0 open .. 500 closed) and other value ranges.
FINGER_MIN: int = 0
FINGER_MAX: int = 500
THUMB_ROTATOR_MAX: int = 750
PWM_MAX: int = 297
#: Closing speed of an i-Limb digit at full PWM (position units per second): a digit closes
#: fully (0 -> 500) in about 0.8 s (manufacturer; Belter et al. 2013, J Rehabil Res Dev 50(5)).
#: The grip-only rule (:mod:`slipreflex.core.grip`) turns grip into closing time with it.
FINGER_SPEED_UNITS_S: float = 625.0


class Finger(enum.IntEnum):
    """i-Limb finger ids on the control unit's serial protocol.

    Examples
    --------
    >>> Finger(2).name
    'MIDDLE'
    """

    THUMB = 0
    INDEX = 1
    MIDDLE = 2
    RING = 3
    LITTLE = 4
    THUMB_ROTATOR = 5
    WRIST = 6


class HandCommand(enum.IntEnum):
    """i-Limb per-finger command codes.

    Examples
    --------
    >>> int(HandCommand.POSITION)
    3
    """

    STOP = 0
    CLOSE = 1
    OPEN = 2
    POSITION = 3


#: Fingers of the tripod grasp; the slip sensor sits on the middle finger.
TRIPOD: tuple[Finger, ...] = (Finger.THUMB, Finger.INDEX, Finger.MIDDLE)
SLIP_FINGER: Finger = Finger.MIDDLE
#: i-Limb packet framing bytes and baud rate.
ILIMB_START: int = 0x24
ILIMB_END: int = 0x21
ILIMB_BAUD: int = 115_200

#: YF-S201: about 450 pulses per litre (frequency = 7.5 x flow in L/min).
FLOW_PULSES_PER_LITRE: float = 450.0
#: Contact force (N) at which the initial tripod closing stops.
CONTACT_FORCE_N: float = 0.8
#: Tactile array on the fingertip used by the comparison methods.
TACTILE_SHAPE: tuple[int, int] = (4, 4)
#: Sampling rates (Hz) of the comparison methods (paper II-E).
NMSD_FS: float = 260.0
SWT_FS: float = 380.0
#: Standard gravity (m/s^2).
GRAVITY: float = 9.80665
#: MPU6050 accelerometer full scale (g) and sensitivity (counts per g) at AFS_SEL = 0 (datasheet).
IMU_RANGE_G: float = 2.0
IMU_LSB_PER_G: int = 16384
#: Gap (m) between the slip sensor and the surface, set by the finger cuff (paper II-D).
SLIP_SENSOR_GAP_M: float = 0.003

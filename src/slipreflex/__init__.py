"""slipreflex: event-based slip detection and reflex-like grip control.

The paper's method as a library: raw optical slip-sensor volts are low-pass
filtered, turned into FA-I-like spikes by send-on-delta (fixed threshold or the
Dynamic Adaptive Threshold), counted in 16-sample windows, and fed to a
Monotonic PI controller that closes the fingers until slip stops.

Examples
--------
>>> import numpy as np, slipreflex
>>> raw = np.r_[np.full(32, 0.40), 0.40 + 0.05 * np.sin(np.arange(64) / 3.0)]
>>> slipreflex.run_chain(raw, dath=True).counts.tolist()
[0, 0, 5, 9, 7, 6]
"""

from .core._moved import install as _install_moved
from .core.errors import DataError, DeviceError, ParameterError, SlipreflexError
from .methods.chain import (
    ChainResult,
    EncoderParams,
    EncoderTrace,
    EventEncoder,
    FilterParams,
    LowPass,
    MPIController,
    MPIParams,
    ReflexParams,
    SlipReflex,
    WindowCounter,
    WindowParams,
    count_windows,
    design_lowpass,
    encode,
    encode_trace,
    lowpass,
    mpi,
    run_chain,
)

__version__ = "0.1.0"

_install_moved()

__all__ = [
    "lowpass", "design_lowpass", "encode", "encode_trace", "count_windows", "mpi", "run_chain",
    "LowPass", "EventEncoder", "WindowCounter", "MPIController", "SlipReflex",
    "EncoderTrace", "ChainResult",
    "FilterParams", "EncoderParams", "WindowParams", "MPIParams", "ReflexParams",
    "SlipreflexError", "ParameterError", "DataError", "DeviceError",
    "__version__",
]

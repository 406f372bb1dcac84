"""The reflex signal chain of the paper (docs/method.md section 1).

Batch functions (:func:`lowpass`, :func:`encode`, :func:`count_windows`,
:func:`mpi`, :func:`run_chain`) and streaming objects (:class:`LowPass`,
:class:`EventEncoder`, :class:`WindowCounter`, :class:`MPIController`,
:class:`SlipReflex`) that agree bit for bit.
"""

from .encoder import EncoderTrace, EventEncoder, encode, encode_trace
from .filters import LowPass, design_lowpass, lowpass
from .mpi import MPIController, mpi
from .params import EncoderParams, FilterParams, MPIParams, ReflexParams, WindowParams
from .reflex import ChainResult, SlipReflex, run_chain
from .windows import WindowCounter, count_windows

__all__ = [
    "lowpass", "design_lowpass", "encode", "encode_trace", "count_windows", "mpi", "run_chain",
    "LowPass", "EventEncoder", "WindowCounter", "MPIController", "SlipReflex",
    "EncoderTrace", "ChainResult",
    "FilterParams", "EncoderParams", "WindowParams", "MPIParams", "ReflexParams",
]

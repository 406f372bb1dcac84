"""The paper's comparison methods on the 4 x 4 tactile array (docs/method.md section 2).

* :class:`NMSD` - neuromimetic slip detection after Osborn et al. (260 Hz);
* :class:`SWTSD` - stationary-wavelet slip detection after Romeo et al. (380 Hz).

Both implement :class:`slipreflex.core.interfaces.Reflex` (``input_kind="tactile"``),
turn detections into finger position targets with the 45 ms closing rule of
:mod:`slipreflex.methods.baselines.closing`, and have batch functions over a
``(K, 4, 4)`` array that give exactly what the streaming objects give. Their
thresholds come from one rule, :func:`rest_threshold`.

Examples
--------
>>> from slipreflex.methods.baselines import NMSD, SWTSD
>>> NMSD(threshold=40.0, speed=500.0).fs, SWTSD(threshold=0.1, speed=500.0).fs
(260.0, 380.0)
"""

from .calibration import REST_K, rest_statistic, rest_threshold
from .closing import CLOSE_S, Closer, ClosingParams, closing_commands
from .nmsd import NMSD, NMSDParams, nmsd_commands, nmsd_detections, nmsd_rest_statistic, nmsd_statistic
from .shell import TactileParams, TactileReflex
from .swt import SWTSD, SWTParams, swt_commands, swt_kernel, swt_on, swt_rest_statistic, swt_statistic

__all__ = [
    "NMSD", "NMSDParams", "nmsd_statistic", "nmsd_detections", "nmsd_commands", "nmsd_rest_statistic",
    "SWTSD", "SWTParams", "swt_statistic", "swt_on", "swt_commands", "swt_kernel", "swt_rest_statistic",
    "CLOSE_S", "ClosingParams", "Closer", "closing_commands",
    "REST_K", "rest_statistic", "rest_threshold", "TactileParams", "TactileReflex",
]

"""Analysis as the paper does it: slip onset, metrics, the paper's table, report.

* :mod:`~slipreflex.analysis.onset` - slip onset from the accelerometer;
* :mod:`~slipreflex.analysis.events` - a pour segmented into slip events;
* :mod:`~slipreflex.analysis.metrics` - response time, controller time, success;
* :mod:`~slipreflex.analysis.trial` - one trial's streams to one row per slip;
* :mod:`~slipreflex.analysis.paper` - the paper's numbers, as data;
* :mod:`~slipreflex.analysis.report` - CSV files, tables;
* :mod:`~slipreflex.analysis.figures` - the figures (matplotlib, imported lazily).

Examples
--------
>>> from slipreflex.analysis import PAPER, detect_onset
>>> PAPER[("pour", "response_ms", "DK", "swt")].text()
'73 ± 22'
"""

from .events import SlipEvent, segment_events
from .metrics import Activity, controller_activity, increases, response_time, suppressed
from .onset import ONSET_K, Onset, OnsetParams, accel_envelope, detect_onset, select_axis
from .paper import PAPER, PAPER_SUCCESS, Reported, paper_value
from .report import SUMMARY_COLUMNS, comparison_markdown, summarize, terminal_table, write_csv
from .trial import RESULT_COLUMNS, TrialRow, TrialStreams, analyse_trial

__all__ = [
    "SlipEvent", "segment_events",
    "Activity", "controller_activity", "increases", "response_time", "suppressed",
    "ONSET_K", "Onset", "OnsetParams", "accel_envelope", "detect_onset", "select_axis",
    "PAPER", "PAPER_SUCCESS", "Reported", "paper_value",
    "SUMMARY_COLUMNS", "comparison_markdown", "summarize", "terminal_table", "write_csv",
    "RESULT_COLUMNS", "TrialRow", "TrialStreams", "analyse_trial",
]

"""results.csv, summary.csv, the terminal table and report.md (one definition of each).

Rows are :class:`~slipreflex.analysis.trial.TrialRow` objects or dicts with the same keys
(a results.csv read back); no data-frame library is needed. The prose of report.md (the
run's setup, the figure captions, the discussion) is here too, every number in it read from
its one definition.

Examples
--------
>>> rows = [{"experiment": "drop", "bottle": "TR", "method": "dath", "trial": i,
...          "response_ms": 50.0 + i, "total_ms": 300.0, "success": i < 2,
...          "onset_error_ms": 3.0, "n_events": 1} for i in range(3)]
>>> s = summarize(rows)[0]
>>> s["response_mean_ms"], s["response_n"], round(s["trial_success_rate"], 3)
(51.0, 3, 0.667)
"""

from __future__ import annotations

from .prose import (
    GRIP_CAPTION,
    SUCCESS_CAPTION,
    bars_caption,
    discussion_text,
    paper_figure,
    setup_lines,
    trial_caption,
    zoom_caption,
)
from .prose import LATE_ONSET_MS as LATE_ONSET_MS  # public outside __all__, importable from here as before
from .tables import (
    NOT_COMPARED,
    SUMMARY_COLUMNS,
    comparison_markdown,
    differences,
    fmt_mean_sd,
    group_key_order,
    onset_markdown,
    pour_slips_markdown,
    read_csv,
    report_markdown,
    success_markdown,
    summarize,
    terminal_table,
    void,
    void_notice,
    write_csv,
)

__all__ = ["SUMMARY_COLUMNS", "summarize", "void", "void_notice", "NOT_COMPARED", "write_csv", "read_csv",
           "terminal_table",
           "comparison_markdown", "success_markdown", "onset_markdown", "pour_slips_markdown",
           "differences",
           "report_markdown", "fmt_mean_sd", "group_key_order", "setup_lines", "discussion_text",
           "trial_caption", "zoom_caption", "bars_caption", "SUCCESS_CAPTION", "GRIP_CAPTION", "paper_figure"]


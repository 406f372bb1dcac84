"""report.md's prose reads every number from its definition, so it follows the run's options."""

from __future__ import annotations

from slipreflex.analysis.report import discussion_text, setup_lines, summarize
from slipreflex.analysis.trial import TrialRow
from slipreflex.reproduce.experiments import ReproduceConfig, ReproduceResult


def _rows():
    rows = []
    for e in ("drop", "pour"):
        for m in ("dath", "fixed", "nmsd", "swt"):
            for b in ("TR", "TX"):
                rows.append(TrialRow(
                    experiment=e, bottle=b, method=m, trial=0, seed=1, event=0, n_events=1,
                    onset_s=1.0, true_onset_s=0.998, onset_error_ms=2.0, response_ms=60.0 if b == "TX" else 80.0,
                    total_ms=100.0, n_increases=2, rise=30.0, success=True, load_at_onset=190.0,
                    true_slip_ms=20.0, true_slip_mm=4.0, fell_out_s=float("nan")))
    return rows


def _result(**config):
    rows = _rows()
    return ReproduceResult(ReproduceConfig(**config), rows, summarize(rows), {"nmsd": 12.0, "swt": 0.02},
                           {}, 1.0, 1)


def test_prose_follows_the_options():
    text = " ".join(setup_lines(_result(rest_k=3.5, swt_persist=4, drop_mass_kg=0.02, pour_volume_ml=100.0))
                    + discussion_text(_result(rest_k=3.5, swt_persist=4, drop_mass_kg=0.02,
                                              pour_volume_ml=100.0)))
    assert "(3.5 sd of the method's statistic" in text and ": 3.5 sd of each method's own statistic" in text
    assert " 5 sd of" not in text
    assert "persistence 4 samples (11 ms)" in text and "for 11 ms after the crossing" in text
    assert "drop: 20 g" in text and "simulated 20 g drop" in text and "10 g" not in text
    assert "pour: 100 ml" in text
    default = " ".join(setup_lines(_result()) + discussion_text(_result()))
    assert "(5 sd of the method's statistic" in default and "persistence 0 samples (0 ms)" in default
    assert "simulated 10 g drop" in default and "decides at the crossing" in default and "to stay over" not in default
    assert "45 ms per detection" in default and "48 ms window" in default


def test_prose_uses_the_method_labels_and_typed_rows():
    text = " ".join(discussion_text(_result()))
    assert "In the pours: DATH 100% of 2, fixed 100% of 2, NMSD 100% of 2, SWT-SD 100% of 2" in text
    assert "**Bottles.** DATH's mean response by bottle, fastest first: drop: TX 60 ms, TR 80 ms" in text


def test_prose_from_rows_read_back_from_csv_is_the_same(tmp_path):
    from slipreflex.analysis.report import read_csv, write_csv
    from slipreflex.analysis.trial import RESULT_COLUMNS

    res = _result()
    back = ReproduceResult(res.config, read_csv(write_csv(tmp_path / "r.csv", res.rows, RESULT_COLUMNS)),
                           res.summary, res.thresholds, {}, 1.0, 1)
    assert discussion_text(back) == discussion_text(res)


def test_pour_responses_say_none_for_a_method_that_never_responded_and_explain_only_what_happened():
    import dataclasses

    rows = [dataclasses.replace(r, response_ms=float("nan")) if (r.experiment, r.method) == ("pour", "swt") else r
            for r in _rows()]
    res = ReproduceResult(ReproduceConfig(), rows, summarize(rows), {"nmsd": 12.0, "swt": 0.02}, {}, 1.0, 1)
    text = " ".join(discussion_text(res))
    assert "SWT-SD none (never responded)" in text and "nan" not in text
    assert "NMSD commands on the very sample" not in text        # NMSD was not faster here
    fast = [dataclasses.replace(r, response_ms=10.0) if (r.experiment, r.method) == ("pour", "nmsd") else r
            for r in rows]
    res = ReproduceResult(ReproduceConfig(), fast, summarize(fast), {"nmsd": 12.0, "swt": 0.02}, {}, 1.0, 1)
    assert "NMSD commands on the very sample" in " ".join(discussion_text(res))


def test_onset_paragraph_reports_each_experiment_and_explains_late_pour_onsets_only_when_there_are_some():
    import dataclasses

    text = " ".join(discussion_text(_result()))
    assert "drop: median absolute error 2.0 ms" in text and "0 of 8 found more than 100 ms after" in text
    assert "creeps before it accelerates" not in text
    rows = [dataclasses.replace(r, onset_error_ms=1274.0) if (r.experiment, r.trial) == ("pour", 0) else r
            for r in _rows()]
    res = ReproduceResult(ReproduceConfig(), rows, summarize(rows), {"nmsd": 12.0, "swt": 0.02}, {}, 1.0, 1)
    late = " ".join(discussion_text(res))
    assert "pour: median absolute error 1274.0 ms, largest 1274 ms, 8 of 8 found more than 100 ms" in late
    assert "creeps before it accelerates" in late

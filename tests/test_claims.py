"""The paper's claims judged from hand-made tables: every claim holds, fails and is untestable."""

import math

import pytest

from slipreflex.analysis import claims as C
from slipreflex.analysis.report import read_csv, write_csv
from slipreflex.analysis.trial import RESULT_COLUMNS
from slipreflex.sim.scan import ScanSummary

BOTTLES = ("TR", "DK", "TX")
NAN = float("nan")


def row(experiment, bottle, method, *, trial=0, event=0, n_events=1, response=50.0, total=300.0,
        success=True, ml=NAN):
    return {"experiment": experiment, "bottle": bottle, "method": method, "trial": trial, "seed": trial,
            "event": event, "n_events": n_events, "response_ms": response, "total_ms": total,
            "success": success, "load_at_onset": ml}


def paper_like():
    """A table on which every row-judged claim holds (the paper's story, idealized)."""
    rows = []
    drop_resp = {"dath": {"TR": 50, "DK": 80, "TX": 30}, "fixed": {"TR": 55, "DK": 90, "TX": 45},
                 "nmsd": {"TR": 60, "DK": 95, "TX": 50}}
    for b in BOTTLES:
        for k in range(10):
            rows.append(row("drop", b, "dath", trial=k, response=drop_resp["dath"][b], total=300.0,
                            success=k < (9 if b == "TX" else 7 if b == "DK" else 8)))
            rows.append(row("drop", b, "fixed", trial=k, response=drop_resp["fixed"][b], success=k < 4))
            rows.append(row("drop", b, "nmsd", trial=k, response=drop_resp["nmsd"][b], total=650.0,
                            success=k < 5))
    pour_resp = {"dath": {"TR": 60, "DK": 70, "TX": 40}, "swt": {"TR": 62, "DK": 73, "TX": 45},
                 "nmsd": {"TR": 100, "DK": 100, "TX": 90}, "fixed": {"TR": 140, "DK": 150, "TX": 60}}
    for m, by in pour_resp.items():
        for b in BOTTLES:
            for k in range(4):
                n = 2 if k < 3 else 1
                for e, ml in list(zip(range(n), (205.0, 410.0))):
                    rows.append(row("pour", b, m, trial=k, event=e, n_events=n, response=by[b], ml=ml))
    return rows


def scan_summary(white=(0.35, 0.45), black=(3.32, 3.345), gaps=(0.09, 0.1), spikes=(100, 300)):
    sp = {("fixed", r): gaps[0] for r in ("white", "black")}
    sp.update({("dath", r): gaps[1] for r in ("white", "black")})
    return ScanSummary(ranges={"white": white, "black": black},
                       spikes={"fixed": spikes[0], "dath": spikes[1]}, spikes_in={}, min_spacing_mm=sp)


def verdicts(rows, scan=None):
    return {r.number: r.verdict for r in C.judge(rows, scan)}


def test_every_claim_holds_on_the_paper_like_table():
    v = verdicts(paper_like(), scan_summary())
    assert v == {n: C.HOLDS for n in range(1, 11)}


def test_every_claim_is_untestable_on_an_empty_table():
    assert set(verdicts([]).values()) == {C.NOT_TESTABLE}


def test_csv_strings_judge_like_floats(tmp_path):
    rows = paper_like()
    p = write_csv(tmp_path / "r.csv", rows, RESULT_COLUMNS)
    assert [r.numbers for r in C.judge(read_csv(p))] == [r.numbers for r in C.judge(rows)]


def _replace(rows, pred, **kw):
    return [{**r, **kw} if pred(r) else r for r in rows]


@pytest.mark.parametrize("number, change", [
    (3, lambda rs: _replace(rs, lambda r: r["experiment"] == "drop" and r["method"] == "fixed"
                            and r["bottle"] == "DK", response_ms=80.0)),        # equal: not faster
    (4, lambda rs: _replace(rs, lambda r: r["experiment"] == "drop" and r["method"] == "dath",
                            success=True)),                                      # 100 % is not about 80 %
    (4, lambda rs: _replace(rs, lambda r: r["experiment"] == "drop" and r["method"] == "fixed"
                            and r["trial"] < 5, success=True)),                  # 50 % is not under 50 %
    (5, lambda rs: _replace(rs, lambda r: r["method"] == "nmsd" and r["experiment"] == "drop",
                            total_ms=301.0)),
    (6, lambda rs: _replace(rs, lambda r: r["experiment"] == "pour" and r["method"] == "dath"
                            and r["trial"] == 0 and r["bottle"] == "TR", success=False)),
    (6, lambda rs: _replace(rs, lambda r: r["experiment"] == "pour" and r["event"] == 0,
                            load_at_onset=140.0)),                               # first slip not near 200
    (7, lambda rs: _replace(rs, lambda r: r["experiment"] == "pour" and r["method"] == "swt"
                            and r["bottle"] == "TR", response_ms=101.0)),
    (8, lambda rs: _replace(rs, lambda r: r["method"] == "dath" and r["bottle"] == "DK"
                            and r["experiment"] == "drop", response_ms=85.0)),   # strict: 85 is not under
    (9, lambda rs: _replace(rs, lambda r: r["method"] == "dath" and r["bottle"] == "TR"
                            and r["experiment"] == "pour", response_ms=75.0)),
    (10, lambda rs: _replace(rs, lambda r: r["method"] == "dath" and r["bottle"] == "TR"
                             and r["experiment"] == "drop", success=True)),      # TX no longer most successful
])
def test_a_claim_fails_when_its_numbers_break_it(number, change):
    v = verdicts(change(paper_like()))
    assert v[number] == C.FAILS
    # the change breaks this claim only
    assert {n for n, x in v.items() if x == C.FAILS} == {number}


def test_tolerances_are_the_documented_ones():
    rows = paper_like()
    r4 = {r.number: r for r in C.judge(rows)}[4]
    assert "DATH 80%" in r4.numbers and "fixed 40%" in r4.numbers
    assert C.ABOUT_RATE_POINTS == pytest.approx(0.10) and "±10" in r4.tolerance
    nm = _replace(rows, lambda r: r["method"] == "nmsd" and r["experiment"] == "drop", total_ms=899.0)
    assert verdicts(nm)[5] == C.HOLDS                       # 899 / 300 = 3.0
    nm = _replace(rows, lambda r: r["method"] == "nmsd" and r["experiment"] == "drop", total_ms=901.0)
    assert verdicts(nm)[5] == C.FAILS
    far = _replace(rows, lambda r: r["experiment"] == "pour" and r["event"] == 1, load_at_onset=449.0)
    assert verdicts(far)[6] == C.HOLDS
    far = _replace(rows, lambda r: r["experiment"] == "pour" and r["event"] == 1, load_at_onset=451.0)
    assert verdicts(far)[6] == C.FAILS


@pytest.mark.parametrize("number, keep", [
    (3, lambda r: not (r["experiment"] == "drop" and r["bottle"] == "TX")),
    (4, lambda r: r["method"] != "fixed"),
    (5, lambda r: r["method"] != "nmsd"),
    (6, lambda r: r["experiment"] != "pour"),
    (7, lambda r: r["method"] != "swt"),
    (8, lambda r: r["method"] != "dath"),
    (9, lambda r: r["bottle"] != "DK"),
    (10, lambda r: r["bottle"] != "TR"),
])
def test_a_claim_is_untestable_without_its_cells(number, keep):
    v = verdicts([r for r in paper_like() if keep(r)])
    assert v[number] == C.NOT_TESTABLE


def test_untestable_when_the_values_are_missing():
    rows = _replace(paper_like(), lambda r: r["experiment"] == "drop" and r["method"] == "fixed",
                    response_ms=NAN)
    res = {r.number: r for r in C.judge(rows)}
    assert res[3].verdict == C.NOT_TESTABLE and "fixed TR" in res[3].numbers


def test_scan_claims():
    assert verdicts([], scan_summary(white=(0.25, 0.45)))[1] == C.FAILS
    assert verdicts([], scan_summary(white=(0.297, 0.503)))[1] == C.HOLDS     # within one LSB
    assert verdicts([], scan_summary(gaps=(0.09, 0.003)))[2] == C.FAILS
    assert verdicts([], scan_summary(gaps=(0.082, 0.09)))[2] == C.HOLDS       # about: >= 90 %
    assert verdicts([], scan_summary(spikes=(300, 300)))[2] == C.FAILS
    s = ScanSummary(ranges={"black": (3.3, 3.34)}, spikes={}, spikes_in={}, min_spacing_mm={})
    assert verdicts([], s)[1] == C.NOT_TESTABLE


def test_tables_print_every_claim():
    res = C.judge(paper_like(), scan_summary())
    md = C.claims_markdown(res)
    assert md.count("**holds**") == 10
    term = C.claims_terminal(res)
    assert term.splitlines()[0].endswith("10 hold, 0 fail, 0 not testable here")
    assert len(term.splitlines()) == 21 and "DATH vs fixed mean response" in term.splitlines()[6]


def test_window_phase_sd_is_uniform_phase_over_the_window():
    assert C.window_phase_sd_ms(16, 1000.0 / 3.0) == pytest.approx(48.0 / math.sqrt(12))
    assert C.window_phase_sd_ms(8, 1000.0) == pytest.approx(8.0 / math.sqrt(12))


def test_capacity_formulas():
    g = 9.80665
    assert C.first_slip_capacity_n(0.04, 200.0, rate_l_min=0.0) == pytest.approx(0.24 * g)
    # no drop height: slip-out needs capacity at most r times the total weight
    assert C.drop_slipout_capacity_n(0.04, 0.01, 0.0, 0.03, 1.0) == pytest.approx(0.05 * g)
    assert C.drop_slipout_capacity_n(0.04, 0.01, 0.03, 0.03, 2.0) == pytest.approx(2 * 0.06 * g)


def test_contradictions_of_the_paper():
    items = {c.topic: c for c in C.contradictions()}
    cap = items["static capacity: drop slip-outs vs the first pour slip"]
    assert cap.inconsistent and "2.38 N" in cap.finding and "The simulated plant agrees" in cap.finding
    assert items["pour totals: fixed and DATH identical"].finding.startswith("6 of 6")
    sd = items["response sd below the window's phase"]
    assert sd.inconsistent and "13.9 ms" in sd.finding and "drop TX DATH 4.16" in sd.finding
    assert "claim 8 on the paper's own table" in items and "claim 9 on the paper's own table" in items
    assert "claim 3 on the paper's own table" not in items
    # a first slip at 50 ml would be consistent with a drop slip-out
    assert not C.contradictions(first_slip_ml=50.0, simulate=False)[0].inconsistent
    assert C.contradictions_markdown(list(items.values())).count("(inconsistent)") == len(items)


@pytest.mark.slow
def test_report_and_terminal_carry_the_claims(tmp_path):
    from slipreflex.analysis.outputs import write_outputs
    from slipreflex.experiments import ReproduceConfig, run_reproduce

    res = run_reproduce(ReproduceConfig(trials=1, bottles=("TX",), methods=("dath",), experiments=("drop",)),
                        jobs=1, progress=False, plots=False)
    md = write_outputs(res, tmp_path)["report"].read_text()
    assert "## The paper's claims, judged on this run" in md and "## Where the paper contradicts itself" in md
    verdicts = C.judge_run(res.rows, seed=res.config.seed)
    assert md.count("| **") == 10 and all(f"| **{r.verdict}** | {r.numbers} |" in md for r in verdicts)
    assert verdicts[2].verdict == C.NOT_TESTABLE     # one bottle, one method: claim 3 cannot be judged


def test_missing_counts_do_not_break_the_judge():
    rows = [{**r, "n_events": "", "event": None} if r["experiment"] == "pour" else r for r in paper_like()]
    res = {r.number: r for r in C.judge(rows)}
    assert res[6].verdict == C.FAILS and "0% of" in res[6].numbers   # no slip counts: no two-slip pours


@pytest.mark.slow
def test_claims_command_judges_a_written_results_table_as_the_run_did(tmp_path, capsys):
    from slipreflex.analysis.claims import claims_terminal, judge_run
    from slipreflex.analysis.outputs import write_outputs
    from slipreflex.cli import main
    from slipreflex.experiments import ReproduceConfig, run_reproduce

    cfg = ReproduceConfig(trials=1, bottles=("TX",), methods=("fixed", "dath"), experiments=("drop",))
    res = run_reproduce(cfg, jobs=1, progress=False, plots=False)
    write_outputs(res, tmp_path)
    capsys.readouterr()
    assert main(["claims", str(tmp_path / "results.csv"), "--seed", str(cfg.seed)]) == 0
    out = capsys.readouterr().out
    assert claims_terminal(judge_run(res.rows, seed=cfg.seed)) in out


def test_claims_command_refuses_what_is_not_a_results_table(tmp_path, capsys):
    from slipreflex.cli import main

    (tmp_path / "summary.csv").write_text("experiment,bottle,method\ndrop,TR,dath\n")
    assert main(["claims", str(tmp_path / "summary.csv")]) == 2
    err = capsys.readouterr().err
    assert "summary.csv: not a results table: no column trial" in err and len(err.strip().splitlines()) == 1
    assert main(["claims", str(tmp_path / "none.csv")]) == 2
    assert "none.csv: no such results file" in capsys.readouterr().err
    bad = "experiment,bottle,method,trial,event,n_events,response_ms,total_ms,success\ndrop,TR,dath,x,0,1,5,5,True\n"
    (tmp_path / "bad.csv").write_text(bad)
    assert main(["claims", str(tmp_path / "bad.csv")]) == 2
    assert "bad.csv, data line 2" in capsys.readouterr().err

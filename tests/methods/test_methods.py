"""The method registry: one specification per method, used by every consumer."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from slipreflex import methods
from slipreflex.analysis.report import read_csv
from slipreflex.cli import main
from slipreflex.core.errors import ParameterError
from slipreflex.core.interfaces import Reflex
from slipreflex.methods.baselines import NMSD, SWTSD
from slipreflex.methods.chain import SlipReflex
from slipreflex.reproduce.experiments import ReproduceConfig


def test_the_paper_methods_in_one_order_with_their_specs():
    assert methods.names(paper=True) == ("dath", "fixed", "nmsd", "swt")
    assert methods.names()[:4] == methods.names(paper=True)
    assert ReproduceConfig().methods == methods.names(paper=True)
    assert [methods.get(m).ramp for m in ("dath", "fixed", "nmsd", "swt")] == [False, False, True, True]
    assert [methods.get(m).input_kind for m in ("dath", "nmsd")] == ["slip", "tactile"]
    assert methods.calibrated()[:2] == ("nmsd", "swt")
    assert methods.get("fixed").rest_statistic is None


@pytest.mark.parametrize("name", ["dath", "DATH", "Dath", "nMsD"])
def test_names_match_in_any_case(name):
    assert methods.canonical(name) == name.strip().lower()
    assert ReproduceConfig(methods=(name,)).methods == (name.strip().lower(),)


def test_make_builds_each_kind_with_context_and_overrides():
    ctx = methods.MethodContext(thresholds={"nmsd": 40.0, "swt": 0.02}, speed=300.0,
                                options={"swt_persist": 3})
    d = methods.make("dath", p0=210.0, context=ctx)
    assert isinstance(d, SlipReflex) and d.params.dath and d.params.p0 == 210.0
    assert not methods.make("fixed").params.dath
    n = methods.make("nmsd", p0=100.0, context=ctx)
    assert isinstance(n, NMSD) and n.params.threshold == 40.0 and n.params.speed == 300.0
    s = methods.make("swt", context=ctx, persist=5)          # a keyword beats the context
    assert isinstance(s, SWTSD) and s.params.persist == 5 and s.params.threshold == 0.02
    assert methods.make("swt", context=ctx).params.persist == 3
    for m in methods.names():
        assert isinstance(methods.make(m, threshold=1.0) if methods.get(m).rest_statistic
                          else methods.make(m), Reflex)
    with pytest.raises(ParameterError, match="nmsd needs a threshold"):
        methods.make("nmsd")
    with pytest.raises(ParameterError, match=r"^method: unknown 'nope' \(known: dath, fixed"):
        methods.make("nope")
    with pytest.raises(ParameterError, match="unknown"):
        methods.make("dath", gain=3.0)


def test_specs_are_validated_and_registration_is_guarded():
    good = dict(name="x", label="X", input_kind="slip", fs=100.0, build=lambda p0, ctx: None)
    for bad in (dict(name="X y"), dict(name=""), dict(input_kind="audio"), dict(fs=0.0),
                dict(build=None), dict(ramp=1), dict(label="")):
        with pytest.raises(ParameterError):
            methods.MethodSpec(**{**good, **bad})
    with pytest.raises(ParameterError, match="already registered"):
        methods.register(methods.get("dath"))
    with pytest.raises(ParameterError, match="MethodSpec"):
        methods.register("dath")


def test_specs_of_built_in_methods_pickle_for_worker_processes():
    for m in methods.names():
        spec = pickle.loads(pickle.dumps(methods.get(m)))
        assert spec.name == m and spec.build(100.0, methods.MethodContext(thresholds={m: 1.0}, method=m)).fs > 0


def test_detections_are_drawn_from_the_spec():
    rng = np.random.default_rng(0)
    volts = 0.4 + np.r_[np.zeros(100), 0.05 * np.sin(np.arange(200) / 3.0)]
    d = methods.get("dath").detections(methods.make("dath"), volts)
    assert d.sensor.shape == volts.shape and d.events.dtype == bool and d.events.any()
    frames = rng.normal(1.0, 0.001, (200, 4, 4))
    frames[120:, 0, 0] -= 0.5                              # a force step (NMSD) ...
    frames[120:, 1, 1] -= 0.05 * np.arange(80)             # ... and a ramp (SWT-SD)
    for m in ("nmsd", "swt"):
        r = methods.make(m, threshold=0.05 if m == "swt" else 20.0)
        d = methods.get(m).detections(r, frames)
        assert d.sensor.shape == (200,) and d.events[110:140].any() and not d.events[:100].any()


@pytest.fixture
def user_method():
    spec = methods.chain_method("dath-d4", "DATH, D = 4", dath=True, dath_samples=4)
    methods.register(spec)
    yield spec
    methods.unregister(spec.name)


@pytest.mark.slow
def test_a_user_registered_method_runs_in_reproduce_and_its_tables(user_method, tmp_path):
    assert methods.make("Dath-D4").params.dath_samples == 4
    out = tmp_path / "r"
    assert main(["reproduce", "--trials", "1", "--bottles", "TX", "--experiments", "drop",
                 "--methods", "DATH-D4,Dath", "--out", str(out), "--jobs", "2", "--no-progress",
                 "--no-figures", "--after", "0.5"]) == 0
    rows = read_csv(out / "results.csv")
    assert [r["method"] for r in rows] == ["dath", "dath-d4"]      # the one method order
    assert all(r["response_ms"] != "" for r in rows)
    md = (out / "report.md").read_text()
    assert "DATH, D = 4 ours" in md


def test_unknown_method_on_the_command_line_is_one_line(capsys):
    with pytest.raises(SystemExit):
        main(["reproduce", "--methods", "dath,bogus"])
    err = capsys.readouterr().err
    assert "bogus" in err and "known: dath, fixed, nmsd, swt" in err


def test_installed_packages_add_methods_through_entry_points(tmp_path, monkeypatch):
    import importlib.metadata as md

    (tmp_path / "my_reflexes.py").write_text(
        "from slipreflex import methods\n"
        "SPECS = [methods.chain_method('dath-d2', 'DATH, D = 2', dath=True, dath_samples=2)]\n"
        "def broken():\n    return ['not a spec']\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    good = md.EntryPoint(name="mine", value="my_reflexes:SPECS", group=methods.ENTRY_POINT_GROUP)
    monkeypatch.setattr(md, "entry_points", lambda group: [good] if group == methods.ENTRY_POINT_GROUP else [])
    monkeypatch.setattr(methods.METHODS, "_group_read", False)
    try:
        assert "dath-d2" in methods.names()                  # loaded on first use
        assert methods.load_plugins() == ()                   # once per process
        assert methods.make("DATH-D2").params.dath_samples == 2
        assert ReproduceConfig(methods=("dath-d2",)).methods == ("dath-d2",)
    finally:
        methods.unregister("dath-d2")
    bad = md.EntryPoint(name="oops", value="my_reflexes:broken", group=methods.ENTRY_POINT_GROUP)
    monkeypatch.setattr(md, "entry_points", lambda group: [bad])
    monkeypatch.setattr(methods.METHODS, "_group_read", False)
    with pytest.raises(ParameterError, match=r"method plugin 'oops' \(my_reflexes:broken\): gave 'not a spec'"):
        methods.load_plugins()

"""The paper's claims in its own words, judged part by part from a run's results, each verdict with its reason.

Each of the paper's eleven claims (``docs/method.md``, "The paper's claims") is a
:class:`Claim`: the paper's sentence (:attr:`Claim.quote`, its short form
:attr:`Claim.text` for tables), where it is (:attr:`Claim.where`), the reading
judged, and a judge function over a :class:`ClaimInput` (the per-slip result rows
of a run, the characterization scan, the plant, a measured scan if one is given).
The judge returns the claim's **parts**; :func:`judge` returns one
:class:`ClaimResult` per claim, its class derived from its parts.

Classes (:data:`VERDICTS`): ``holds``; ``fails-definition`` (the method's
equations or the paired design make it impossible); ``fails-paper`` (the paper's
own table violates it as stated); ``fails-plant`` (the interval lies on the wrong
side of the criterion on this plant); ``depends-plant`` (a study: it holds on
some plausible plants and fails on others); ``unresolved`` (the interval
straddles the criterion); ``not-decidable`` (the run lacks what decides it, or
the quantity is an input the simulator was calibrated to: the part's
``qualifier`` says "calibrated input").

**The class of a claim from its parts.** Every part is judged and reported with
its own class (``claim_parts.csv``). A part is *primary* when it belongs to the
reading the paper's own summary gives (abstract, conclusion); the others are
alternative readings, reported beside it. A claim's class is the conjunction of
its primary parts: the first class, in the order of :data:`VERDICTS`, among
them (a definition beats the paper's numbers, which beat the plant; noise beats
a missing cell; "holds" needs every primary part). A secondary part never sets
the claim's class, and every part that holds is printed as holding.

**Statistics** (:mod:`slipreflex.analysis.stats`): every slip is a trial,
clustered by its trial (a pour's slips share a pour); intervals are cluster
bootstraps, paired where two methods faced the same trial seeds; a slip a
method never answered within the cutoff is a censored trial, and a comparison
with one uses the censoring-aware probabilistic index (non-response ranks
slowest) instead of a mean. A comparison is one-sided where the paper is ("less
than", "more than twice"): it holds when the whole interval lies on the claimed
side of the criterion, fails when it lies wholly on the other, and is unresolved
otherwise. The level of every interval is set by the replication design, one constant
boundary over its looks (:func:`looks_level`): with the truth on the criterion a decisive class comes
with probability at most 5 % over every look the replication may take.

Examples
--------
>>> rows = [{"experiment": "drop", "bottle": b, "method": m, "trial": k, "seed": k, "event": 0,
...          "n_events": 1, "response_ms": r + k, "total_ms": 100.0, "success": True}
...         for b in ("TR", "DK", "TX") for k in range(6) for m, r in (("dath", 40.0), ("fixed", 50.0))]
>>> res = {c.number: c for c in judge(rows)}
>>> res[3].verdict, [p.label for p in res[3].parts][:2]
('holds', ['TR', 'DK'])
>>> res[1].verdict, res[1].qualifier
('not-decidable', 'calibrated input')
"""

from __future__ import annotations

import csv
import functools
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

# The chain's method names, as before the split (tests and scripts read them from here).
from ...methods import DATH, FIXED
from ...methods import NMSD as NMSD
from ...methods import SWT as SWT
from ...methods import names as method_names

# Public names outside __all__, importable from here as before the split.
from .drop import DROP_ASSUMPTIONS as DROP_ASSUMPTIONS
from .drop import (
    STATIC_OVER_KINETIC_MAX,
    DropBounds,
    drop_bounds,
    drop_momentum_capacity_n,
    drop_slipout_capacity_n,
    first_slip_capacity_n,
)
from .findings import Contradiction, claims_section, contradictions, contradictions_markdown, window_phase_sd_ms
from .judging import CLAIMS, _combine, tilt_and_taper
from .judging import PHYSICS as PHYSICS
from .judging import POUR_ORDER as POUR_ORDER
from .judging import _compare as _compare
from .tables import (
    CLAIMS_CSV_COLUMNS,
    PARTS_CSV_COLUMNS,
    claims_markdown,
    claims_terminal,
    explain,
    parts_markdown,
    read_claims_csv,
    write_claims_csv,
    write_parts_csv,
)
from .verdicts import (
    BOOTSTRAP_SEED,
    CALIBRATED_INPUT,
    CENTRAL,
    CONFIDENCE,
    DECISIVE,
    DEPENDS_PLANT,
    FAILING,
    FAILS_DEFINITION,
    FAILS_PAPER,
    FAILS_PLANT,
    HOLDS,
    LENGTH_TOL_MM,
    LOOKS,
    MOST,
    NEAR_ML,
    NOT_DECIDABLE,
    REPLICATES_MAX,
    TIME_TOL_MS,
    TOLERANCES,
    UNDER_MS,
    UNRESOLVED,
    VERDICTS,
    VOLT_TOL,
    Claim,
    ClaimInput,
    ClaimResult,
    Part,
    Reading,
    _num,
    about_rate_band,
    difference_interval,
    looks_level,
    mean_interval,
    median_interval,
    proportion_interval,
    ratio_interval,
    stated_tolerance,
)
from .verdicts import INF as INF
from .verdicts import PAPER_DROP_TRIALS as PAPER_DROP_TRIALS

__all__ = [
    "HOLDS", "FAILS_DEFINITION", "FAILS_PAPER", "FAILS_PLANT", "DEPENDS_PLANT", "UNRESOLVED", "NOT_DECIDABLE",
    "VERDICTS", "FAILING", "DECISIVE", "CALIBRATED_INPUT", "CONFIDENCE", "CENTRAL", "BOOTSTRAP_SEED", "VOLT_TOL",
    "TIME_TOL_MS", "LENGTH_TOL_MM", "NEAR_ML", "MOST", "UNDER_MS", "TOLERANCES", "stated_tolerance", "Reading",
    "Part", "Claim", "ClaimInput", "ClaimResult", "CLAIMS", "CLAIMS_CSV_COLUMNS", "PARTS_CSV_COLUMNS", "judge",
    "judge_run", "scan_ensemble_for", "measured_scan", "write_claims_csv", "write_parts_csv", "read_claims_csv",
    "claims_section", "claims_markdown", "parts_markdown", "claims_terminal", "explain", "mean_interval",
    "difference_interval",
    "ratio_interval", "proportion_interval", "median_interval", "DropBounds", "drop_bounds", "Contradiction",
    "contradictions", "contradictions_markdown", "window_phase_sd_ms", "drop_slipout_capacity_n",
    "drop_momentum_capacity_n", "first_slip_capacity_n", "STATIC_OVER_KINETIC_MAX", "REPLICATES_MAX", "LOOKS",
    "looks_level", "plant_reading", "tilt_and_taper", "replicate_seed", "undecided_methods", "about_rate_band",
]


def undecided_methods(results: Sequence[ClaimResult]) -> tuple[str, ...]:
    """The methods whose trials decide the claims ``results`` leaves unresolved (what to replicate).

    Examples
    --------
    >>> r = ClaimResult(10, "t", UNRESOLVED, "", 0.0, -1.0, 1.0, "", "", "")
    >>> undecided_methods([r])
    ('dath',)
    >>> undecided_methods([])
    ()
    """
    by_number = {c.number: c for c in CLAIMS}
    wanted = {m for r in results if r.verdict == UNRESOLVED for m in by_number[r.number].methods}
    return tuple(m for m in method_names(paper=True) if m in wanted)


def replicate_seed(master: int, k: int) -> int:
    """Master seed of replicate ``k`` (1, 2, ...) of a run with master seed ``master``.

    Derived with ``numpy.random.SeedSequence`` so that replicates of nearby master seeds
    never share trials; the same ``(master, k)`` gives the same seed on every machine.

    Examples
    --------
    >>> replicate_seed(20191215, 1) == replicate_seed(20191215, 1) != replicate_seed(20191215, 2)
    True
    """
    if k < 1:
        raise ValueError(f"replicate k: {k} (replicates count from 1; 0 is the run itself)")
    return int(np.random.SeedSequence([int(master), int(k)]).generate_state(1, np.uint32)[0])




def judge(rows: Sequence[Any], scan: Any = None, plant: Any = None, *, measured: Any = None,
          reading: Reading | None = None) -> list[ClaimResult]:
    """Judge every claim of :data:`CLAIMS` from a run's rows, its scan ensemble and its plant.

    Parameters
    ----------
    rows : sequence of mapping
        Per-slip result rows (see :class:`ClaimInput`).
    scan : ScanEnsemble, optional
        The simulated characterization scan over texture seeds (claim 2).
    plant : Plant, optional
        The simulated plant (claim 4's bounds).
    measured : ScanEnsemble, optional
        A real or replayed scan (claim 1; :func:`measured_scan`).
    reading : Reading, optional
        The judge's choices (default: :class:`Reading`, one look).

    Returns
    -------
    list of ClaimResult
        One per claim, in order.

    Examples
    --------
    >>> [r.verdict for r in judge([])][:3]
    ['not-decidable', 'not-decidable', 'not-decidable']
    """
    ci = ClaimInput(list(rows), scan, plant, measured, reading or plant_reading(plant))
    return [_combine(c, c.judge(ci)) for c in CLAIMS]


def plant_reading(plant: Any, looks: int = 1) -> Reading:
    """The judge's reading a plant carries (a study draws the cutoff and tolerances), else the default.

    Examples
    --------
    >>> from slipreflex.sim.uncertain import plant_from_values
    >>> plant_reading(plant_from_values({"response_cutoff": 800.0})).cutoff_ms
    800.0
    >>> plant_reading(None) == Reading()
    True
    """
    got = dict(getattr(plant, "readings", None) or {})
    keys = ("cutoff_ms", "time_tol_ms", "near_ml")
    return Reading(**{k: float(got[k]) for k in keys if k in got}, looks=looks)


def scan_ensemble_for(seed: int, sensor: Any = None, n: int | None = None):
    """The scan ensemble a run judges claim 2 on: ``n`` texture seeds from ``seed`` (cached).

    Examples
    --------
    >>> len(scan_ensemble_for(3, n=2))
    2
    """
    from ...sim.scan import ENSEMBLE_SEEDS  # deferred: heavy (llvmlite, numba, scipy)

    return _ensemble(int(seed), sensor, int(ENSEMBLE_SEEDS if n is None else n))


@functools.lru_cache(maxsize=4)
def _ensemble(seed: int, sensor: Any, n: int):
    from ...sim.scan import scan_ensemble  # deferred: heavy (llvmlite, numba, scipy)

    return scan_ensemble(n, base=seed, sensor=sensor)


def measured_scan(path: str | Path):
    """A recorded scan (CSV with ``t``, ``position_mm`` and ``volts``, as ``slipreflex scan`` writes) as one entry.

    The paper's layout (:data:`slipreflex.sim.scan.PAPER_LAYOUT`) says where white and
    black lie along the path; the levels and spikes are found as for a simulated scan.
    Raises ``ValueError`` naming the file and what is wrong.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from slipreflex.sim.scan import scan
    >>> r = scan(seed=4)
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "scan.csv"
    >>> _ = p.write_text("t,position_mm,volts\\n" + "".join(
    ...     f"{float(a)!r},{float(b)!r},{float(c)!r}\\n" for a, b, c in zip(r.t, r.position * 1e3, r.volts)))
    >>> round(float(measured_scan(p).black_hi[0]), 2) > 3
    True
    """
    from ...sim.scan import PAPER_LAYOUT, ScanEnsemble, ScanResult  # deferred: heavy (numba kernels)

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"{path}: no such scan file")
    with path.open(newline="") as fh:
        reader = csv.DictReader(line for line in fh if not line.startswith("#"))
        gone = [c for c in ("t", "position_mm", "volts") if c not in (reader.fieldnames or ())]
        if gone:
            raise ValueError(f"{path}: not a scan recording: no column {', '.join(gone)}")
        cols: dict[str, list[float]] = {"t": [], "position_mm": [], "volts": []}
        for i, d in enumerate(reader, start=2):
            for k in cols:
                v = _num(d.get(k))
                if v != v:
                    raise ValueError(f"{path}, line {i}: {k} is not a number ({d.get(k)!r})")
                cols[k].append(v)
    t, pos, volts = (np.asarray(cols[k]) for k in ("t", "position_mm", "volts"))
    if t.size < 3 or not np.all(np.diff(t) > 0):
        raise ValueError(f"{path}: need at least 3 samples with increasing t")
    regions, start = [], 0.0
    for surface, length in PAPER_LAYOUT:
        name = surface if isinstance(surface, str) else surface.name
        regions.append((name, start, start + length))
        start += length
    fs = float(1.0 / np.median(np.diff(t)))
    speed = float((pos[-1] - pos[0]) * 1e-3 / (t[-1] - t[0]))
    a = ScanResult(t, pos * 1e-3, volts, regions, speed, fs).analyse()
    nan = (math.nan, math.nan)
    lv = {f"{r}_{e}": np.array([a.ranges.get(r, nan)[i]]) for r in ("white", "black")
          for i, e in enumerate(("lo", "hi"))}
    gaps = {m: [v for (mm, r), v in a.min_spacing_mm.items() if mm == m and r in ("white", "black") and v is not None]
            for m in (FIXED, DATH)}
    return ScanEnsemble(seeds=np.array([0]), step_mm=speed * 1e3 / fs, **lv,
                        fixed_gap=np.array([min(gaps[FIXED], default=math.nan)]),
                        dath_gap=np.array([min(gaps[DATH], default=math.nan)]),
                        fixed_spikes=np.array([a.spikes[FIXED]]), dath_spikes=np.array([a.spikes[DATH]]))


def judge_run(rows: Sequence[Any], *, seed: int = 0, plant: Any = None, scan_seeds: int | None = None,
              measured: Any = None, looks: int = LOOKS) -> list[ClaimResult]:
    """Judge the claims of a run: its rows, a scan ensemble of its slip sensor, its plant, the design's looks.

    The ensemble (:func:`scan_ensemble_for`: :data:`slipreflex.sim.scan.ENSEMBLE_SEEDS`
    texture seeds from ``seed``, with the plant's slip sensor) supplies claim 2; every
    interval is at the level of the replication design's ``looks`` (:func:`looks_level`).

    Examples
    --------
    >>> [r.verdict for r in judge_run([], seed=0, scan_seeds=4)][2]
    'not-decidable'
    """
    sensor = None if plant is None else plant.slip_sensor
    return judge(rows, scan_ensemble_for(seed, sensor, scan_seeds), plant, measured=measured,
                 reading=plant_reading(plant, looks))



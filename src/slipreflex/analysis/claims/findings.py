"""Findings about the paper's own numbers, and the claims section of report.md.

Re-exported by :mod:`slipreflex.analysis.claims`.

Examples
--------
>>> round(window_phase_sd_ms(), 1) > 0
True
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from ...core import hardware as hw
from ...methods import DATH, FIXED
from ...methods import label as _label
from ..paper import BOTTLE_ORDER, PAPER
from .drop import DROP_ASSUMPTIONS, drop_bounds
from .judging import CLAIMS
from .tables import _counts, claims_markdown, parts_markdown
from .verdicts import FAILS_PAPER, TOLERANCES, VERDICTS, ClaimInput, ClaimResult

__all__ = ["claims_section", "Contradiction", "contradictions", "contradictions_markdown", "window_phase_sd_ms"]


@dataclass(frozen=True)
class Contradiction:
    """One finding about the paper's own numbers.

    Attributes
    ----------
    topic : str
    finding : str
        What was computed, with the numbers, formulas and assumptions.
    inconsistent : bool
        True when the paper's numbers cannot all be true (under the assumptions named).

    Examples
    --------
    >>> Contradiction("t", "x", True).inconsistent
    True
    """

    topic: str
    finding: str
    inconsistent: bool


def window_phase_sd_ms(n: int = hw.WINDOW_N, fs: float = hw.DAQ_FS) -> float:
    """Sd (ms) a free-running window of ``n`` samples adds to a response time.

    The first command comes at the end of the window holding the first spike;
    with the slip's onset at a uniform phase inside a window of length
    ``T = n / fs``, that wait is uniform on [0, T): sd ``T / sqrt(12)``.

    Examples
    --------
    >>> round(window_phase_sd_ms(16, 1000 / 3), 2)
    13.86
    """
    return 1e3 * n / fs / math.sqrt(12.0)


def _bounds_item(plant: Any, first_slip_ml: float, simulate: bool) -> Contradiction:
    bounds = drop_bounds(plant, first_slip_ml)
    text = ("; ".join(b.text() for b in bounds) + ". Energy: C <= r[(M+m)g + mgh/d], no impact loss; momentum: "
            "C <= r[(M+m)g + m^2 g h/(d(M+m))], a fully inelastic impact, then sliding out against the grip; "
            "h = release height + bottle depth. Both assume " + DROP_ASSUMPTIONS + ".")
    if simulate:
        from ...sim import BOTTLES  # deferred: heavy (llvmlite, numba, scipy)
        from ...sim.calibration import drop_fall_capacity  # deferred: heavy (numba kernels)

        kw = None if plant is None else plant.rig_kwargs()
        sim = drop_fall_capacity((BOTTLES if plant is None else plant.bottles)["TR"], rig_kwargs=kw, iterations=8)
        text += (f" The simulated plant (open loop, sim.calibration.drop_fall_capacity) lets a 10 g drop knock TR "
                 f"out only below a capacity of {sim['capacity_g']:.0f} g, while its pour-calibrated grasp holds "
                 f"{sim['bottle_capacity_g']:.0f} g.")
    text += (" Under these assumptions the paper's drop slip-outs and its first pour slip near 200 ml cannot "
             "share one 0.8 N grasp; tilt or fingertips moving onto a tapering shoulder may change that.")
    return Contradiction("drop slip-outs beside the first pour slip (bounds, with their assumptions)", text,
                         not any(b.possible for b in bounds))


def _identical_totals() -> Contradiction:
    same, parts = 0, []
    for b in BOTTLE_ORDER:
        d, f = PAPER[("pour", "total_ms", b, DATH)], PAPER[("pour", "total_ms", b, FIXED)]
        hits = [fv is not None and math.floor(fv) == dv for dv, fv in ((d.mean, f.mean), (d.sd, f.sd))]
        same += sum(hits)
        parts.append(f"{b} DATH {d.text()} vs fixed {f.text()}")
    return Contradiction(
        "pour totals: fixed and DATH identical",
        f"{same} of {2 * len(BOTTLE_ORDER)} pour-total means and sds of DATH equal the fixed threshold's "
        f"truncated to whole ms ({'; '.join(parts)}); separate physical runs cannot agree to the digit",
        same == 2 * len(BOTTLE_ORDER))


def _window_sd() -> Contradiction:
    floor = window_phase_sd_ms()
    low = [(e, b, m, v.sd) for (e, metric, b, m), v in PAPER.items()
           if metric == "response_ms" and m in (FIXED, DATH) and v.sd is not None and v.sd < floor]
    cells = ", ".join(f"{e} {b} {_label(m)} {sd:g}" for e, b, m, sd in low)
    return Contradiction(
        "response sd below the window's phase",
        f"a free-running {hw.WINDOW_N}-sample window at {hw.DAQ_FS:.2f} Hz "
        f"({1e3 * hw.WINDOW_N / hw.DAQ_FS:.0f} ms) alone gives a response sd of "
        f"{floor:.1f} ms (T/sqrt(12), onset phase uniform); the paper reports less in "
        f"{len(low)} fixed/DATH cells ({cells} ms): only windows aligned to the perturbation allow it",
        bool(low))


def _own_table() -> list[Contradiction]:
    ci = ClaimInput([])
    out = []
    for c in CLAIMS:
        for p in c.judge(ci):
            if p.verdict == FAILS_PAPER:
                out.append(Contradiction(f"claim {c.number} on the paper's own table", f"{c.text}: {p.reason}", True))
    return out


def contradictions(first_slip_ml: float = 200.0, *, plant: Any = None, simulate: bool = True
                   ) -> list[Contradiction]:
    """What the paper's own numbers say about themselves: bounds, identical totals, sds, its table vs its claims.

    Parameters
    ----------
    first_slip_ml : float
        Volume at the paper's first pour slip (its Fig. 15: about 200 ml).
    plant : slipreflex.sim.uncertain.Plant, optional
        The simulated plant (default: the package's) whose open-loop drop is simulated.
    simulate : bool
        Also find, on the simulated plant, the largest capacity at which the
        drop still ends in complete slippage (about a second).

    Returns
    -------
    list of Contradiction

    Examples
    --------
    >>> [c.inconsistent for c in contradictions(simulate=False)][:3]
    [True, True, True]
    """
    return [_bounds_item(plant, first_slip_ml, simulate), _identical_totals(), _window_sd(), *_own_table()]


def contradictions_markdown(items: Sequence[Contradiction]) -> str:
    """The findings as a markdown list.

    Examples
    --------
    >>> contradictions_markdown([Contradiction("a", "b", True)])
    '- **a** (inconsistent): b'
    """
    return "\n".join(f"- **{c.topic}** ({'inconsistent' if c.inconsistent else 'consistent'}): {c.finding}"
                     for c in items)


def claims_section(results: Sequence[ClaimResult], items: Sequence[Contradiction] | None = None, *,
                   plant: Any = None) -> list[str]:
    """The report.md sections: the claims judged, the tolerances, the paper's own numbers.

    Examples
    --------
    >>> from slipreflex.analysis.claims import judge
    >>> claims_section(judge([]), [])[0]
    "## The paper's claims, judged on this run"
    """
    lines = ["## The paper's claims, judged on this run", "",
             "Each claim of the paper (docs/method.md) judged from this run's results.csv, a characterization "
             "scan over texture seeds and the plant (`slipreflex.analysis.claims`; the same table is in "
             f"claims.csv). Classes: {', '.join(VERDICTS)}. Count: {_counts(results)}.", "",
             claims_markdown(results), "",
             "Every part of every claim (claim_parts.csv; a claim's class is the first, in the order "
             + ", ".join(VERDICTS) + ", among its primary parts):", "", parts_markdown(results), "",
             "Tolerances (one definition each, none finer than the instrument or the paper's last digit): "
             + "; ".join(f"{k}: {v}" for k, v in TOLERANCES.items()) + ".", ""]
    items = contradictions(plant=plant) if items is None else items
    if items:
        lines += ["## The paper's own numbers", "",
                  "Computed from the paper's numbers (and the rig's geometry); reported, not chased.", "",
                  contradictions_markdown(items), ""]
    return lines

"""The paper's reported results, kept as data in one place (docs/method.md section 4).

``PAPER`` maps ``(experiment, metric, bottle, method)`` to a
:class:`Reported` value (mean and sd in ms, or a note where the paper gives
only words). Methods use the registry's names (:mod:`slipreflex.methods`;
their order and labels are defined there); experiments ``"drop"`` and ``"pour"``; metrics
``"response_ms"`` and ``"total_ms"``. ``PAPER_SUCCESS`` holds the success
rates the text states.

Examples
--------
>>> PAPER[("drop", "response_ms", "TR", DATH)].mean
50.0
>>> paper_value("pour", "total_ms", "TX", NMSD).text()
'630 ± 29'
>>> paper_value("drop", "response_ms", "TR", SWT) is None
True
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass

from ..methods import DATH, FIXED, NMSD, SWT

__all__ = ["PAPER_SCAN_VOLTS", "Reported", "PAPER", "PAPER_SUCCESS", "PAPER_NOTES", "paper_value",
           "EXPERIMENTS", "METRICS", "BOTTLE_ORDER", "bottle_key"]

EXPERIMENTS: tuple[str, ...] = ("drop", "pour")
METRICS: tuple[str, ...] = ("response_ms", "total_ms")
BOTTLE_ORDER: tuple[str, ...] = ("TR", "DK", "TX")


def bottle_key(bottle: str) -> int:
    """A paper bottle's position in :data:`BOTTLE_ORDER`; another bottle's key from its name (never 0-2).

    Keys the trial seeds of a bottle (:func:`slipreflex.reproduce.experiments.trial_seed`) and the
    order of results.csv, so neither depends on which other bottles run.

    Examples
    --------
    >>> bottle_key("DK"), bottle_key("JAR") > 2
    (1, True)
    """
    if bottle in BOTTLE_ORDER:
        return BOTTLE_ORDER.index(bottle)
    return (1 << 32) + zlib.crc32(bottle.encode())


@dataclass(frozen=True, slots=True)
class Reported:
    """One number of the paper: mean and sd in ms, or only a note.

    Examples
    --------
    >>> Reported(50.0, 6.48).text()
    '50 ± 6.48'
    >>> Reported(None, None, "faster than DATH").text()
    'faster than DATH'
    """

    mean: float | None
    sd: float | None
    note: str = ""

    def text(self) -> str:
        """Human-readable form, as the paper prints it.

        Examples
        --------
        >>> Reported(273.0, 22.51, "also 274.4").text()
        '273 ± 22.51 (also 274.4)'
        """
        if self.mean is None:
            return self.note
        s = f"{self.mean:g} ± {self.sd:g}"
        return f"{s} ({self.note})" if self.note else s


def _r(mean: float, sd: float, note: str = "") -> Reported:
    return Reported(float(mean), float(sd), note)


#: The paper's table (docs/method.md section 4), ms.
PAPER: dict[tuple[str, str, str, str], Reported] = {
    ("drop", "response_ms", "TR", DATH): _r(50, 6.48),
    ("drop", "response_ms", "TR", FIXED): _r(55, 9.16),
    ("drop", "response_ms", "DK", DATH): _r(88.2, 24),
    ("drop", "response_ms", "DK", FIXED): _r(93.75, 66),
    ("drop", "response_ms", "DK", SWT): Reported(None, None, "faster than DATH"),
    ("drop", "response_ms", "TX", DATH): _r(31.3, 4.16),
    ("drop", "response_ms", "TX", FIXED): _r(45, 4.24),
    ("drop", "total_ms", "TR", DATH): _r(298.5, 77.41),
    ("drop", "total_ms", "TR", NMSD): _r(661, 283),
    ("drop", "total_ms", "DK", DATH): _r(322.5, 48.15),
    ("drop", "total_ms", "DK", NMSD): _r(743, 396.5),
    ("drop", "total_ms", "TX", DATH): _r(273, 22.51, "also 274.4"),
    ("drop", "total_ms", "TX", NMSD): _r(769, 191),
    ("pour", "response_ms", "TR", DATH): _r(88, 30),
    ("pour", "response_ms", "TR", FIXED): _r(147.75, 48.45),
    ("pour", "response_ms", "TR", NMSD): _r(103, 59),
    ("pour", "response_ms", "TR", SWT): _r(86, 9),
    ("pour", "response_ms", "DK", DATH): _r(70, 29.4),
    ("pour", "response_ms", "DK", FIXED): _r(155, 101.52),
    ("pour", "response_ms", "DK", NMSD): _r(100, 17),
    ("pour", "response_ms", "DK", SWT): _r(73, 22),
    ("pour", "response_ms", "TX", DATH): _r(43, 30.34),
    ("pour", "response_ms", "TX", FIXED): _r(60, 30.9),
    ("pour", "total_ms", "TR", DATH): _r(509, 102),
    ("pour", "total_ms", "TR", FIXED): _r(509, 102.45),
    ("pour", "total_ms", "TR", NMSD): _r(792, 192),
    ("pour", "total_ms", "DK", DATH): _r(460, 168),
    ("pour", "total_ms", "DK", FIXED): _r(460, 168.47),
    ("pour", "total_ms", "DK", NMSD): _r(749, 281),
    ("pour", "total_ms", "TX", DATH): _r(411, 282),
    ("pour", "total_ms", "TX", FIXED): _r(411.66, 282.68),
    ("pour", "total_ms", "TX", NMSD): _r(630, 29),
}

#: Success rates stated in the text: (experiment, bottle or "all", method) -> text.
PAPER_SUCCESS: dict[tuple[str, str, str], str] = {
    ("drop", "all", DATH): "about 80 %",
    ("drop", "TX", DATH): "90 %",
    ("drop", "all", FIXED): "under 50 %",
    ("pour", "all", DATH): "100 %",
}

#: Other claims of the paper a reader may check against our run.
PAPER_NOTES: tuple[str, ...] = (
    "Whole-system response (DATH) under 85 ms; human grip reactions take 60-80 ms.",
    "Pours show two slips in most trials, near 200 ml and near 400 ml.",
    "SWT-SD was the fastest to react on the dark bottle (DK) in the drop.",
    "Fixed-threshold and DATH pour totals are identical in the paper (likely a copy in the source).",
)


def paper_value(experiment: str, metric: str, bottle: str, method: str) -> Reported | None:
    """The paper's value for one cell, or None when the paper does not report it.

    Examples
    --------
    >>> paper_value("drop", "total_ms", "DK", NMSD).mean
    743.0
    """
    return PAPER.get((experiment, metric, bottle, method))


#: The paper's characterization scan (section II, Figs. 6-9): the filtered slip-sensor output on the
#: white and on the black part of the test surface, volts (low, high).
PAPER_SCAN_VOLTS: dict[str, tuple[float, float]] = {"white": (0.3, 0.5), "black": (3.32, 3.35)}

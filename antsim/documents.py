"""What the source documents publish: the numbers a run's tables print beside its own.

F. Ghigo, *Pointing Calibration of the ESSCO 45-ft Antenna at Green Bank*, NRAO EDIR 288
(June 1990), and its Appendix A, E. B. Fomalont, *45-Foot Pointing and Efficiency* (memo of
8 March 1973), which is not in this repository. Each constant names its table or section;
``docs/facts.md`` lists where each is used and which test checks it. A run's report finds
its document by the scenario's name (:func:`reference_for`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

__all__ = ["FOMALONT1973", "FOMALONT1973_COEFFICIENTS", "FOMALONT1973_DATES",
           "FOMALONT1973_EFFICIENCY", "FOMALONT1973_SOURCES", "GHIGO1990", "GHIGO1990_GAIN_CURVE",
           "GHIGO1990_TABLE1_POINTS", "GHIGO1990_TABLE1_POSITIONS", "Reference", "reference_for"]


@dataclass(frozen=True)
class Reference:
    """A document's published fit, to print beside a run's.

    ``terms``: term -> (value, standard error or None), arcmin, in the run's term names;
    ``labels``: term -> the document's own name of it where that differs (Fomalont's C1, D5);
    ``fixed``: terms the document held fixed; ``table2``: fit -> (xel rms, el rms) arcsec
    and ``points``: fit -> number of points (the 1990 report's Table 2); ``source_points``:
    source -> points in fit A (its Table 1); ``rms_arcsec``: the document's single (xel, el)
    rms where it gives no Table 2.
    """

    citation: str
    terms: Mapping[str, tuple[float, float | None]]
    #: what a table calls the document's column ("report", "memo")
    column: str = "report"
    labels: Mapping[str, str] = field(default_factory=dict)
    fixed: tuple[str, ...] = ()
    table2: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    points: Mapping[str, int] = field(default_factory=dict)
    source_points: Mapping[str, int] = field(default_factory=dict)
    rms_arcsec: tuple[float, float] | None = None


#: Ghigo 1990, section V: relative gain against elevation, flat above 30 deg, 95% at 20 deg,
#: 90% at 10 deg; (elevation deg, relative gain), linear in between
GHIGO1990_GAIN_CURVE: tuple[tuple[float, float], ...] = (
    (10.0, 0.90), (20.0, 0.95), (30.0, 1.0), (90.0, 1.0))

#: Ghigo 1990, Table 1: the calibration sources at their B1950 positions, as printed
GHIGO1990_TABLE1_POSITIONS: dict[str, tuple[str, str]] = {
    "3C84": ("03:16:29.6", "41:19:52"), "Taurus A": ("05:31:31.0", "21:59:00"),
    "Orion A": ("05:32:49.0", "-05:25:15"), "3C273": ("12:26:33.3", "02:19:43"),
    "Virgo A": ("12:28:17.6", "12:40:02"), "W31": ("18:06:25.6", "-20:19:36"),
    "Cygnus A": ("19:57:44.4", "40:35:46"), "Cassiopeia A": ("23:21:09.0", "58:32:30"),
}

#: Fomalont 1973, introduction: the eight sources, in the memo's order and names ("3C274" is
#: the report's Virgo A), and the dates of the survey
FOMALONT1973_SOURCES = ("Tau A", "3C147.1", "3C274", "Cen A", "Sgr A", "W31", "Cyg A", "Cas A")
FOMALONT1973_DATES = ("1973-02-28", "1973-03-02")

#: Ghigo 1990, Table 1: points per source used in fit A (they add up to 282; its Tables 2
#: and section III give 285 for fit A)
GHIGO1990_TABLE1_POINTS: dict[str, int] = {
    "3C84": 22, "Taurus A": 34, "Orion A": 19, "3C273": 29, "Virgo A": 34, "W31": 27,
    "Cygnus A": 53, "Cassiopeia A": 64,
}

GHIGO1990 = Reference(
    citation="Ghigo 1990 (NRAO EDIR 288)",
    # Table 3, arcmin: value and std. err.
    terms={"W1": (-1.88, 0.15), "W2": (-0.17, 0.07), "W3": (-1.54, 0.06), "W4": (-2.16, 0.29),
           "W5": (0.80, 0.05), "W6": (12.24, 0.55), "W7": (1.62, 0.10), "W8": (-0.35, 0.09),
           "W9": (-3.35, 0.54), "W10": (-1.79, 0.71)},
    # Table 2: rms in dA cos E and dE (arcsec), and the points of each fit
    table2={"A": (23.0, 38.0), "B": (23.0, 35.0), "C": (28.0, 43.0), "D": (24.0, 40.0),
            "E": (18.0, 26.0), "F": (31.0, 41.0)},
    points={"A": 285, "B": 276, "C": 279, "D": 142, "E": 115, "F": 302},
    source_points=GHIGO1990_TABLE1_POINTS,
)


def _feed_terms(c6: float, c7_deg: float, d6: float, d7_deg: float) -> dict[str, float]:
    """Fomalont's C6 cos(f - C7) (dA cos E) and D6 cos(f - D7) (dE), arcmin, as the linear
    feed terms of controller/pointing/terms.py (HSCF, HSSF: dA cos E = -c cos F, -c sin F;
    HECF, HESF: dE = +c cos F, +c sin F; TPOINT's correction sign, minus the memo's)."""
    c7, d7 = math.radians(c7_deg), math.radians(d7_deg)
    return {"HSCF": c6 * math.cos(c7), "HSSF": c6 * math.sin(c7),
            "HECF": -d6 * math.cos(d7), "HESF": -d6 * math.sin(d7)}


#: Fomalont 1973 (Appendix A, section I): C1..C7 and D1..D7, arcmin (C7, D7 in degrees)
FOMALONT1973_COEFFICIENTS: dict[str, float] = {
    "C1": 1.03, "C2": -0.40, "C3": 0.94, "C4": 2.32, "C5": -5.24, "C6": 0.71, "C7": 152.0,
    "D1": 2.34, "D2": 0.68, "D3": 0.61, "D4": -7.00, "D5": 1.10, "D6": 0.76, "D7": 250.0,
}

#: Fomalont 1973, section II: efficiency (%) against elevation (deg) and azimuth (deg), S-band
#: (SR) and X-band (XL); the Cyg A point at 59 deg has no S-band value. "There is no
#: systematic changes of efficiency with elevation"; means 38.6 (S) and 37.6 (X).
FOMALONT1973_EFFICIENCY: tuple[tuple[str, float, float, float | None, float], ...] = (
    ("Cas A", 13.0, 338.0, 36.0, 41.0),
    ("Tau A", 23.0, 280.0, 38.0, 37.0),
    ("Cyg A", 33.0, 61.0, 38.0, 41.0),
    ("Cas A", 38.0, 41.0, 43.0, 39.0),
    ("Cyg A", 59.0, 73.0, None, 34.0),
    ("Tau A", 65.0, 235.0, 38.0, 34.0),
)

_F = FOMALONT1973_COEFFICIENTS
FOMALONT1973 = Reference(
    citation="Fomalont 1973 (1990 report, Appendix A), section I",
    column="memo",
    terms={**{w: (_F[c], None) for c, w in (("D1", "W1"), ("D2", "W2"), ("D3", "W3"),
                                            ("D4", "W4"), ("D5", "W5"), ("C1", "W6"),
                                            ("C2", "W7"), ("C3", "W8"), ("C4", "W9"),
                                            ("C5", "W10"))},
           **{k: (v, None) for k, v in _feed_terms(_F["C6"], _F["C7"], _F["D6"],
                                                     _F["D7"]).items()}},
    labels={"W1": "D1", "W2": "D2", "W3": "D3", "W4": "D4", "W5": "D5", "W6": "C1", "W7": "C2",
            "W8": "C3", "W9": "C4", "W10": "C5", "HSCF": "C6 cos C7", "HSSF": "C6 sin C7",
            "HECF": "-D6 cos D7", "HESF": "-D6 sin D7"},
    # "Refraction of 1'.1 was assumed in the solution" (comment 6)
    fixed=("W5",),
    # "The rms deviation in azimuth of a data point from the best fit is 0'.49; for
    # elevation the rms deviation is 0'.84"
    rms_arcsec=(0.49 * 60.0, 0.84 * 60.0),
)

#: scenario name -> its document (the run's report prints it beside the fits)
_BY_SCENARIO: dict[str, Reference] = {
    "ghigo1990": GHIGO1990,
    "fomalont1973_s": FOMALONT1973,
    "fomalont1973_x": FOMALONT1973,
}


def reference_for(scenario_name: str) -> Reference | None:
    """The document a scenario re-creates, or None."""
    return _BY_SCENARIO.get(scenario_name)

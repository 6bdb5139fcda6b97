"""Crane's eleven pointing coefficients C1..C11 of the NRAO 140-ft (Engineering Memo 147, 1981).

Crane (1981, section I) fitted "the 11 pointing coefficients ... following the procedure
outlined by Sebastian von Hoerner in Engineering Division Internal Report No. 102" and lists
them in Table 4 (arcmin) without their definitions; EDIR 102 was not found in any corpus we
could search (Maddalena 1992, "Proposed Changes to the Pointing Model for the 140-ft
Telescope", confirms only that the 140-ft's model of the time was von Hoerner's, 1976-77). The
memo itself fixes four things, which every definition here keeps:

* C1 and C6 are the terms a subreflector offset moves (section III: "causing changes in C1
  and C6"; 5.83' and -5.16' at 4990 MHz against ~2' and -1.7' in the other bands): the
  collimation of the beam, constant on the sky, in hour angle (C1) and declination (C6);
* C5 is 0.97-1.02 +- 0.01-0.02 in every band (Table 4): a dimensionless scale factor. The only
  pointing correction of an equatorial radio telescope that is "about 1" whatever the
  receiver is the refraction, so C5 scales the control program's refraction (the memo's
  "arcmin" unit then reads: the coefficient is C5 times the refraction of a reference
  atmosphere, and with R(E) about 1' cot E a scale of 1 is 1');
* the rms per point is given per axis (RA ~20", Dec ~10"), so the fits weight the axes
  separately.

Everything else is our choice (``docs/telescopes.md`` gives the evidence: with the runs'
schedules and noise, the standard errors of each candidate set against Table 4's, printed by
``benchmarks/crane1981.py``). Sign: "indicated minus true" (what the control program adds to
the catalogue position to command the axes), as NRAO's 45-ft model of the period (Ghigo
1990); as for Ghigo's W1..W10 (:mod:`controller.pointing.terms`) the basis functions are negated so
that a fitted coefficient is the number Crane would print. ``x = dH cos(dec)`` is the
cross-declination (on-sky) error, H the hour angle (positive West), phi the latitude.

The chosen definitions (``crane1981``):

| C | axis | function | physics |
|---|---|---|---|
| C1 | x | 1 | collimation in hour angle (moves with the subreflector) |
| C2 | x | sin(H) | tube flexure, hour-angle part (TPOINT's TF: x = TF cos(phi) sin H) |
| C3 | x | cos(H) cos(dec) | hour-angle encoder eccentricity, cosine (TPOINT's HCEC) |
| C4 | x | cos(H) sin(dec) | polar axis left or right of the pole (TPOINT's MA, hour-angle part) |
| C5 | both | R(E) / 1' | refraction scale (R: ERFA's radio refraction, reference atmosphere) |
| C6 | dec | 1 | declination zero and collimation (moves with the subreflector) |
| C7 | dec | cos(2H) | twice-per-turn error in hour angle (polar shaft, yoke) |
| C8 | dec | sin(dec) | declination encoder eccentricity, sine (TPOINT's DCES) |
| C9 | dec | cos(H) | polar axis elevation and yoke flexure (TPOINT's ME and FO) |
| C10 | dec | cos(H) sin(dec) | declination flexure with hour angle |
| C11 | dec | cos(phi) cos(H) sin(dec) - sin(phi) cos(dec) | tube flexure, declination part (TF) |

C9, C10 and C11 all vary as cos H, so they are strongly correlated: their standard errors are
the largest of the eleven, as in Table 4, and none of them "differed significantly from zero"
(summary item 3).

The alternatives tried (``CANDIDATES``) differ in C2..C4 and C7..C11.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from controller.astro.refraction import refraction_rad
from controller.astro.site import Weather, standard_pressure_hpa
from controller.units import RAD_PER_ARCMIN

from .terms import Term

__all__ = ["CANDIDATES", "CRANE_NAMES", "HEIGHT_M", "REFRACTION_SCALE_TERM", "crane_term",
           "crane_terms", "is_crane_term", "reference_weather"]

CRANE_NAMES = tuple(f"C{i}" for i in range(1, 12))
#: the coefficient that scales the refraction (dimensionless; 60" of the model per unit)
REFRACTION_SCALE_TERM = "C5"
#: the 140-ft's height (m; SLALIB/PAL GBVA140): C5's reference pressure is the standard
#: atmosphere's there (the equatorial vocabulary resolves terms by latitude only, and C1..C11
#: are the 140-ft's)
HEIGHT_M = 881.0

SIN_H, COS_H = ("sin", "AN", 1), ("cos", "AN", 1)
SIN_D, COS_D = ("sin", "E", 1), ("cos", "E", 1)
SIN_2H, COS_2H = ("sin", "AN", 2), ("cos", "AN", 2)
LIN_H = ("lin", "AN", 1)

#: functions by key: (axis, factors) with axis "S" (x = dH cos dec) or "E" (declination);
#: "tf" (tube flexure) and "refr" (refraction) are built from the latitude
_FUNCTIONS: dict[str, tuple[str, tuple]] = {
    "x1": ("S", ()), "xsd": ("S", (SIN_D,)), "xcd": ("S", (COS_D,)),
    "xchsd": ("S", (COS_H, SIN_D)), "xshsd": ("S", (SIN_H, SIN_D)),
    "xch": ("S", (COS_H,)), "xsh": ("S", (SIN_H,)), "xchcd": ("S", (COS_H, COS_D)),
    "xshcd": ("S", (SIN_H, COS_D)), "xs2h": ("S", (SIN_2H,)), "xc2h": ("S", (COS_2H,)),
    "d1": ("E", ()), "dch": ("E", (COS_H,)), "dsh": ("E", (SIN_H,)), "dcd": ("E", (COS_D,)),
    "dsd": ("E", (SIN_D,)), "ds2h": ("E", (SIN_2H,)), "dc2h": ("E", (COS_2H,)),
    "dh": ("E", (LIN_H,)), "dchsd": ("E", (COS_H, SIN_D)),
}

_DESCRIPTIONS = {
    "x1": "x = 1", "xsd": "x = sin(dec)", "xcd": "x = cos(dec)", "xchsd": "x = cos H sin(dec)",
    "xshsd": "x = sin H sin(dec)", "xch": "x = cos H", "xsh": "x = sin H",
    "xchcd": "x = cos H cos(dec)", "xshcd": "x = sin H cos(dec)", "xs2h": "x = sin 2H",
    "xc2h": "x = cos 2H", "d1": "dDec = 1", "dch": "dDec = cos H", "dsh": "dDec = sin H",
    "dcd": "dDec = cos(dec)", "dsd": "dDec = sin(dec)", "ds2h": "dDec = sin 2H",
    "dc2h": "dDec = cos 2H", "dh": "dDec = H (rad)", "dchsd": "dDec = cos H sin(dec)",
    "dtf": "dDec = cos(phi) cos H sin(dec) - sin(phi) cos(dec)",
    "refr": "R(E)/1' on both axes (refraction scale)",
}

#: candidate definitions of C1..C11 (keys of the functions above; C1 = x1, C5 = refr and
#: C6 = d1 in all, as the memo requires); "crane1981" is the chosen one
CANDIDATES: dict[str, tuple[str, ...]] = {
    "crane1981": ("x1", "xsh", "xchcd", "xchsd", "refr", "d1", "dc2h", "dsd", "dch", "dchsd",
                  "dtf"),
    #: the runner-up of the search (benchmarks/crane1981.py): C2 sin H and C4 sin(dec)
    "runner_up": ("x1", "xsh", "xchcd", "xsd", "refr", "d1", "dc2h", "dsd", "dch", "dchsd",
                  "dtf"),
    #: the textbook reading, rejected: RA = collimation, non-perpendicularity and the polar
    #: axis; Dec = zero, polar axis, tube flexure and encoder eccentricity
    "textbook": ("x1", "xsd", "xchsd", "xshsd", "refr", "d1", "dch", "dsh", "dtf", "dcd",
                 "dsd"),
}


def reference_weather(height_m: float) -> Weather:
    """The reference atmosphere of C5's refraction: 10 C, 50% humidity, the standard
    pressure at ``height_m`` (the controller's "standard" refraction; an assumption: the
    1981 program's own formula is not in the memo; the same as the controller's
    ``controller.scans.tracking.standard_weather``)."""
    return Weather(temperature_c=10.0, pressure_hpa=standard_pressure_hpa(height_m),
                   relative_humidity=0.5)


@dataclass(frozen=True)
class _RefractionOverCotE:
    """R(E) tan(E) / 1' at hour angle and declination (rad): the factor that turns TPOINT's
    tan Z law (dE = cot E) into the reference atmosphere's refraction in arcmin."""

    phi_rad: float
    pressure_hpa: float
    temperature_c: float
    relative_humidity: float

    def __call__(self, ha, dec):
        s = (math.sin(self.phi_rad) * np.sin(dec)
             + math.cos(self.phi_rad) * np.cos(dec) * np.cos(ha))
        el = np.arcsin(np.clip(s, -1.0, 1.0))
        weather = Weather(self.temperature_c, self.pressure_hpa, self.relative_humidity)
        el_safe = np.maximum(el, math.radians(1.0))
        return np.asarray(refraction_rad(el_safe, weather)) * np.tan(el_safe) / RAD_PER_ARCMIN


@dataclass(frozen=True)
class _SinElevation:
    phi_rad: float

    def __call__(self, ha, dec):
        return 1.0 / np.maximum(math.sin(self.phi_rad) * np.sin(dec) + math.cos(self.phi_rad)
                                * np.cos(dec) * np.cos(ha), math.sin(math.radians(1.0)))


def _components(key: str, latitude_deg: float, height_m: float) -> tuple:
    """TPOINT-sign components (minus the indicated-minus-true function) of ``key``."""
    phi = math.radians(latitude_deg)
    sp, cp = math.sin(phi), math.cos(phi)
    if key in _FUNCTIONS:
        axis, factors = _FUNCTIONS[key]
        return ((axis, -1.0, factors),)
    if key == "dtf":
        return (("E", -cp, (COS_H, SIN_D)), ("E", sp, (COS_D,)))
    if key == "refr":
        # refraction raises the source: indicated - true = +R along the vertical; on the axes
        # that is TPOINT's TX (dE = -cot E) times R tan E (units of 1' per unit coefficient)
        w = reference_weather(height_m)
        g = ("lin", _RefractionOverCotE(phi, w.pressure_hpa, w.temperature_c,
                                        w.relative_humidity), 1)
        csc = ("lin", _SinElevation(phi), 1)
        return (("A", cp, (SIN_H, ("sec", "E", 1), csc, g)),
                ("E", cp, (COS_H, SIN_D, csc, g)), ("E", -sp, (COS_D, csc, g)))
    raise KeyError(f"unknown Crane function {key!r}; known: {', '.join(sorted(_DESCRIPTIONS))}")


@lru_cache(maxsize=64)
def crane_terms(latitude_deg: float, height_m: float = HEIGHT_M,
                definition: str = "crane1981") -> tuple[Term, ...]:
    """The terms C1..C11 of ``definition`` (a key of :data:`CANDIDATES`) for a site at
    ``latitude_deg`` and ``height_m`` (C5's reference pressure)."""
    keys = CANDIDATES[definition]
    out = []
    for name, key in zip(CRANE_NAMES, keys, strict=True):
        kind = "angle"
        desc = f"Crane {name} ({definition}): {_DESCRIPTIONS[key]} (indicated - true)"
        if key == "refr":
            desc = (f"Crane {name}: refraction scale, value_arcsec / 60 = the scale of "
                    "R(E) (ERFA radio refraction, 10 C, 50% RH, standard pressure)")
        out.append(Term(name, desc, _components(key, latitude_deg, height_m), kind))
    return tuple(out)


def is_crane_term(name: str) -> bool:
    return str(name).strip().upper() in CRANE_NAMES


def crane_term(name: str, latitude_deg: float, height_m: float = HEIGHT_M) -> Term:
    """One of C1..C11 (the chosen definitions)."""
    key = str(name).strip().upper()
    return crane_terms(float(latitude_deg), float(height_m))[CRANE_NAMES.index(key)]


def candidate_terms(definition: str | tuple[str, ...], latitude_deg: float,
                    height_m: float = HEIGHT_M) -> tuple[Term, ...]:
    """C1..C11 of a candidate definition: a key of :data:`CANDIDATES` or 11 function keys."""
    if isinstance(definition, str):
        return crane_terms(float(latitude_deg), float(height_m), definition)
    return tuple(Term(name, _DESCRIPTIONS[key], _components(key, latitude_deg, height_m))
                 for name, key in zip(CRANE_NAMES, definition, strict=True))

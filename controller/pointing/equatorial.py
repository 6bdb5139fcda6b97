"""Pointing terms of an equatorial (polar) mount, in TPOINT's equatorial vocabulary.

An equatorial model is an ordinary :class:`~controller.pointing.model.PointingModel` whose terms are
evaluated at (hour angle, declination) instead of (azimuth, elevation): everything that takes
``az_rad, el_rad`` (the model, the fitter, :class:`~controller.pointing.data.PointingData`) takes
``ha_rad, dec_rad`` for it, and cross-axis errors are cross-declination, ``dH cos(dec)``. The
terms are built here as :class:`~controller.pointing.terms.Term` objects (factors of ``AN`` read the
hour angle, of ``E`` the declination), bound to the site's latitude phi where TPOINT's formula
needs it. Signs are TPOINT's: true = raw + correction (``dH``, ``dDec`` below); hour angle is
positive West.

| term | correction | meaning |
|---|---|---|
| IH | dH = -IH | hour-angle index (encoder zero) |
| ID | dDec = -ID | declination index |
| CH | dH = -CH sec(dec) | east-west collimation |
| NP | dH = -NP tan(dec) | HA/Dec axis non-perpendicularity |
| MA | dH = -MA cos H tan(dec), dDec = +MA sin H | polar axis left-right of the pole |
| ME | dH = +ME sin H tan(dec), dDec = +ME cos H | polar axis elevation |
| TF | dH = +TF cos(phi) sin H sec(dec), | tube flexure, sin Z law |
| | dDec = +TF (cos(phi) cos H sin(dec) - sin(phi) cos(dec)) | |
| TX | TF's expressions divided by sin E | tube flexure / refraction error, tan Z law |
| FO | dDec = +FO cos H | fork (yoke) flexure |
| DAF | dH = -DAF (cos(phi) cos H + sin(phi) tan(dec)) | declination-axis flexure |
| HCES, HCEC | dH = +HCES sin H, +HCEC cos H | hour-angle encoder centring |
| DCES, DCEC | dDec = +DCES sin(dec), +DCEC cos(dec) | declination encoder centring |

with ``sin E = sin(phi) sin(dec) + cos(phi) cos(dec) cos H``. TF and TX are exactly the alt-az
TF (dE = -TF cos E) and TX (dE = -TX cot E) moved onto the hour-angle and declination axes
(tested), so TPOINT's alt-az and equatorial sign conventions agree. MA, ME, TF, FO and DAF are
as the rotse.net summary of TPOINT lists them; IH, ID, CH and NP carry the same
negative sign as TPOINT's alt-az IA, CA and NPAE (TPOINT's own formula sheet was not
retrievable: an assumption, stated in ``docs/telescopes.md``). The harmonic generator works
as TPOINT's: ``H`` + result (``H``: dH, ``D``: dDec, ``X``: dH cos(dec)) + one or two factors
``S``/``C`` of ``H`` or ``D`` with an optional multiplier, e.g. ``HDSD`` is dDec = c sin(dec).

Named models: ``crane11``, the NRAO 140-ft's eleven terms (Crane 1981; von Hoerner's own
definitions, EDIR 102, were not available, see ``docs/telescopes.md``): IH ID CH NP MA ME TF
FO DAF TX HCES. HCEC is left out because DAF = -cos(phi) HCEC + sin(phi) NP exactly.
``crane1981``: Crane's own C1..C11 (Engineering Memo 147, Table 4), defined in
:mod:`controller.pointing.crane`.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from controller.errors import InputError

from .crane import CRANE_NAMES, crane_term
from .model import PointingModel
from .modelio import check_value, read_model_file, refuse_empty
from .terms import Term, TermError, harmonic_factors

__all__ = [
    "EQUATORIAL_MODELS",
    "EQUATORIAL_TERMS",
    "equatorial_model",
    "equatorial_term",
    "equatorial_terms",
    "is_equatorial_term",
    "load_equatorial_model",
]

#: the fixed equatorial terms (the harmonic generator adds more)
EQUATORIAL_TERMS = ("IH", "ID", "CH", "NP", "MA", "ME", "TF", "TX", "FO", "DAF",
                    "HCES", "HCEC", "DCES", "DCEC")

#: named equatorial models
EQUATORIAL_MODELS: dict[str, tuple[str, ...]] = {
    "none": (),
    "crane11": ("IH", "ID", "CH", "NP", "MA", "ME", "TF", "FO", "DAF", "TX", "HCES"),
    #: Crane's own C1..C11 (Table 4 of Engineering Memo 147; definitions: controller.pointing.crane)
    "crane1981": tuple(f"C{i}" for i in range(1, 12)),
    "equatorial6": ("IH", "ID", "CH", "NP", "MA", "ME"),
}

SIN_H, COS_H = ("sin", "AN", 1), ("cos", "AN", 1)
SIN_D, COS_D = ("sin", "E", 1), ("cos", "E", 1)
TAN_D, SEC_D = ("tan", "E", 1), ("sec", "E", 1)


@dataclass(frozen=True)
class _Elevation:
    """The elevation (rad) of hour angle and declination at latitude ``phi_rad``: a factor
    argument of TX (hashable, so that models cache it like any factor)."""

    phi_rad: float

    def __call__(self, ha, dec):
        s = (math.sin(self.phi_rad) * np.sin(dec)
             + math.cos(self.phi_rad) * np.cos(dec) * np.cos(ha))
        return np.arcsin(np.clip(s, -1.0, 1.0))


def _term(name: str, desc: str, *components) -> Term:
    return Term(name, desc, tuple((ax, float(sg), tuple(fs)) for ax, sg, fs in components))


@lru_cache(maxsize=64)
def _fixed_terms(latitude_deg: float) -> dict[str, Term]:
    phi = math.radians(latitude_deg)
    sp, cp = math.sin(phi), math.cos(phi)
    csc_e = ("csc", _Elevation(phi), 1)
    terms = [
        _term("IH", "hour-angle index: dH = -IH", ("A", -1, ())),
        _term("ID", "declination index: dDec = -ID", ("E", -1, ())),
        _term("CH", "east-west collimation: dH = -CH sec(dec)", ("A", -1, (SEC_D,))),
        _term("NP", "HA/Dec non-perpendicularity: dH = -NP tan(dec)", ("A", -1, (TAN_D,))),
        _term("MA", "polar axis left-right: dH = -MA cos H tan(dec), dDec = MA sin H",
              ("A", -1, (COS_H, TAN_D)), ("E", 1, (SIN_H,))),
        _term("ME", "polar axis elevation: dH = ME sin H tan(dec), dDec = ME cos H",
              ("A", 1, (SIN_H, TAN_D)), ("E", 1, (COS_H,))),
        _term("TF", "tube flexure (sin Z): dH = TF cos(phi) sin H sec(dec), "
                    "dDec = TF (cos(phi) cos H sin(dec) - sin(phi) cos(dec))",
              ("A", cp, (SIN_H, SEC_D)), ("E", cp, (COS_H, SIN_D)), ("E", -sp, (COS_D,))),
        _term("TX", "tube flexure / refraction (tan Z): TF's expressions / sin E",
              ("A", cp, (SIN_H, SEC_D, csc_e)), ("E", cp, (COS_H, SIN_D, csc_e)),
              ("E", -sp, (COS_D, csc_e))),
        _term("FO", "fork (yoke) flexure: dDec = FO cos H", ("E", 1, (COS_H,))),
        _term("DAF", "declination-axis flexure: dH = -DAF (cos(phi) cos H + sin(phi) tan(dec))",
              ("A", -cp, (COS_H,)), ("A", -sp, (TAN_D,))),
        _term("HCES", "hour-angle encoder centring, sine: dH = HCES sin H", ("A", 1, (SIN_H,))),
        _term("HCEC", "hour-angle encoder centring, cosine: dH = HCEC cos H",
              ("A", 1, (COS_H,))),
        _term("DCES", "declination encoder centring, sine: dDec = DCES sin(dec)",
              ("E", 1, (SIN_D,))),
        _term("DCEC", "declination encoder centring, cosine: dDec = DCEC cos(dec)",
              ("E", 1, (COS_D,))),
    ]
    return {t.name: t for t in terms}


_HARMONIC = re.compile(r"^H([HDX])([SC])([HD])(\d*)(?:([SC])([HD])(\d*))?$")


def _harmonic(name: str) -> Term | None:
    m = _HARMONIC.match(name)
    if not m:
        return None
    result, *groups = m.groups()
    raw = harmonic_factors(*groups)
    if raw is None:
        return None
    factors = tuple(("sin" if f == "S" else "cos", "AN" if a == "H" else "E", n)
                    for f, a, n in raw)
    axis = {"H": "A", "D": "E", "X": "S"}[result]
    words = {"H": "dH", "D": "dDec", "X": "dH cos(dec)"}[result]
    desc = " * ".join(f"{'sin' if f == 'S' else 'cos'}({'' if n == 1 else n}{a})"
                      for f, a, n in raw)
    return _term(name, f"harmonic: {words} = {name} {desc}", (axis, 1, factors))


def is_equatorial_term(name: str) -> bool:
    """Whether ``name`` names an equatorial term (fixed or harmonic)."""
    key = str(name).strip().upper()
    return (key in EQUATORIAL_TERMS or _HARMONIC.match(key) is not None
            or key in CRANE_NAMES)


@lru_cache(maxsize=512)
def _term_at(key: str, latitude_deg: float) -> Term:
    fixed = _fixed_terms(latitude_deg)
    if key in fixed:
        return fixed[key]
    if key in CRANE_NAMES:
        return crane_term(key, latitude_deg)
    term = _harmonic(key)
    if term is None:
        raise TermError(
            f"unknown equatorial pointing term {key!r}: use {' '.join(EQUATORIAL_TERMS)} or a "
            "harmonic such as HDSD or HHCH2 (H + result H/D/X + S/C of H or D), or Crane's C1..C11"
        )
    return term


def equatorial_term(name: str, latitude_deg: float) -> Term:
    """The equatorial term ``name`` for a site at geodetic latitude ``latitude_deg``."""
    return _term_at(str(name).strip().upper(), float(latitude_deg))


def equatorial_terms(names: Iterable[str | Term], latitude_deg: float) -> tuple[Term, ...]:
    """Terms by name (Term objects pass through) at ``latitude_deg``."""
    return tuple(n if isinstance(n, Term) else equatorial_term(n, latitude_deg) for n in names)


def equatorial_model(terms: str | Sequence[str | Term], latitude_deg: float,
                     values_arcsec: Sequence[float] | Mapping[str, float] | None = None,
                     name: str | None = None) -> PointingModel:
    """An equatorial :class:`PointingModel`: a named model (``crane11``...) or term names,
    with coefficients (arcsec, TPOINT sign) in model order or by name."""
    if isinstance(terms, str):
        if terms not in EQUATORIAL_MODELS:
            raise KeyError(f"unknown equatorial model {terms!r}; known: "
                           f"{', '.join(sorted(EQUATORIAL_MODELS))}")
        name = name or terms
        terms = EQUATORIAL_MODELS[terms]
    if isinstance(values_arcsec, Mapping):
        values_arcsec = {equatorial_term(k, latitude_deg).name: float(v)
                         for k, v in values_arcsec.items()}
    return PointingModel(equatorial_terms(terms, latitude_deg), values_arcsec, name)


def load_equatorial_model(spec: str, latitude_deg: float) -> PointingModel:
    """An equatorial model from a name (zero coefficients), a ``fit.json``/model JSON or a
    TPOINT ``.mod`` file (``antsim run --model`` on an equatorial mount: the closed loop).
    Bad input raises :class:`~controller.errors.InputError`."""
    text_spec = str(spec)
    if text_spec in EQUATORIAL_MODELS:
        return equatorial_model(text_spec, latitude_deg)
    path = Path(text_spec)
    if not path.is_file():
        raise InputError("command line", "--model", text_spec,
                         "neither a named equatorial model nor an existing file",
                         f"equatorial models: {', '.join(sorted(EQUATORIAL_MODELS))}")
    kind, content = read_model_file(path)
    names: list[str] = []
    values: list[float] = []
    name = path.stem
    if kind == "json":
        try:
            data = content
            terms = data["terms"]
            names = list(terms)
            values = [float(t["value_arcsec"] if isinstance(t, dict) else t)
                      for t in terms.values()]
            name = str(data.get("model", name))
        except (json.JSONDecodeError, KeyError, TypeError, ValueError) as err:
            raise InputError(str(path), "terms", type(err).__name__,
                             "not a model JSON ({'terms': {name: {'value_arcsec': x}}})") \
                from None
    else:
        lines = [ln.split("!", 1)[0].strip() for ln in content.splitlines()]
        lines = [ln for ln in lines if ln]
        for line_no, line in enumerate(lines[1:], start=2):  # the first is the caption
            if line.upper() == "END":
                break
            tokens = line.lstrip("&= ").split()
            if not is_equatorial_term(tokens[0]):
                if line_no == 2:  # the parameters record (method, N, sky RMS, ...)
                    continue
                raise InputError(str(path), "term", tokens[0], "unknown equatorial term")
            try:
                values.append(float(tokens[1]))
            except (IndexError, ValueError):
                raise InputError(str(path), tokens[0], line, "expected a value in arcsec") \
                    from None
            names.append(tokens[0].upper())
    for term, value in zip(names, values, strict=True):
        check_value(value, str(path), term)
    try:
        model = PointingModel(equatorial_terms(names, latitude_deg), values, name)
    except (TermError, ValueError) as err:
        raise InputError(str(path), "terms", names, str(err)) from None
    return refuse_empty(model, str(path))

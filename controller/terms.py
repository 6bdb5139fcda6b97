"""Pointing-model terms: the TPOINT vocabulary, Ghigo's W1..W10 and katpoint's P1..P22.

Every term is linear in its coefficient. ``Term.basis(az_rad, el_rad)`` returns the
*correction* per unit coefficient in TPOINT's sign convention,

    true (observed) = raw (indicated, encoder) + correction,

as ``(dA, dE)`` in radians per radian of coefficient, evaluated at the observed (true)
position. Azimuth arguments are North-based (N = 0, E = 90 deg) everywhere in this package.

Two facts fix the signs (both are tested):

* TPOINT evaluates its terms with its own South-based azimuth ``A_S = A_N - 180 deg``.
  Only then does a fit of ``../shared/data/real/mmt_20210821_k_and_e.dat`` reproduce
  TPOINT's published AN = +2.495" and AW = -10.335" (with North-based azimuth both flip).
  Even harmonics of azimuth are unaffected; odd ones change sign.
* Ghigo (1990) and katpoint write the opposite quantity, "indicated minus true", which is
  minus the TPOINT correction. Their basis functions are therefore negated here, so that a
  fitted coefficient equals the number those sources print.

Ghigo's W1..W10: the report's own equations were not available to us (see
``docs/assumptions.md``). They are reconstructed as five azimuth and five elevation terms of
the kind an NRAO model of 1990 fitted independently, keeping what the issues state: W4 is the
gravitational sag (cos E in elevation) and W6, 12.24', is the elevation zero offset::

    dA = W1 + W2 sec E + W3 tan E + W9 sin A tan E + W10 cos A tan E
    dE = W4 cos E + W5 cot E + W6 + W7 cos A + W8 sin A      (indicated - true)

The harmonic generator follows TPOINT: ``H`` + result letter (A: azimuth, E: elevation,
S: left-right on the sky = dA cos E, Z: zenith distance = -dE) + one or two factors, each
``S`` or ``C`` (sine, cosine) of ``A``, ``E`` or ``Z`` with an optional integer multiplier:
``HESA2`` is dE = c sin 2A, ``HSCA5CE8`` is dA cos E = c cos 5A cos 8E.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

__all__ = [
    "GHIGO_EQUIVALENTS",
    "KATPOINT_EQUIVALENTS",
    "Term",
    "TermError",
    "get_term",
    "is_term_name",
]

Basis = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]


class TermError(KeyError):
    """An unknown term name."""

    def __str__(self) -> str:  # KeyError quotes its message; a user should read plain text
        return str(self.args[0])


@dataclass(frozen=True)
class Term:
    """One linear pointing term.

    ``kind`` is ``"angle"`` for coefficients that are angles (value in arcsec) or
    ``"scale"`` for dimensionless scale factors (katpoint P9, P12; their ``value_arcsec`` is
    the error at one radian of the argument).
    """

    name: str
    description: str
    _basis: Basis = field(repr=False, compare=False)
    kind: str = "angle"

    def basis(self, az_rad, el_rad) -> tuple[np.ndarray, np.ndarray]:
        """TPOINT-sign correction (dA, dE) per unit coefficient, radians per radian."""
        az = np.asarray(az_rad, dtype=float)
        el = np.asarray(el_rad, dtype=float)
        d_az, d_el = self._basis(az, el)
        shape = np.broadcast(az, el).shape
        return np.broadcast_to(d_az, shape).astype(float), np.broadcast_to(d_el, shape).astype(float)


def _zeros(az, el):
    return np.zeros(np.broadcast(az, el).shape)


def _az_s(az):
    """TPOINT's South-based azimuth from our North-based one."""
    return az - math.pi


def _sec(el):
    return 1.0 / np.cos(el)


# ---------------------------------------------------------------------------------------------
# TPOINT's basic terms (alt-az mount)
# ---------------------------------------------------------------------------------------------
def _tpoint_terms() -> dict[str, Term]:
    t: dict[str, Term] = {}

    def add(name, desc, fn, kind="angle"):
        t[name] = Term(name, desc, fn, kind)

    add("IA", "azimuth index (encoder zero): dA = -IA",
        lambda a, e: (-np.ones_like(a + e), _zeros(a, e)))
    add("IE", "elevation index (encoder zero): dE = +IE",
        lambda a, e: (_zeros(a, e), np.ones_like(a + e)))
    add("CA", "collimation, left-right: dA = -CA sec E",
        lambda a, e: (-_sec(e) + 0 * a, _zeros(a, e)))
    add("NPAE", "az/el axis non-perpendicularity: dA = -NPAE tan E",
        lambda a, e: (-np.tan(e) + 0 * a, _zeros(a, e)))
    add("AN", "azimuth axis tilt, north-south: dA = -AN sin A tan E, dE = -AN cos A",
        lambda a, e: (-np.sin(_az_s(a)) * np.tan(e), -np.cos(_az_s(a)) + 0 * e))
    add("AW", "azimuth axis tilt, east-west: dA = -AW cos A tan E, dE = +AW sin A",
        lambda a, e: (-np.cos(_az_s(a)) * np.tan(e), np.sin(_az_s(a)) + 0 * e))
    add("TF", "tube flexure (gravitational sag), cos E law: dE = -TF cos E",
        lambda a, e: (_zeros(a, e), -np.cos(e) + 0 * a))
    add("TX", "tube flexure / refraction error, cot E law: dE = -TX cot E",
        lambda a, e: (_zeros(a, e), -1.0 / np.tan(e) + 0 * a))
    add("ACEC", "azimuth centering error, cos component: dA = +ACEC cos A",
        lambda a, e: (np.cos(_az_s(a)) + 0 * e, _zeros(a, e)))
    add("ACES", "azimuth centering error, sin component: dA = +ACES sin A",
        lambda a, e: (np.sin(_az_s(a)) + 0 * e, _zeros(a, e)))
    add("ECEC", "elevation centering error, cos component: dE = +ECEC cos E",
        lambda a, e: (_zeros(a, e), np.cos(e) + 0 * a))
    add("ECES", "elevation centering error, sin component: dE = +ECES sin E",
        lambda a, e: (_zeros(a, e), np.sin(e) + 0 * a))
    return t


# ---------------------------------------------------------------------------------------------
# TPOINT harmonic generator
# ---------------------------------------------------------------------------------------------
_HARMONIC = re.compile(r"^H([AESZ])([SC])([AEZ])(\d*)(?:([SC])([AEZ])(\d*))?$")


def _argument(letter: str, az, el):
    if letter == "A":
        return _az_s(az)
    if letter == "E":
        return el
    return 0.5 * math.pi - el  # Z: zenith distance


def _harmonic(name: str) -> Term | None:
    m = _HARMONIC.match(name)
    if not m:
        return None
    result, f1, a1, n1, f2, a2, n2 = m.groups()
    factors = [(f1, a1, int(n1) if n1 else 1)]
    if f2:
        factors.append((f2, a2, int(n2) if n2 else 1))
    if any(n == 0 for _, _, n in factors):
        return None

    def fn(az, el):
        value = np.ones(np.broadcast(az, el).shape)
        for func, arg, mult in factors:
            x = mult * _argument(arg, az, el)
            value = value * (np.sin(x) if func == "S" else np.cos(x))
        zero = np.zeros_like(value)
        if result == "A":
            return value, zero
        if result == "E":
            return zero, value
        if result == "Z":
            return zero, -value
        return value / np.cos(el), zero  # S: left-right on the sky

    words = {"A": "dA", "E": "dE", "S": "dA cos E", "Z": "dZ"}
    desc = " * ".join(
        f"{'sin' if f == 'S' else 'cos'}({'' if n == 1 else n}{a})" for f, a, n in factors
    )
    return Term(name, f"harmonic: {words[result]} = {name} {desc}", fn)


# ---------------------------------------------------------------------------------------------
# Ghigo (1990) W1..W10: indicated - true, North-based azimuth (see module docstring)
# ---------------------------------------------------------------------------------------------
def _ghigo_terms() -> dict[str, Term]:
    t: dict[str, Term] = {}

    def add(name, desc, fn):
        # fn returns indicated - true; the TPOINT correction is its negative
        def basis(a, e, fn=fn):
            d_az, d_el = fn(a, e)
            return -d_az, -d_el

        t[name] = Term(name, desc, basis)

    add("W1", "azimuth encoder zero: dA = W1",
        lambda a, e: (np.ones_like(a + e), _zeros(a, e)))
    add("W2", "collimation: dA = W2 sec E", lambda a, e: (_sec(e) + 0 * a, _zeros(a, e)))
    add("W3", "az/el axis non-perpendicularity: dA = W3 tan E",
        lambda a, e: (np.tan(e) + 0 * a, _zeros(a, e)))
    add("W4", "gravitational sag: dE = W4 cos E", lambda a, e: (_zeros(a, e), np.cos(e) + 0 * a))
    add("W5", "refraction error: dE = W5 cot E",
        lambda a, e: (_zeros(a, e), 1.0 / np.tan(e) + 0 * a))
    add("W6", "elevation encoder zero: dE = W6", lambda a, e: (_zeros(a, e), np.ones_like(a + e)))
    add("W7", "azimuth axis tilt seen in elevation: dE = W7 cos A",
        lambda a, e: (_zeros(a, e), np.cos(a) + 0 * e))
    add("W8", "azimuth axis tilt seen in elevation: dE = W8 sin A",
        lambda a, e: (_zeros(a, e), np.sin(a) + 0 * e))
    add("W9", "azimuth axis tilt seen in azimuth: dA = W9 sin A tan E",
        lambda a, e: (np.sin(a) * np.tan(e), _zeros(a, e)))
    add("W10", "azimuth axis tilt seen in azimuth: dA = W10 cos A tan E",
        lambda a, e: (np.cos(a) * np.tan(e), _zeros(a, e)))
    return t


# ---------------------------------------------------------------------------------------------
# katpoint P1..P22 (katpoint.PointingModel.offset: indicated - true, North-based azimuth)
# ---------------------------------------------------------------------------------------------
def _katpoint_terms() -> dict[str, Term]:
    t: dict[str, Term] = {}

    def add(name, desc, fn, kind="angle"):
        def basis(a, e, fn=fn):
            d_az, d_el = fn(a, e)
            return -d_az, -d_el

        t[name] = Term(name, f"katpoint {name}: {desc}", basis, kind)

    z = _zeros
    add("P1", "az offset: daz = P1", lambda a, e: (np.ones_like(a + e), z(a, e)))
    add("P2", "az gravitational sag (unused by katpoint for alt-az)", lambda a, e: (z(a, e), z(a, e)))
    add("P3", "left-right axis skew: daz = P3 tan E", lambda a, e: (np.tan(e) + 0 * a, z(a, e)))
    add("P4", "collimation: daz = -P4 sec E", lambda a, e: (-_sec(e) + 0 * a, z(a, e)))
    add("P5", "tilt out: daz = P5 sin A tan E, del = P5 cos A",
        lambda a, e: (np.sin(a) * np.tan(e), np.cos(a) + 0 * e))
    add("P6", "tilt over: daz = -P6 cos A tan E, del = P6 sin A",
        lambda a, e: (-np.cos(a) * np.tan(e), np.sin(a) + 0 * e))
    add("P7", "el offset: del = P7", lambda a, e: (z(a, e), np.ones_like(a + e)))
    add("P8", "gravity sag: del = P8 cos E", lambda a, e: (z(a, e), np.cos(e) + 0 * a))
    add("P9", "el excess scale: del = P9 E", lambda a, e: (z(a, e), e + 0 * a), "scale")
    add("P10", "cos E in del, redundant with P8 (unused by katpoint)",
        lambda a, e: (z(a, e), z(a, e)))
    add("P11", "asymmetric sag: del = P11 sin E", lambda a, e: (z(a, e), np.sin(e) + 0 * a))
    add("P12", "az excess scale: daz = P12 A", lambda a, e: (a + 0 * e, z(a, e)), "scale")
    add("P13", "az centering: daz = P13 cos A", lambda a, e: (np.cos(a) + 0 * e, z(a, e)))
    add("P14", "az centering: daz = P14 sin A", lambda a, e: (np.sin(a) + 0 * e, z(a, e)))
    add("P15", "el nod twice per turn: del = P15 cos 2A",
        lambda a, e: (z(a, e), np.cos(2 * a) + 0 * e))
    add("P16", "el nod twice per turn: del = P16 sin 2A",
        lambda a, e: (z(a, e), np.sin(2 * a) + 0 * e))
    add("P17", "az encoder tilt: daz = P17 cos 2A", lambda a, e: (np.cos(2 * a) + 0 * e, z(a, e)))
    add("P18", "az encoder tilt: daz = P18 sin 2A", lambda a, e: (np.sin(2 * a) + 0 * e, z(a, e)))
    add("P19", "el encoder scale distortion: del = P19 cos 8E",
        lambda a, e: (z(a, e), np.cos(8 * e) + 0 * a))
    add("P20", "el encoder scale distortion: del = P20 sin 8E",
        lambda a, e: (z(a, e), np.sin(8 * e) + 0 * a))
    add("P21", "el nod once per turn: del = P21 cos A", lambda a, e: (z(a, e), np.cos(a) + 0 * e))
    add("P22", "el nod once per turn: del = P22 sin A", lambda a, e: (z(a, e), np.sin(a) + 0 * e))
    return t


_FIXED: dict[str, Term] = {**_tpoint_terms(), **_ghigo_terms(), **_katpoint_terms()}

#: Where Ghigo's W terms coincide with TPOINT's: W = sign * TPOINT coefficient (tested).
GHIGO_EQUIVALENTS: dict[str, tuple[str, float]] = {
    "W1": ("IA", 1.0),
    "W2": ("CA", 1.0),
    "W3": ("NPAE", 1.0),
    "W4": ("TF", 1.0),
    "W5": ("TX", 1.0),
    "W6": ("IE", -1.0),
    "W7": ("HECA", 1.0),
    "W8": ("HESA", 1.0),
    "W9": ("HSSASE", 1.0),
    "W10": ("HSCASE", 1.0),
}

#: Where katpoint's P terms coincide with TPOINT's: P = sign * TPOINT coefficient (tested).
#: P5/P6 are the azimuth-axis tilt and equal -AN/+AW in both axes at once. P2 and P10 are
#: unused by katpoint; P9 and P12 are scale factors with no TPOINT twin here.
KATPOINT_EQUIVALENTS: dict[str, tuple[str, float]] = {
    "P1": ("IA", 1.0),
    "P3": ("NPAE", 1.0),
    "P4": ("CA", -1.0),
    "P5": ("AN", -1.0),
    "P6": ("AW", 1.0),
    "P7": ("IE", -1.0),
    "P8": ("TF", 1.0),
    "P11": ("HESE", -1.0),
    "P13": ("HACA", 1.0),
    "P14": ("HASA", 1.0),
    "P15": ("HECA2", -1.0),
    "P16": ("HESA2", -1.0),
    "P17": ("HACA2", -1.0),
    "P18": ("HASA2", -1.0),
    "P19": ("HECE8", -1.0),
    "P20": ("HESE8", -1.0),
    "P21": ("HECA", 1.0),
    "P22": ("HESA", 1.0),
}


@lru_cache(maxsize=512)
def get_term(name: str) -> Term:
    """The term called ``name`` (TPOINT name, harmonic, W1..W10 or P1..P22)."""
    key = name.strip().upper()
    if key in _FIXED:
        return _FIXED[key]
    term = _harmonic(key)
    if term is None:
        raise TermError(
            f"unknown pointing term {name!r}: use a TPOINT name (IA IE CA NPAE AN AW TF TX "
            "ACEC ACES ECEC ECES), a harmonic such as HESA2 or HSCA2CE, W1..W10 or P1..P22"
        )
    return term


def is_term_name(name: str) -> bool:
    """Whether ``name`` names a known term."""
    try:
        get_term(name)
    except TermError:
        return False
    return True

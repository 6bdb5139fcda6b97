"""The units and sign of a model's terms, in words: the sentence every output prints beside
its coefficients.

TPOINT's terms are corrections, true (observed) = raw (encoder) + correction; the source
documents' vocabularies (Ghigo 1990's W1..W10, Wright 1992's a(i), b(i), Crane 1981's
C1..C11) and katpoint's P1..P22 are "indicated minus true", the negative
(:mod:`controller.pointing.terms`). Imports nothing, so that the fit's result and the model
files can both use it.
"""

from __future__ import annotations

import re
from collections.abc import Iterable

__all__ = ["INDICATED_MINUS_TRUE", "TPOINT_SIGN", "UNITS", "sign_convention"]

UNITS = "arcsec"
TPOINT_SIGN = "true (observed) = raw (encoder) + correction"

#: (pattern, the vocabulary's name): each writes "indicated minus true"
INDICATED_MINUS_TRUE = (
    (re.compile(r"^W([1-9]|10)$"), "W1..W10 (Ghigo 1990, NRAO EDIR 288, section II)"),
    (re.compile(r"^P([1-9]|1\d|2[0-2])$"), "P1..P22 (katpoint)"),
    (re.compile(r"^[AB][1-7]$"), "A1..A7, B1..B7 (Wright 1992, BIMA memo 23, a(i), b(i))"),
    (re.compile(r"^C([1-9]|1[01])$"), "C1..C11 (Crane 1981, NRAO Engineering Memo 147)"),
    (re.compile(r"^(T[ES](DFB|YFB|DRL|YRL|SUN|FACE|SIDE|AIR)|TPYRL|TNPNS|TWPEW|TNSUN|TWSUN"
                r"|TTILT)$"),
     "the thermal terms (controller.pointing.thermal; per kelvin, or per unit of a proxy)"),
)


def sign_convention(names: Iterable[str]) -> str:
    """The sign of the terms ``names`` in words: TPOINT's, or "indicated minus true" for the
    vocabularies of the source documents and katpoint (the units are :data:`UNITS`)."""
    names = [str(n).strip().upper() for n in names]
    theirs = [label for pattern, label in INDICATED_MINUS_TRUE
              if any(pattern.match(n) for n in names)]
    others = [n for n in names if not any(p.match(n) for p, _ in INDICATED_MINUS_TRUE)]
    parts = []
    if theirs:
        parts.append(f"{', '.join(theirs)}: indicated minus true (the negative of TPOINT's "
                     "correction)")
    if others or not theirs:
        parts.append(f"{'the other terms ' if theirs else ''}TPOINT's: {TPOINT_SIGN}")
    return "; ".join(parts)

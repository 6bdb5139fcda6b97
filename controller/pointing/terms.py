"""Pointing-model terms: the TPOINT vocabulary, Ghigo's W1..W10 and katpoint's P1..P22.

Every term is linear in its coefficient. ``Term.basis(az_rad, el_rad)`` returns the
*correction* per unit coefficient in TPOINT's sign convention,

    true (observed) = raw (indicated, encoder) + correction,

as ``(dA, dE)`` in radians per radian of coefficient, evaluated at the observed (true)
position. Azimuth arguments are North-based (N = 0, E = 90 deg) everywhere in this package.

Two facts fix the signs (both are tested):

* TPOINT writes its terms in its own azimuth, South = 0, East = 90: ``A_T = 180 deg - A_N``,
  the mirror image of the North-based azimuth, not a half turn of it (P. T. Wallace, TPOINT
  routine tptPterms, revision of 14 November 2006, note 8: "Azimuth - zero for due south,
  and 90 degrees for due east"), with its azimuth corrections growing with ``A_T``. Every
  TPOINT term here is TPOINT's formula at ``A_T`` with its azimuth results negated (``dA_N =
  -dA_T``): AN is dA = -AN sin A_T tan E, dE = +AN cos A_T (tptPterms term 31: "the pole of
  the mounting is north of the zenith"), AW is dA = +AW cos A_T tan E, dE = +AW sin A_T
  (term 32: "west of the zenith"), ACES and ACEC are dA = -ACES sin A_T, -ACEC cos A_T
  (terms 34, 35). The basic terms are written below in ``A_N`` (sin A_T = sin A_N, cos A_T =
  -cos A_N); the harmonic generator's azimuth is ``A_T`` itself. A TPOINT data file's
  azimuth is North-based (:mod:`.tpoint` reads it as it is), so the same terms fit TPOINT
  files as TPOINT fits them (``examples/mmt_20210821_k_and_e.dat``: TPOINT's AN = +2.495",
  AW = -10.335") and North-based data (CSV, recordings, the simulated telescope) with
  TPOINT's meaning: AN > 0 is the azimuth axis's pole north of the zenith, AW > 0 west of it.
* Ghigo (1990) and katpoint write the opposite quantity, "indicated minus true", which is
  minus the TPOINT correction. Their basis functions are therefore negated here, so that a
  fitted coefficient equals the number those sources print.

Ghigo's W1..W10 are the 1990 report's (Ghigo 1990, NRAO EDIR 288, section II; Table 3
names each term), indicated minus true, North-based azimuth::

    dE       = W1 + W2 cos A + W3 sin A + W4 cos E + W5 cot E
    dA cos E = W6 cos E + (W7 cos A + W8 sin A + W9) sin E + W10

The report ties W2 = W8 (elevation axis misalignment) and W3 = -W7 (azimuth axis
misalignment) physically but fits all ten independently (Table 3: W2 -0.17', W8 -0.35').
With TPOINT's corrections (true = raw + correction, TPOINT's azimuth A_T = 180 deg - A_N)
every W is one TPOINT term up to sign (``GHIGO_EQUIVALENTS``; tested column by column):
W1 = -IE, W2 = HECA, W3 = -HESA, W4 = TF, W5 = TX, W6 = IA, W7 = -HSCASE, W8 = HSSASE,
W9 = NPAE, W10 = CA; tied, an azimuth-axis tilt is W2 = W8 = AN and W3 = -W7 = -AW
(``GHIGO_TILT``). Fomalont's 1973 model (the report's Appendix A) has the same ten functions:
C1..C5 = W6..W10 and D1..D5 = W1..W5 (``FOMALONT_NAMES``), plus its feed terms.

The harmonic generator follows TPOINT: ``H`` + result letter (A: azimuth, E: elevation,
S: left-right on the sky = dA cos E, Z: zenith distance) + one or two factors, each ``S`` or
``C`` (sine, cosine) of ``A``, ``E`` or ``Z`` with an optional integer multiplier. Its signs
are TPOINT's own, those of its basic terms, and TPOINT's FAUTO fit of
``examples/auxtel_20200315.dat`` (22 terms, ten of them harmonics with results A, E and S and
arguments up to 7A) confirms them (tested):

* the azimuth of a harmonic is TPOINT's own, ``A_T = 180 deg - A_N``;
* an ``A`` or ``S`` result is minus the harmonic (``dA_N = -dA_T``, as for IA and CA):
  ``HACA2`` is dA = -c cos 2A_T, ``HSCA5CE8`` is dA cos E = -c cos 5A_T cos 8E;
* an ``E`` result is plus it (``HESA2`` is dE = +c sin 2A_T = -c sin 2A_N) and a ``Z`` result
  is dZ = +c f, i.e. dE = -c f.

So TPOINT's ACEC and ACES are HACA and HASA, column for column (tptPterms terms 34, 35). With
the North-based azimuth, sin kA_T = -(-1)^k sin kA_N and cos kA_T = (-1)^k cos kA_N: HECA is
dE = -c cos A_N, HESA dE = +c sin A_N, HESA2 dE = -c sin 2A_N.
Among the conventions "argument +-A_N + k 180 deg, one sign per result letter" this is the
only one that reproduces the signs of all ten of TPOINT's harmonic coefficients on that file
(HACA2, HASA7, HESACE, HESA2, HESA3, HSCA5CE8, HSSA6CE6, HSCE3, HSSE8, HSCE8). No ``Z``
harmonic was in that fit: its sign (dE = -c f) is the natural reading of a zenith-distance
result (tptPterms' TF and TX are changes in zenith distance), not evidence.

Beyond TPOINT, the argument ``F`` is the feed (rotator) angle of a feed box turned during a
campaign (Fomalont 1973's feed terms). TPOINT has no such argument; for consistency the
result signs follow the same rule, so ``HSCF`` is dA cos E = -c cos F and ``HECF`` is
dE = +c cos F (the feed angle itself is used as it is, not negated). Terms with an ``F``
factor need the feed angle (``feed_rad``) wherever they are evaluated.

Beyond TPOINT too, a factor's argument may be a :class:`Regressor`: a quantity recorded with
each observation rather than a function of the position, such as the difference of two
structure temperatures (K) or a proxy for them (:mod:`controller.pointing.thermal`). Each
axis' rows read their own recording of it (the cross-elevation rows the reading taken during
the azimuth scan, the elevation rows the one taken during the elevation scan): ``aux`` maps
the recorded name to its (cross-elevation, elevation) arrays wherever such terms are
evaluated.

Extension for other mounts (:mod:`controller.pointing.equatorial`): a factor's argument may also be
a hashable callable ``(lon_rad, lat_rad) -> array`` of the two coordinates the terms are
evaluated at (for an equatorial model: hour angle and declination, passed in place of azimuth
and elevation), e.g. the elevation that TPOINT's equatorial TX needs. Names never produce
such factors: terms with them are built by hand and state their own signs; were one built
as a harmonic, the same result rule would apply (A and S results minus, E plus). The
equatorial harmonic generator (``HHSH``, ``HDCD``... in :mod:`controller.pointing.equatorial`) is a
separate one, with every result ``+c f``: no TPOINT fit with equatorial harmonics was
available to test it against.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np

__all__ = [
    "FOMALONT_NAMES",
    "GHIGO_EQUIVALENTS",
    "GHIGO_TILT",
    "KATPOINT_EQUIVALENTS",
    "KNOWN_TERMS",
    "NOT_ESTABLISHED",
    "WRIGHT_EQUIVALENTS",
    "Regressor",
    "Term",
    "TermError",
    "basis_columns",
    "basis_parts",
    "combine_arrays",
    "combine_scalar",
    "evaluate_basis",
    "get_term",
    "harmonic_factors",
    "is_term_name",
    "term_refusal",
]

# A term is a sum of components; each component is sign * product of factors, landing in
# dA (axis "A"), dE (axis "E") or left-right on the sky (axis "S": dA cos E). A factor is
# (function, argument, multiplier): functions sin cos tan sec cot lin csc; arguments
# "AN" (North-based azimuth), "AT" (TPOINT's own azimuth pi - A_N, South = 0, East = 90, of
# its harmonic generator), "E" (elevation), "Z" (zenith distance), "F" (feed angle), a
# Regressor (a recorded quantity) or a hashable callable (see the module docstring). Models
# evaluate each distinct factor once (see ``evaluate_basis``; a Regressor's once per axis).
Factor = tuple[str, str, int]
Component = tuple[str, float, tuple[Factor, ...]]


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
    components: tuple[Component, ...] = field(repr=False)
    kind: str = "angle"

    def basis(self, az_rad, el_rad) -> tuple[np.ndarray, np.ndarray]:
        """TPOINT-sign correction (dA, dE) per unit coefficient, radians per radian."""
        az, el = np.broadcast_arrays(np.asarray(az_rad, dtype=float),
                                     np.asarray(el_rad, dtype=float))
        basis_az, basis_el = evaluate_basis((self,), az.reshape(-1), el.reshape(-1))
        return basis_az[:, 0].reshape(az.shape), basis_el[:, 0].reshape(az.shape)


@dataclass(frozen=True)
class Regressor:
    """A recorded quantity a term is linear in: the value recorded as ``plus``, less the one
    recorded as ``minus`` when given (e.g. two structure temperatures, K; a proxy alone).
    ``aux`` maps each recorded name to its (cross-elevation rows, elevation rows) values."""

    plus: str
    minus: str | None = None

    @property
    def names(self) -> tuple[str, ...]:
        return (self.plus,) if self.minus is None else (self.plus, self.minus)

    def value(self, aux, side: int):
        """The regressor on one side (0: cross-elevation rows, 1: elevation rows)."""
        if aux is None or any(n not in aux for n in self.names):
            missing = [n for n in self.names if aux is None or n not in aux]
            raise ValueError(
                f"a thermal term needs the recorded {', '.join(missing)}: give aux (the "
                "recordings' structure temperature columns, or the proxies of "
                "controller.pointing.proxies)")
        out = aux[self.plus][side]
        return out if self.minus is None else out - aux[self.minus][side]


def _side(axis: str) -> int:
    """Which recording of a Regressor an axis' rows use: 0 cross-elevation, 1 elevation."""
    return 1 if axis == "E" else 0


def _argument(arg, az: np.ndarray, el: np.ndarray, feed=None) -> np.ndarray:
    if callable(arg):
        return arg(az, el)
    if arg == "F":
        return _feed(feed)
    if arg == "AT":
        return math.pi - az
    if arg == "AN":
        return az
    if arg == "E":
        return el
    return 0.5 * math.pi - el  # "Z"


def _factor_argument(arg, mult: int, side: int | None, az: np.ndarray, el: np.ndarray,
                     feed=None, aux=None) -> np.ndarray:
    """A factor's argument times its multiplier; ``side``: a Regressor's recording."""
    if side is not None:
        x = np.broadcast_to(np.asarray(arg.value(aux, side), float), az.shape)
    else:
        x = _argument(arg, az, el, feed)
    return x if mult == 1 else mult * x


_FUNCTIONS = {
    "sin": np.sin,
    "cos": np.cos,
    "tan": np.tan,
    "sec": lambda x: 1.0 / np.cos(x),
    "cot": lambda x: 1.0 / np.tan(x),
    "lin": lambda x: x,
    "csc": lambda x: 1.0 / np.sin(x),
    # the powers of TPOINT's polynomial terms (PEE2 ...): x ** n, n = 2..9
    **{f"pow{n}": (lambda x, n=n: x**n) for n in range(2, 10)},
}


def _feed(feed):
    if feed is None:
        raise ValueError("a term with a feed-angle factor (F) needs the feed angle: give "
                         "feed_rad (the recordings' feed_angle_deg column)")
    return feed


def evaluate_basis(terms: Sequence[Term], az_rad: np.ndarray,
                   el_rad: np.ndarray, feed_rad=None, aux=None) -> tuple[np.ndarray, np.ndarray]:
    """TPOINT-sign correction basis of ``terms`` at 1-D arrays of points: two (N, M) arrays.
    ``feed_rad``: feed angle(s) (rad), needed only by terms with an ``F`` factor; ``aux``:
    recorded quantities, needed only by terms with a :class:`Regressor` factor."""
    n = az_rad.shape[0]
    basis_az = np.zeros((n, len(terms)))
    basis_el = np.zeros((n, len(terms)))
    for j, (parts_az, parts_el) in enumerate(basis_parts(terms, az_rad, el_rad, feed_rad, aux)):
        for part in parts_az:
            basis_az[:, j] += part
        for part in parts_el:
            basis_el[:, j] += part
    return basis_az, basis_el


def basis_columns(terms: Sequence[Term], az_rad: np.ndarray, el_rad: np.ndarray, feed_rad=None,
                  aux=None, cos_el=None) -> Iterator[tuple[np.ndarray | float, np.ndarray | float]]:
    """:func:`evaluate_basis` a term at a time: its (dA, dE) columns with the basis' bits,
    each a new (N,) array the caller may write into, or 0.0 for a column of zeros.
    ``cos_el``: ``np.cos(el_rad)`` where the caller has it (the sky terms divide by it)."""
    n = az_rad.shape[0]
    for parts_az, parts_el in basis_parts(terms, az_rad, el_rad, feed_rad, aux, cos_el):
        yield _column(parts_az, n), _column(parts_el, n)


def _column(parts: list, n: int) -> np.ndarray | float:
    """A column of zeros plus each part in order (0.0 + -0.0 is +0.0), in the first part's
    own array; 0.0 for no parts."""
    if not parts:
        return 0.0
    first, *rest = parts
    col = np.add(first, 0.0, out=first) if np.ndim(first) else np.full(n, first + 0.0)
    for part in rest:
        col += part
    return col


def basis_parts(terms: Sequence[Term], az_rad: np.ndarray, el_rad: np.ndarray, feed_rad=None,
                aux=None, cos_el=None) -> Iterator[tuple[list, list]]:
    """Per term, the parts its dA and dE columns add up, in order: each ``sign * value``
    (a left-right one over cos E), a new (N,) array or a float. Each distinct factor is
    evaluated once, its argument once for its sine and cosine."""
    values: dict = {}  # (factor, side) -> its function of its argument
    arguments: dict = {}  # (arg, mult, side) -> the argument, shared by sine and cosine
    sec_el = None
    for term in terms:
        parts_az: list = []
        parts_el: list = []
        for axis, sign, factors in term.components:
            value = None
            for factor in factors:
                func, arg, mult = factor
                side = _side(axis) if isinstance(arg, Regressor) else None
                arr = values.get((factor, side))
                if arr is None:
                    x = arguments.get((arg, mult, side))
                    if x is None:
                        x = _factor_argument(arg, mult, side, az_rad, el_rad, feed_rad, aux)
                        arguments[(arg, mult, side)] = x
                    arr = values[(factor, side)] = _FUNCTIONS[func](x)
                value = arr if value is None else value * arr
            part = sign * (1.0 if value is None else value)
            if axis == "S":  # left-right on the sky, dA = value / cos E
                if sec_el is None:
                    sec_el = 1.0 / (np.cos(el_rad) if cos_el is None else cos_el)
                part = part * sec_el
            (parts_el if axis == "E" else parts_az).append(part)
        yield parts_az, parts_el


_MATH = {"sin": math.sin, "cos": math.cos, "tan": math.tan,
         "sec": lambda x: 1.0 / math.cos(x), "cot": lambda x: 1.0 / math.tan(x),
         "lin": lambda x: x, "csc": lambda x: 1.0 / math.sin(x),
         **{f"pow{n}": (lambda x, n=n: x**n) for n in range(2, 10)}}


def _argument_scalar(arg, az: float, el: float, feed=None) -> float:
    if callable(arg):
        return float(arg(az, el))
    if arg == "F":
        return _feed(feed)
    if arg == "AT":
        return math.pi - az
    if arg == "AN":
        return az
    if arg == "E":
        return el
    return 0.5 * math.pi - el


def combine_scalar(terms: Sequence[Term], coeffs: Sequence[float], az_rad: float,
                   el_rad: float, feed_rad: float | None = None,
                   aux=None) -> tuple[float, float]:
    """``sum_j coeffs[j] * basis_j`` at one point, with plain floats (fast for scalars);
    ``aux`` as for :func:`evaluate_basis`, with one value per side."""
    return _combine(terms, coeffs, az_rad, el_rad, feed_rad, _MATH, _argument_scalar, math.cos,
                    aux)


def combine_arrays(terms: Sequence[Term], coeffs: Sequence[float], az_rad: np.ndarray,
                   el_rad: np.ndarray, feed_rad=None, aux=None) -> tuple[np.ndarray, np.ndarray]:
    """:func:`combine_scalar` on arrays of any (common) shape, element by element: no basis
    matrix (the fast path for a few points, e.g. an ensemble's members at one instant)."""
    az, el = np.broadcast_arrays(np.asarray(az_rad, dtype=float), np.asarray(el_rad, dtype=float))
    total_az, total_el = _combine(terms, coeffs, az, el, feed_rad, _FUNCTIONS, _argument, np.cos,
                                  aux)
    return total_az + np.zeros(az.shape), total_el + np.zeros(az.shape)


def _combine(terms, coeffs, az, el, feed, functions, argument, cos, aux=None):
    cache: dict[Factor, Any] = {}
    total_az = total_el = 0.0
    for term, coeff in zip(terms, coeffs, strict=True):
        if coeff == 0.0:
            continue
        for axis, sign, factors in term.components:
            value = sign * coeff
            for factor in factors:
                f = cache.get(factor)
                if f is None:
                    func, arg, mult = factor
                    if isinstance(arg, Regressor):  # one value per side: not cached
                        f = functions[func](mult * arg.value(aux, _side(axis)))
                    else:
                        f = functions[func](mult * argument(arg, az, el, feed))
                        cache[factor] = f
                value = value * f
            if axis == "A":
                total_az = total_az + value
            elif axis == "E":
                total_el = total_el + value
            else:
                total_az = total_az + value / cos(el)
    return total_az, total_el


def _t(name, desc, *components, kind="angle") -> Term:
    return Term(name, desc, tuple((ax, float(sg), tuple(fs)) for ax, sg, fs in components), kind)


SIN_AN, COS_AN = ("sin", "AN", 1), ("cos", "AN", 1)
TAN_E, SEC_E, COT_E = ("tan", "E", 1), ("sec", "E", 1), ("cot", "E", 1)
SIN_E, COS_E = ("sin", "E", 1), ("cos", "E", 1)


# ---------------------------------------------------------------------------------------------
# TPOINT's basic terms (alt-az mount)
# ---------------------------------------------------------------------------------------------
def _tpoint_terms() -> dict[str, Term]:
    terms = [
        _t("IA", "azimuth index (encoder zero): dA = -IA", ("A", -1, ())),
        _t("IE", "elevation index (encoder zero): dE = +IE", ("E", 1, ())),
        _t("CA", "collimation, left-right: dA = -CA sec E", ("A", -1, (SEC_E,))),
        _t("NPAE", "az/el axis non-perpendicularity: dA = -NPAE tan E", ("A", -1, (TAN_E,))),
        # TPOINT's AN and AW (tptPterms, terms 31 and 32) in its azimuth A_T = 180 deg - A_N:
        # dA_T = +AN sin A_T tan E, dE = +AN cos A_T ("the pole of the mounting is north of
        # the zenith"); dA_T = -AW cos A_T tan E, dE = +AW sin A_T ("west of the zenith").
        # Written in A_N (sin A_T = sin A_N, cos A_T = -cos A_N, dA_N = -dA_T):
        _t("AN", "azimuth axis tilt, pole north of the zenith: dA = -AN sin A tan E, "
           "dE = -AN cos A (A North-based)",
           ("A", -1, (SIN_AN, TAN_E)), ("E", -1, (COS_AN,))),
        _t("AW", "azimuth axis tilt, pole west of the zenith: dA = -AW cos A tan E, "
           "dE = +AW sin A (A North-based)",
           ("A", -1, (COS_AN, TAN_E)), ("E", 1, (SIN_AN,))),
        _t("TF", "tube flexure (gravitational sag), cos E law: dE = -TF cos E",
           ("E", -1, (COS_E,))),
        _t("TX", "tube flexure / refraction error, cot E law: dE = -TX cot E",
           ("E", -1, (COT_E,))),
        # TPOINT's ACES and ACEC are its harmonics HASA and HACA (tptPterms, terms 34 and
        # 35: dA_T = ACES sin A_T, ACEC cos A_T): written in A_N, dA = -ACES sin A_N,
        # +ACEC cos A_N (tested equal to HASA, HACA column by column)
        _t("ACEC", "azimuth centering error, cos component: dA = +ACEC cos A (A North-based)",
           ("A", 1, (COS_AN,))),
        _t("ACES", "azimuth centering error, sin component: dA = -ACES sin A (A North-based)",
           ("A", -1, (SIN_AN,))),
        _t("ECEC", "elevation centering error, cos component: dE = +ECEC cos E",
           ("E", 1, (COS_E,))),
        _t("ECES", "elevation centering error, sin component: dE = +ECES sin E",
           ("E", 1, (SIN_E,))),
        # TPOINT's Nasmyth rotator displacements (P. T. Wallace, TPOINT routine tptPterms,
        # revision of 14 November 2006, terms 38 and 39): left-right on the sky
        # NRX cos E and elevation -NRX sin E; left-right NRY sin E and elevation +NRY cos E.
        # Functions of the elevation only: the image at a Nasmyth focus turns with the
        # elevation, so a displacement of the rotator's axis draws this circle on the sky.
        # Left-right is minus dA cos E here (as CA's), elevation as it is (as IE's).
        _t("NRX", "Nasmyth rotator displacement: dA cos E = -NRX cos E, dE = -NRX sin E",
           ("S", -1, (COS_E,)), ("E", -1, (SIN_E,))),
        _t("NRY", "Nasmyth rotator displacement: dA cos E = -NRY sin E, dE = +NRY cos E",
           ("S", -1, (SIN_E,)), ("E", 1, (COS_E,))),
    ]
    return {t.name: t for t in terms}


# ---------------------------------------------------------------------------------------------
# TPOINT harmonic generator
# ---------------------------------------------------------------------------------------------
_HARMONIC = re.compile(r"^H([AESZ])([SC])([AEZF])(\d*)(?:([SC])([AEZF])(\d*))?$")

#: result letter -> (axis, sign): TPOINT's dA and dA cos E results are minus the harmonic
#: (as its IA and CA are), dE is plus it and dZ = -dE (see the module docstring)
_HARMONIC_RESULT = {"A": ("A", -1), "E": ("E", 1), "S": ("S", -1), "Z": ("E", -1)}


def harmonic_factors(f1: str, a1: str, n1: str, f2: str | None, a2: str | None,
                     n2: str | None) -> list[tuple[str, str, int]] | None:
    """The (S/C, argument letter, multiplier) factors of a harmonic name's regex groups (a
    missing multiplier is 1); ``None`` for a zero multiplier. Shared by the alt-az and the
    equatorial (:mod:`controller.pointing.equatorial`) generators."""
    raw = [(f1, a1, int(n1) if n1 else 1)]
    if f2:
        raw.append((f2, a2, int(n2) if n2 else 1))
    return None if any(n == 0 for _, _, n in raw) else raw


def _harmonic(name: str) -> Term | None:
    m = _HARMONIC.match(name)
    if not m:
        return None
    result, *groups = m.groups()
    raw = harmonic_factors(*groups)
    if raw is None:
        return None
    factors = tuple(
        ("sin" if f == "S" else "cos", "AT" if a == "A" else a, n) for f, a, n in raw
    )
    axis, sign = _HARMONIC_RESULT[result]
    words = {"A": "dA = -", "E": "dE = ", "S": "dA cos E = -", "Z": "dZ = "}
    desc = " * ".join(f"{'sin' if f == 'S' else 'cos'}({'' if n == 1 else n}"
                      f"{'A_T' if a == 'A' else a})" for f, a, n in raw)
    if any(a == "A" for _, a, _ in raw):
        desc += ", A_T = 180 deg - A_N"
    return _t(name, f"harmonic: {words[result]}{name} {desc}", (axis, sign, factors))


# ---------------------------------------------------------------------------------------------
# TPOINT polynomial terms
# ---------------------------------------------------------------------------------------------
_POLYNOMIAL = re.compile(r"^P([AESZ])([AEZ])(\d?)(?:([AEZ])(\d?))?$")


def _polynomial(name: str) -> Term | None:
    """TPOINT's polynomial terms: ``P`` + result letter (as the harmonics': A, E, S, Z) +
    one or two factors, each a coordinate (E elevation, Z zenith distance, radians) and its
    power 1..9 (1 if left out): ``PEE1`` is dE = +PEE1 E, an elevation scale error (the
    coefficient is the error at E = 1 rad), ``PSE2`` dA cos E = -PSE2 E^2. The result signs
    are the harmonics' (TPOINT's dA and dA cos E results minus, dE plus, dZ = -dE), as in
    RTS2's TPOINT terms PHH and PDD (dH = PHH H, dDec = PDD Dec). Polynomials in the
    azimuth (``PAA1``) are refused (:func:`term_refusal`)."""
    m = _POLYNOMIAL.match(name)
    if not m:
        return None
    result, a1, n1, a2, n2 = m.groups()
    raw = [(a1, int(n1 or 1))] + ([(a2, int(n2 or 1))] if a2 else [])
    if any(a == "A" for a, _ in raw) or any(n == 0 for _, n in raw):
        return None
    factors = tuple(("lin" if n == 1 else f"pow{n}", a, 1) for a, n in raw)
    axis, sign = _HARMONIC_RESULT[result]
    words = {"A": "dA = ", "E": "dE = ", "S": "dA cos E = ", "Z": "dZ = "}
    power = " * ".join(a if n == 1 else f"{a}^{n}" for a, n in raw)
    return _t(name, f"polynomial: {words[result]}{'-' if result in 'AS' else '+'}{name} "
              f"{power} (radians)", (axis, sign, factors), kind="scale")


# ---------------------------------------------------------------------------------------------
# Ghigo (1990) W1..W10, section II of the report: indicated - true, North-based azimuth; the
# TPOINT correction is the negative, hence the minus signs below. The azimuth terms are
# written as dA (the report's dA cos E divided by cos E), which is exact at every elevation.
# ---------------------------------------------------------------------------------------------
def _ghigo_terms() -> dict[str, Term]:
    terms = [
        _t("W1", "elevation encoder offset: dE = W1", ("E", -1, ())),
        _t("W2", "elevation axis misalignment (= W8): dE = W2 cos A", ("E", -1, (COS_AN,))),
        _t("W3", "azimuth axis misalignment (= -W7): dE = W3 sin A", ("E", -1, (SIN_AN,))),
        _t("W4", "gravitational sag: dE = W4 cos E", ("E", -1, (COS_E,))),
        _t("W5", "refraction: dE = W5 cot E", ("E", -1, (COT_E,))),
        _t("W6", "azimuth encoder offset: dA cos E = W6 cos E", ("A", -1, ())),
        _t("W7", "azimuth axis misalignment (= -W3): dA cos E = W7 cos A sin E",
           ("A", -1, (COS_AN, TAN_E))),
        _t("W8", "elevation axis misalignment (= W2): dA cos E = W8 sin A sin E",
           ("A", -1, (SIN_AN, TAN_E))),
        _t("W9", "non-perpendicularity of azimuth and elevation axes: dA cos E = W9 sin E",
           ("A", -1, (TAN_E,))),
        _t("W10", "non-perpendicularity of beam centre and elevation axis: dA cos E = W10",
           ("A", -1, (SEC_E,))),
    ]
    return {t.name: t for t in terms}


# ---------------------------------------------------------------------------------------------
# katpoint P1..P22 (katpoint.PointingModel.offset: indicated - true, North-based azimuth);
# negated like Ghigo's.
# ---------------------------------------------------------------------------------------------
def _katpoint_terms() -> dict[str, Term]:
    def kp(name, desc, *components, kind="angle"):
        flipped = tuple((ax, -sg, fs) for ax, sg, fs in components)
        return _t(name, f"katpoint {name}: {desc}", *flipped, kind=kind)

    terms = [
        kp("P1", "az offset: daz = P1", ("A", 1, ())),
        kp("P2", "az gravitational sag (unused by katpoint for alt-az)"),
        kp("P3", "left-right axis skew: daz = P3 tan E", ("A", 1, (TAN_E,))),
        kp("P4", "collimation: daz = -P4 sec E", ("A", -1, (SEC_E,))),
        kp("P5", "tilt out: daz = P5 sin A tan E, del = P5 cos A",
           ("A", 1, (SIN_AN, TAN_E)), ("E", 1, (COS_AN,))),
        kp("P6", "tilt over: daz = -P6 cos A tan E, del = P6 sin A",
           ("A", -1, (COS_AN, TAN_E)), ("E", 1, (SIN_AN,))),
        kp("P7", "el offset: del = P7", ("E", 1, ())),
        kp("P8", "gravity sag: del = P8 cos E", ("E", 1, (COS_E,))),
        kp("P9", "el excess scale: del = P9 E", ("E", 1, (("lin", "E", 1),)), kind="scale"),
        kp("P10", "cos E in del, redundant with P8 (unused by katpoint)"),
        kp("P11", "asymmetric sag: del = P11 sin E", ("E", 1, (SIN_E,))),
        kp("P12", "az excess scale: daz = P12 A", ("A", 1, (("lin", "AN", 1),)), kind="scale"),
        kp("P13", "az centering: daz = P13 cos A", ("A", 1, (COS_AN,))),
        kp("P14", "az centering: daz = P14 sin A", ("A", 1, (SIN_AN,))),
        kp("P15", "el nod twice per turn: del = P15 cos 2A", ("E", 1, (("cos", "AN", 2),))),
        kp("P16", "el nod twice per turn: del = P16 sin 2A", ("E", 1, (("sin", "AN", 2),))),
        kp("P17", "az encoder tilt: daz = P17 cos 2A", ("A", 1, (("cos", "AN", 2),))),
        kp("P18", "az encoder tilt: daz = P18 sin 2A", ("A", 1, (("sin", "AN", 2),))),
        kp("P19", "el encoder scale distortion: del = P19 cos 8E", ("E", 1, (("cos", "E", 8),))),
        kp("P20", "el encoder scale distortion: del = P20 sin 8E", ("E", 1, (("sin", "E", 8),))),
        kp("P21", "el nod once per turn: del = P21 cos A", ("E", 1, (COS_AN,))),
        kp("P22", "el nod once per turn: del = P22 sin A", ("E", 1, (SIN_AN,))),
    ]
    return {t.name: t for t in terms}


# ---------------------------------------------------------------------------------------------
# Wright (1992, BIMA memo 23) equations (1) and (2): a(1)..a(7) in dA cos E, b(1)..b(7) in dE,
# North-based azimuth. Sign: indicated - true (what is added to the catalogue position), the
# reading under which b(7) = 0.84-0.87' on every antenna (Table 1) is the optical refraction
# at Hat Creek (about 0.87' cot E at 1043 m); negated like Ghigo's.
# ---------------------------------------------------------------------------------------------
def _wright_terms() -> dict[str, Term]:
    s2a, c2a = ("sin", "AN", 2), ("cos", "AN", 2)
    terms = [
        _t("A1", "a(1) azimuth encoder + mount offset from the meridian: dA cos E = a1 cos E",
           ("S", -1, (COS_E,))),
        _t("A2", "a(2) collimation of the optical or radio axis: dA cos E = a2", ("S", -1, ())),
        _t("A3", "a(3) elevation axis misaligned to the azimuth axis: dA cos E = a3 sin E",
           ("S", -1, (SIN_E,))),
        _t("A4", "a(4) tilt of the azimuth axis: dA cos E = a4 sin E sin A",
           ("S", -1, (SIN_E, SIN_AN))),
        _t("A5", "a(5) tilt of the azimuth axis: dA cos E = a5 sin E cos A",
           ("S", -1, (SIN_E, COS_AN))),
        _t("A6", "a(6) residual: dA cos E = a6 cos E sin 2A", ("S", -1, (COS_E, s2a))),
        _t("A7", "a(7) residual: dA cos E = a7 cos E cos 2A", ("S", -1, (COS_E, c2a))),
        _t("B1", "b(1) elevation encoder offset: dE = b1", ("E", -1, ())),
        _t("B2", "b(2) elevation axis error: dE = b2 sin E", ("E", -1, (SIN_E,))),
        _t("B3", "b(3) elevation axis error: dE = b3 cos E", ("E", -1, (COS_E,))),
        _t("B4", "b(4) tilt of the azimuth axis: dE = b4 sin A", ("E", -1, (SIN_AN,))),
        _t("B5", "b(5) tilt of the azimuth axis: dE = b5 cos A", ("E", -1, (COS_AN,))),
        _t("B6", "b(6) Fourier analysis residual: dE = b6 sin 2A", ("E", -1, (s2a,))),
        _t("B7", "b(7) refraction: dE = b7 cot E", ("E", -1, (COT_E,))),
    ]
    return {t.name: t for t in terms}


_FIXED: dict[str, Term] = {**_tpoint_terms(), **_ghigo_terms(), **_katpoint_terms(),
                           **_wright_terms()}

#: Where Wright's a(i), b(i) coincide with TPOINT's terms: coefficient = sign * TPOINT's
#: (tested column by column in tests/end_to_end/test_bima.py).
WRIGHT_EQUIVALENTS: dict[str, tuple[str, float]] = {
    "A1": ("IA", 1.0),
    "A2": ("CA", 1.0),
    "A3": ("NPAE", 1.0),
    "A4": ("HSSASE", 1.0),
    "A5": ("HSCASE", -1.0),
    "A6": ("HASA2", -1.0),
    "A7": ("HACA2", 1.0),
    "B1": ("IE", -1.0),
    "B2": ("HESE", -1.0),
    "B3": ("TF", 1.0),
    "B4": ("HESA", -1.0),
    "B5": ("HECA", 1.0),
    "B6": ("HESA2", 1.0),
    "B7": ("TX", 1.0),
}

#: Where Ghigo's W terms coincide with TPOINT's: W = sign * TPOINT coefficient (tested). Each
#: W fitted on its own (as the report fits ten) is one TPOINT term or harmonic.
GHIGO_EQUIVALENTS: dict[str, tuple[str, float]] = {
    "W1": ("IE", -1.0),
    "W2": ("HECA", 1.0),
    "W3": ("HESA", -1.0),
    "W4": ("TF", 1.0),
    "W5": ("TX", 1.0),
    "W6": ("IA", 1.0),
    "W7": ("HSCASE", -1.0),
    "W8": ("HSSASE", 1.0),
    "W9": ("NPAE", 1.0),
    "W10": ("CA", 1.0),
}

#: The report's tied pairs (section II: W2 = W8, W3 = -W7) are TPOINT's azimuth-axis tilt:
#: a tilt AN is W2 = W8 = AN, a tilt AW is W3 = -W7 = -AW, i.e. TPOINT term = sum of
#: (sign * W term) over the pair, as basis columns (tested).
GHIGO_TILT: dict[str, tuple[tuple[str, float], tuple[str, float]]] = {
    "AN": (("W2", 1.0), ("W8", 1.0)),
    "AW": (("W3", -1.0), ("W7", 1.0)),
}

#: Fomalont's 1973 coefficients (the 1990 report's Appendix A) on the report's functions:
#: C1..C5 in dA cos E, D1..D5 in dE (the feed terms C6/C7, D6/D7 are HSCF/HSSF, HECF/HESF).
FOMALONT_NAMES: dict[str, str] = {
    "C1": "W6", "C2": "W7", "C3": "W8", "C4": "W9", "C5": "W10",
    "D1": "W1", "D2": "W2", "D3": "W3", "D4": "W4", "D5": "W5",
}

#: Where katpoint's P terms coincide with TPOINT's: P = sign * TPOINT coefficient (tested).
#: P5/P6 are the azimuth-axis tilt and equal +AN/-AW in both axes at once. P2 and P10 are
#: unused by katpoint; P9 and P12 are scale factors with no TPOINT twin here.
KATPOINT_EQUIVALENTS: dict[str, tuple[str, float]] = {
    "P1": ("IA", 1.0),
    "P3": ("NPAE", 1.0),
    "P4": ("CA", -1.0),
    "P5": ("AN", 1.0),
    "P6": ("AW", -1.0),
    "P7": ("IE", -1.0),
    "P8": ("TF", 1.0),
    "P11": ("HESE", -1.0),
    "P13": ("HACA", -1.0),
    "P14": ("HASA", 1.0),
    "P15": ("HECA2", -1.0),
    "P16": ("HESA2", 1.0),
    "P17": ("HACA2", 1.0),
    "P18": ("HASA2", -1.0),
    "P19": ("HECE8", -1.0),
    "P20": ("HESE8", -1.0),
    "P21": ("HECA", 1.0),
    "P22": ("HESA", -1.0),
}


#: terms other modules build from this one's pieces (controller.pointing.thermal's, which
#: the package imports first): name -> term
_REGISTERED: dict[str, Term] = {}


def register_terms(terms: dict[str, Term]) -> None:
    """Make ``terms`` known to :func:`get_term` by name (names must be new)."""
    clash = sorted(set(terms) & (set(_FIXED) | set(_REGISTERED)))
    if clash:
        raise ValueError(f"term names already taken: {', '.join(clash)}")
    _REGISTERED.update(terms)
    get_term.cache_clear()


@lru_cache(maxsize=512)
def get_term(name: str) -> Term:
    """The term called ``name`` (TPOINT name, harmonic, W1..W10, P1..P22, Wright's
    A1..A7, B1..B7, or a thermal term of :mod:`controller.pointing.thermal`)."""
    key = name.strip().upper()
    if key in _FIXED:
        return _FIXED[key]
    if key in _REGISTERED:
        return _REGISTERED[key]
    term = _harmonic(key) or _polynomial(key)
    if term is None:
        problem, hint = term_refusal(key)
        raise TermError(f"{problem} {name!r}: {hint}" if problem == "unknown pointing term"
                        else f"{problem}; {hint}")
    return term


#: the terms any unknown name is told about
KNOWN_TERMS = ("a TPOINT name (IA IE CA NPAE AN AW TF TX ACEC ACES ECEC ECES NRX NRY), a "
               "harmonic such as HESA2 or HSCA2CE, a polynomial such as PEE1, W1..W10, "
               "P1..P22, A1..A7, B1..B7, or a thermal term (TEDFB TSDRL TEYFB TSYRL TNPNS "
               "TWPEW, proxies TESUN TEFACE TSSIDE TNSUN TWSUN TEAIR)")

#: TPOINT terms antsim knows of but cannot define from public documents, and why
NOT_ESTABLISHED: dict[str, str] = {
    "TX10": "is TPOINT's variant of TX, whose definition no public TPOINT document "
            "establishes (docs/assumptions.md)",
}


def term_refusal(name: str) -> tuple[str, str]:
    """(problem, hint) for a name :func:`get_term` does not know: TPOINT terms whose
    definition public documents do not establish are said to be so."""
    key = name.strip().upper()
    if key in NOT_ESTABLISHED:
        return f"{key} {NOT_ESTABLISHED[key]}", "fit TX (dE = -TX cot E) instead"
    m = _POLYNOMIAL.match(key)
    if m and "A" in (m.group(2), m.group(4)):
        return (f"{key} is a TPOINT polynomial in the azimuth, whose value depends on the "
                "range TPOINT takes the azimuth in, which no public TPOINT document "
                "establishes", "use harmonics (HACA, HASA, ...) or katpoint's P12 (dA = P12 A, "
                "North-based)")
    return "unknown pointing term", f"use {KNOWN_TERMS}"


def is_term_name(name: str) -> bool:
    """Whether ``name`` names a known term."""
    try:
        get_term(name)
    except TermError:
        return False
    return True

"""Pointing models: a named, ordered set of linear terms with their coefficients.

Like katpoint's ``PointingModel``: ``offset`` gives what must be added to a requested (true)
position to obtain the position to command the encoders to, ``apply`` adds it, ``reverse``
inverts ``apply`` iteratively, and ``fit`` returns a :class:`~controller.pointing.result.FitResult`
without changing the model. Models are immutable; ``with_values`` makes a new one.

Signs: coefficients are stored in each vocabulary's own sign (TPOINT names as TPOINT prints
them, W1..W10 as Ghigo, P1..P22 as katpoint) and in arcsec. ``offset`` is "indicated minus
true" = minus the TPOINT correction; see :mod:`controller.pointing.terms`.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from astropy import units as u

from controller.units import ARCSEC_PER_RAD, RAD_PER_ARCSEC, to_value

from .data import PointingData
from .terms import Term, combine_arrays, combine_scalar, evaluate_basis, get_term
from .thermal import thermal_regressors

__all__ = ["NAMED_MODELS", "PointingModel", "named_model_terms"]

#: Named term lists. ``ghigo10`` is the 45-ft model of the 1990 report, ``tpoint8`` the
#: eight physical terms TPOINT users start from, ``katpoint22`` katpoint's full model.
NAMED_MODELS: dict[str, tuple[str, ...]] = {
    "none": (),
    "ghigo10": tuple(f"W{i}" for i in range(1, 11)),
    "tpoint8": ("IA", "IE", "NPAE", "CA", "AN", "AW", "TF", "TX"),
    "tpoint6": ("IA", "IE", "NPAE", "CA", "AN", "AW"),
    "katpoint22": tuple(f"P{i}" for i in range(1, 23)),
    #: BIMA memo 23 (Wright 1992), equations (1) and (2): a(1)..a(7), b(1)..b(7) by name
    "wright14": (*(f"A{i}" for i in range(1, 8)), *(f"B{i}" for i in range(1, 8))),
    #: the same 7 + 7 terms in TPOINT's names, in the memo's order (controller.pointing.bima)
    "bima14": ("IA", "CA", "NPAE", "HSSASE", "HSCASE", "HASA2", "HACA2",
               "IE", "HESE", "TF", "HESA", "HECA", "HESA2", "TX"),
    #: Fomalont 1973 (1990 report, Appendix A): the 45-ft's ten terms and the feed terms
    #: C6 cos(f - C7) (cross-elevation) and D6 cos(f - D7) (elevation), linear in cos f, sin f
    "fomalont14": (*(f"W{i}" for i in range(1, 11)), "HSCF", "HSSF", "HECF", "HESF"),
}


def named_model_terms(name: str) -> tuple[str, ...]:
    """Term names of the named model ``name`` (KeyError with the choices if unknown)."""
    try:
        return NAMED_MODELS[name]
    except KeyError:
        raise KeyError(
            f"unknown model {name!r}; known models: {', '.join(sorted(NAMED_MODELS))}"
        ) from None


@dataclass(frozen=True, eq=False)
class PointingModel:
    """An immutable pointing model: term names, coefficients in arcsec, and a name."""

    terms: tuple[Term, ...]
    values_arcsec: np.ndarray
    name: str = "custom"

    def __init__(
        self,
        terms: Iterable[str | Term] | str = (),
        values_arcsec: Sequence[float] | np.ndarray | Mapping[str, float] | None = None,
        name: str | None = None,
    ):
        if isinstance(terms, str):
            model_name = terms
            terms = named_model_terms(terms)
            name = name or model_name
        term_objs = tuple(t if isinstance(t, Term) else get_term(t) for t in terms)
        names = [t.name for t in term_objs]
        if len(set(names)) != len(names):
            dup = sorted({n for n in names if names.count(n) > 1})
            raise ValueError(f"pointing model lists term(s) {', '.join(dup)} more than once")
        if values_arcsec is None:
            values = np.zeros(len(term_objs))
        elif isinstance(values_arcsec, Mapping):
            unknown = set(values_arcsec) - set(names)
            if unknown:
                raise ValueError(f"values given for terms not in the model: {sorted(unknown)}")
            values = np.array([float(values_arcsec.get(n, 0.0)) for n in names])
        else:
            values = np.array(values_arcsec, dtype=float).reshape(-1)
            if values.size != len(term_objs):
                raise ValueError(f"{values.size} values for {len(term_objs)} terms")
        values.setflags(write=False)
        object.__setattr__(self, "terms", term_objs)
        object.__setattr__(self, "values_arcsec", values)
        object.__setattr__(self, "name", name or "custom")

    # ------------------------------------------------------------------ basic properties
    @property
    def names(self) -> tuple[str, ...]:
        return tuple(t.name for t in self.terms)

    def __len__(self) -> int:
        return len(self.terms)

    def __getitem__(self, name: str) -> float:
        """Coefficient of term ``name`` in arcsec."""
        return float(self.values_arcsec[self.names.index(name.upper())])

    def as_dict(self) -> dict[str, float]:
        """``{term name: value in arcsec}`` in model order."""
        return {n: float(v) for n, v in zip(self.names, self.values_arcsec, strict=True)}

    def with_values(self, values_arcsec, name: str | None = None) -> PointingModel:
        """A copy with new coefficients (sequence in model order, or a mapping)."""
        if isinstance(values_arcsec, Mapping):
            merged = self.as_dict()
            unknown = set(values_arcsec) - set(merged)
            if unknown:
                raise ValueError(f"values given for terms not in the model: {sorted(unknown)}")
            merged.update({k: float(v) for k, v in values_arcsec.items()})
            values_arcsec = list(merged.values())
        return PointingModel(self.terms, values_arcsec, name or self.name)

    def __repr__(self) -> str:
        body = ", ".join(f"{n}={v:+.2f}\"" for n, v in self.as_dict().items())
        return f"PointingModel({self.name!r}: {body})"

    # ------------------------------------------------------------------ evaluation (floats)
    @property
    def needs_feed(self) -> bool:
        """Whether a term has a feed-angle factor (``F``): evaluation needs ``feed_rad``."""
        cached = self.__dict__.get("_needs_feed")
        if cached is None:
            cached = any(f[1] == "F" for t in self.terms for _, _, fs in t.components
                         for f in fs)
            object.__setattr__(self, "_needs_feed", cached)
        return cached

    @property
    def regressors(self) -> frozenset[str]:
        """The recorded quantities the model's thermal terms read (``aux`` of
        :meth:`design_matrix`); empty for a model of the position alone."""
        cached = self.__dict__.get("_regressors")
        if cached is None:
            cached = frozenset(thermal_regressors(self.terms))
            object.__setattr__(self, "_regressors", cached)
        return cached

    def design_matrix(self, az_rad, el_rad, feed_rad=None,
                      aux=None) -> tuple[np.ndarray, np.ndarray]:
        """TPOINT-sign correction basis, each of shape ``(N, M)``: dA and dE per radian.
        ``feed_rad``: feed angle(s), needed only by feed terms (see :attr:`needs_feed`);
        ``aux``: recorded quantities, name -> (cross-elevation, elevation) arrays, needed only
        by thermal terms (see :attr:`regressors`)."""
        az, el = np.broadcast_arrays(np.atleast_1d(np.asarray(az_rad, dtype=float)),
                                     np.atleast_1d(np.asarray(el_rad, dtype=float)))
        if feed_rad is not None:
            feed_rad = np.broadcast_to(np.asarray(feed_rad, dtype=float), az.shape).reshape(-1)
        return evaluate_basis(self.terms, az.reshape(-1), el.reshape(-1), feed_rad, aux)

    def offset_rad(self, az_rad, el_rad, feed_rad=None, aux=None) -> tuple[np.ndarray, np.ndarray]:
        """Indicated minus true (daz, del) in radians at true position(s), plain floats."""
        shape = np.broadcast(np.asarray(az_rad), np.asarray(el_rad)).shape
        if not self.terms:
            return np.zeros(shape), np.zeros(shape)
        basis_az, basis_el = self.design_matrix(az_rad, el_rad, feed_rad, aux)
        coeff_rad = self.values_arcsec * RAD_PER_ARCSEC
        return -(basis_az @ coeff_rad).reshape(shape), -(basis_el @ coeff_rad).reshape(shape)

    def offset_scalar_rad(self, az_rad: float, el_rad: float,
                          feed_rad: float | None = None, aux=None) -> tuple[float, float]:
        """:meth:`offset_rad` without a basis matrix (a fast path for simulations): plain
        floats at one point, element by element for arrays (an ensemble's member axis)."""
        combine = combine_arrays if np.ndim(az_rad) or np.ndim(el_rad) else combine_scalar
        corr_az, corr_el = combine(self.terms, self._coeff_rad, az_rad, el_rad, feed_rad, aux)
        return -corr_az, -corr_el

    @property
    def _coeff_rad(self) -> list[float]:
        cached = self.__dict__.get("_coeff_cache")
        if cached is None:
            cached = [float(v) * RAD_PER_ARCSEC for v in self.values_arcsec]
            object.__setattr__(self, "_coeff_cache", cached)
        return cached

    def apply_rad(self, az_rad, el_rad) -> tuple[np.ndarray, np.ndarray]:
        """Encoder position to command for true position(s), radians."""
        d_az, d_el = self.offset_rad(az_rad, el_rad)
        return np.asarray(az_rad) + d_az, np.asarray(el_rad) + d_el

    def reverse_rad(self, enc_az_rad, enc_el_rad, tol_rad: float = 1e-4 / ARCSEC_PER_RAD,
                    max_iter: int = 30) -> tuple[np.ndarray, np.ndarray]:
        """True position(s) that ``apply`` maps onto the given encoder position(s).

        Fixed-point iteration ``x <- enc - offset(x)``: the offset changes by far less than
        an arcsec per arcmin of position for any physical model, so it contracts fast
        (typically 3-4 iterations to 0.1 mas).
        """
        enc_az = np.asarray(enc_az_rad, dtype=float)
        enc_el = np.asarray(enc_el_rad, dtype=float)
        az, el = enc_az.copy(), enc_el.copy()
        for _ in range(max_iter):
            d_az, d_el = self.offset_rad(az, el)
            new_az, new_el = enc_az - d_az, enc_el - d_el
            step = np.hypot((new_az - az) * np.cos(new_el), new_el - el)
            az, el = new_az, new_el
            if np.all(step < tol_rad):
                return az, el
        raise ArithmeticError(
            "pointing model reverse did not converge; the model is too large or singular here"
        )

    # ------------------------------------------------------------------ Quantity API
    def offset(self, az, el):
        """Indicated minus true at true position(s): ``(daz, del)`` as Quantity (arcsec)."""
        d_az, d_el = self.offset_rad(to_value(az, "rad", "az"), to_value(el, "rad", "el"))
        return (d_az * ARCSEC_PER_RAD) * u.arcsec, (d_el * ARCSEC_PER_RAD) * u.arcsec

    def apply(self, az, el):
        """Encoder position to command for a true position: ``(az, el)`` Quantity (deg)."""
        a, e = self.apply_rad(to_value(az, "rad", "az"), to_value(el, "rad", "el"))
        return (np.degrees(a)) * u.deg, (np.degrees(e)) * u.deg

    def reverse(self, az, el):
        """True position for an encoder position: inverse of :meth:`apply` (Quantity, deg)."""
        a, e = self.reverse_rad(to_value(az, "rad", "az"), to_value(el, "rad", "el"))
        return (np.degrees(a)) * u.deg, (np.degrees(e)) * u.deg

    def fit(self, az, el, d_xel, d_el, **options):
        """Fit this model's terms to measured pointing errors; returns a ``FitResult``.

        ``d_xel``, ``d_el``: total pointing error, indicated minus true, cross-elevation and
        elevation (Quantity). The model itself is not changed; ``result.model`` is the fit.
        """
        data = PointingData(
            az_rad=np.atleast_1d(to_value(az, "rad", "az")),
            el_rad=np.atleast_1d(to_value(el, "rad", "el")),
            xel_arcsec=np.atleast_1d(to_value(d_xel, "arcsec", "d_xel")),
            el_arcsec=np.atleast_1d(to_value(d_el, "arcsec", "d_el")),
        )
        # the fitter brings scipy (0.3 s): imported when a model is first fitted, so that
        # importing a model (every controller and simulator module does) stays cheap
        from .robust import fit_terms

        start = PointingModel(list(self.names), name=options.pop("name", "custom"))
        return fit_terms(data, start, **options)

"""Fitting a pointing model to pointing data: :func:`fit_model`, the entry point.

The pieces: the data (:class:`~controller.pointing.data.PointingData`), the procedure in the
1990 report's stages and TPOINT's statistics (:mod:`controller.pointing.robust`), the linear
algebra (:mod:`controller.pointing.solvers`), the honest error bars
(:mod:`controller.pointing.jackknife`) and the result
(:class:`~controller.pointing.result.FitResult`). :func:`fit_model` takes the terms by name
(or a named model); :meth:`PointingModel.fit <controller.pointing.model.PointingModel.fit>`
fits a model's own terms.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence

import numpy as np

from .data import PointingData, require_pointing_data
from .jackknife import BLOCK_PHASES, BLOCK_S, JackknifeResult
from .model import NAMED_MODELS, PointingModel
from .result import FitResult, readonly
from .robust import LAD_FACTOR, RMS_FACTOR, fit_terms
from .terms import Term

__all__ = ["fit_model", "without_fixed"]


def _resolve_terms(terms: Sequence[str | Term] | str, name: str) -> PointingModel:
    if isinstance(terms, str):
        if terms in NAMED_MODELS:
            return PointingModel(NAMED_MODELS[terms], name=terms if name == "custom" else name)
        raise ValueError(
            f"terms must be a sequence of term names, not the string {terms!r}; "
            f"named models are {', '.join(sorted(NAMED_MODELS))}"
        )
    return PointingModel(list(terms), name=name)


def fit_model(
    data: PointingData,
    terms: Sequence[str],
    *,
    robust: bool = True,
    weighted: bool = False,
    name: str = "custom",
    lad_factor: float = LAD_FACTOR,
    rms_factor: float = RMS_FACTOR,
    block_s: float = BLOCK_S,
    block_phases: int = BLOCK_PHASES,
    fixed: Mapping[str, float] | None = None,
) -> FitResult:
    """Fit the linear pointing terms ``terms`` to ``data`` by the 1990 report's procedure
    (:mod:`controller.pointing.robust`).

    Besides TPOINT's sigma, the result carries honest error bars of the same coefficients: the
    cluster jackknife covariance (CV3, MacKinnon, Nielsen and Webb 2023) ``(G-1)/G sum_g d_g
    d_g^T`` of the exact leave-one-cluster-out changes ``d_g = -(A^T A - A_g^T A_g)^-1 A_g^T
    r_g``. With few clusters (the ~24 one-hour blocks of a day) the plain sandwich (CV1) is
    optimistic, because each cluster's own residuals are pulled towards the fit (by its
    leverage); the jackknife removes that. Each observation's xel and el rows form one cluster,
    so the two axes' different scatter is respected (TPOINT scales every term by the Sky RMS,
    which is sqrt(2) times the per-equation scatter for isotropic errors and ignores that xel
    and el residuals differ); with ``data.t_s`` the observations are further grouped in time
    blocks of ``block_s`` so that residuals correlated over minutes to an hour (thermal drifts,
    slow wander) are allowed for; the variance is the mean over ``block_phases`` block grids,
    each shifted by 1/``block_phases`` of a block (less noisy than one grid, the same
    expectation). With so few clusters the jackknife variance is itself noisy
    and (error / sigma) follows a t distribution: ``sigma_honest_arcsec`` is the jackknife
    sigma times sqrt(nu / (nu - 2)), nu its Satterthwaite degrees of freedom, the spread of
    that t distribution (:mod:`controller.pointing.jackknife`). A robust fit's rejection makes the
    coefficients vary more than the kept residuals say; with time blocks the jackknife
    replays the last rejection in each replicate and scales the variances by the mean ratio.

    ``fixed``: terms held at the given values (arcsec) instead of fitted, as Fomalont (1973)
    held his refraction term at 1'.1 and TPOINT's ``FIX`` does: their offsets are taken off
    the data, the others fitted to the rest, and the result lists every term in order, the
    fixed ones with their value, no sigma and no correlation (``result.fixed``).

    Raises ``ValueError`` (plain sentence) for no observations, fewer used observations than
    terms, invalid factors or ``block_phases``, ``weighted=True`` without weights, a term
    that is infinite at an observation (e.g. TX at elevation 0, CA at 90 deg), or a fixed
    term that is not among ``terms``. Unknown term names raise
    :class:`~controller.pointing.terms.TermError`.
    """
    require_pointing_data(data)
    start = _resolve_terms(terms, name)
    options = {"robust": robust, "weighted": weighted, "lad_factor": lad_factor,
               "rms_factor": rms_factor, "block_s": block_s, "block_phases": block_phases}
    if not fixed:
        return fit_terms(data, start, **options)
    fixed = {n.strip().upper(): float(v) for n, v in fixed.items()}
    unknown = sorted(set(fixed) - set(start.names))
    if unknown:
        raise ValueError(f"fixed term(s) {', '.join(unknown)} are not among the terms fitted "
                         f"({', '.join(start.names)})")
    free = PointingModel([n for n in start.names if n not in fixed], name=start.name)
    return _with_fixed(fit_terms(without_fixed(data, fixed), free, **options), start, fixed)


def without_fixed(data: PointingData, fixed: Mapping[str, float] | None) -> PointingData:
    """``data`` less the offsets of the ``fixed`` terms (names upper case, values in arcsec):
    what the other terms are fitted to."""
    if not fixed:
        return data
    held = PointingModel(list(fixed), list(fixed.values()))
    d_az, d_el = held.offset_rad(data.az_rad, data.el_rad, data.feed_rad, data.aux)
    return dataclasses.replace(
        data, xel_arcsec=data.xel_arcsec - np.degrees(d_az) * 3600.0 * np.cos(data.el_rad),
        el_arcsec=data.el_arcsec - np.degrees(d_el) * 3600.0)


def _with_fixed(result: FitResult, start: PointingModel, fixed: Mapping[str, float]) -> FitResult:
    """``result`` (a fit of the free terms) with the ``fixed`` terms put back in ``start``'s
    order: their values, NaN sigmas and correlations."""
    names = start.names
    where = np.array([names.index(n) for n in result.names], dtype=int)

    def spread(vector: np.ndarray) -> np.ndarray:
        out = np.full(len(names), np.nan)
        out[where] = vector
        return out

    values = spread(result.values_arcsec)
    for n, v in fixed.items():
        values[names.index(n)] = v
    corr = np.full((len(names), len(names)), np.nan)
    corr[np.ix_(where, where)] = result.correlation
    source = result.honest_source

    def honest() -> JackknifeResult:
        j = source()
        return dataclasses.replace(j, sigma=spread(j.sigma), dof=spread(j.dof))

    return dataclasses.replace(
        result, model=start.with_values(values, name=start.name),
        sigma_arcsec=readonly(spread(result.sigma_arcsec)), correlation=readonly(corr),
        honest_source=honest if source is not None else None,
        fixed=tuple(n for n in names if n in fixed))

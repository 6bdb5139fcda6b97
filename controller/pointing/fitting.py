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

from collections.abc import Sequence

from .data import PointingData, require_pointing_data
from .jackknife import BLOCK_PHASES
from .model import NAMED_MODELS, PointingModel
from .result import FitResult
from .robust import fit_terms
from .terms import Term

__all__ = ["fit_model"]


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
    lad_factor: float = 4.0,
    rms_factor: float = 3.0,
    block_s: float = 3600.0,
    block_phases: int = BLOCK_PHASES,
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

    Raises ``ValueError`` (plain sentence) for no observations, fewer used observations than
    terms, invalid factors or ``block_phases``, ``weighted=True`` without weights, or a term
    that is infinite at an observation (e.g. TX at elevation 0, CA at 90 deg). Unknown term
    names raise :class:`~controller.pointing.terms.TermError`.
    """
    require_pointing_data(data)
    return fit_terms(data, _resolve_terms(terms, name), robust=robust, weighted=weighted,
                     lad_factor=lad_factor, rms_factor=rms_factor, block_s=block_s,
                     block_phases=block_phases)

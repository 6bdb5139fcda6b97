"""Tail probabilities of the chi-square, F and normal laws, as scipy.stats computes them.

scipy.stats's distributions call these same scipy.special functions (``chi2.sf`` is
``chdtrc``, ``f.sf`` is ``fdtrc``, ``norm.isf`` is ``-ndtri``, ``chi2.logsf`` in the tail
is the log of ``sf``), but importing scipy.stats costs most of a second of every ``antsim
diagnose``. The values here are the same bit for bit (tested), outside the support too,
except ``chi2_logsf`` near the body of the law (within 1e-9 there; it serves the far tail).
"""

from __future__ import annotations

import math

from scipy import special

__all__ = ["chi2_isf", "chi2_logsf", "chi2_sf", "f_sf", "norm_isf"]


def chi2_sf(x: float, dof: float) -> float:
    """P(chi2_dof > x); 1 for x <= 0."""
    if math.isnan(x) or math.isnan(dof) or dof <= 0:
        return math.nan
    return 1.0 if x <= 0 else float(special.chdtrc(dof, x))


def chi2_logsf(x: float, dof: float) -> float:
    """log P(chi2_dof > x). Where the probability underflows (a chi^2 of ~1400 and more),
    the tail's leading term, log Q(k/2, x/2) ~ -x/2 + (k/2 - 1) log(x/2) - log Gamma(k/2),
    instead of -inf, whose Gaussian equivalent would be NaN."""
    p = chi2_sf(x, dof)
    if math.isnan(p):
        return math.nan
    if p > 0:
        return math.log(p)
    if not math.isfinite(x):
        return -math.inf
    half_x = 0.5 * x
    return -half_x + (0.5 * dof - 1.0) * math.log(half_x) - math.lgamma(0.5 * dof)


def chi2_isf(p: float, dof: float) -> float:
    """The x with P(chi2_dof > x) = p."""
    if math.isnan(p) or math.isnan(dof) or dof <= 0 or not 0.0 <= p <= 1.0:
        return math.nan
    return float(special.chdtri(dof, p))


def f_sf(x: float, dfn: float, dfd: float) -> float:
    """P(F_{dfn, dfd} > x); 1 for x <= 0."""
    if math.isnan(x) or math.isnan(dfn) or math.isnan(dfd) or dfn <= 0 or dfd <= 0:
        return math.nan
    return 1.0 if x <= 0 else float(special.fdtrc(dfn, dfd, x))


def norm_isf(q: float) -> float:
    """The z with P(N(0,1) > z) = q."""
    if math.isnan(q) or not 0.0 <= q <= 1.0:
        return math.nan
    return float(-special.ndtri(q))

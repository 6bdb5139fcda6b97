"""Fitting pointing models: the Ghigo/Payne robust procedure with TPOINT's statistics.

Signs. The data are total pointing errors, "indicated minus true" (Ghigo's and katpoint's
sign): ``xel = dA cos E`` and ``el = dE`` at the true (observed) position. A model's TPOINT
correction is minus that, so with ``Ba, Be = PointingModel.design_matrix(az, el)`` the
equations are the stacked rows ``-xel = (Ba cos E) @ c`` and ``-el = Be @ c`` (c in arcsec).
A fitted model's :meth:`~controller.pointing.model.PointingModel.offset_rad` reproduces the data.

Procedure (``robust=True``, the 1990 report's): (1) least-absolute-deviation (LAD) fit,
(2) reject observations whose xel or el residual exceeds ``lad_factor`` times the mean
absolute residual of that axis, (3) least squares on the rest, (4) reject beyond
``rms_factor`` times that axis' rms, (5) final least squares. ``robust=False`` is plain least
squares on everything (the report's fit F; TPOINT's own fit). The means and rms are taken
over the observations still in use; rejected observations stay rejected. No threshold goes
below 1e-9 of the largest |datum|, so rounding noise in noise-free data is never "rejected".

Statistics (TPOINT's, verified on the MMT data in ``../shared/data/real/README.md``), over
the N used observations and the M fitted terms:

* Sky RMS = sqrt(mean(xel_res^2 + el_res^2)); xel and el rms separately;
* sigma_j = sqrt(diag((A^T A)^-1))_j * Sky RMS;
* Popn SD = Sky RMS * sqrt(N / (N - M)).

With ``weighted=True`` the rows are scaled by sqrt(weight) (weights are 1/sigma^2 in
1/arcsec^2), A^T A becomes the weighted normal matrix A^T W A, and sigma is scaled by the
weighted rms sqrt(mean(w_xel xel_res^2 + w_el el_res^2)) instead of the Sky RMS, so that
multiplying every weight by a constant changes nothing and unit weights give the unweighted
result. Sky RMS, the axis rms and Popn SD stay the plain (unweighted) figures in arcsec.
The robust rejection thresholds then apply to the weighted (normalised) residuals.

Rank deficiency is reported, never papered over: a term whose design column is zero over the
used observations, or whose unit-scaled column lies within ``RANK_RTOL`` (the sine of the
angle) of the span of the columns of the terms listed before it, is *unconstrained*: it is
not fitted, its value is 0 and its sigma NaN (null in JSON), and a warning names it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import cached_property, partial
from typing import Any

import numpy as np
import scipy.linalg
from scipy.optimize import linprog

from .jackknife import BLOCK_PHASES, JackknifeResult, Rejection, cluster_jackknife, within_rms
from .model import NAMED_MODELS, PointingModel
from .terms import Term

__all__ = [
    "CORRELATION_WARNING_LEVEL",
    "RANK_RTOL",
    "FitResult",
    "PointingData",
    "fit_model",
]

#: A term is unconstrained when its unit-length design column is within this distance (the
#: sine of the angle) of the span of the columns before it, or is this small relative to the
#: largest column. Exact dependences (W1 with IA, HESA2 with HESACA, P2's zero column) sit at
#: the 1e-16 level in floating point; a term this close to degenerate would have a sigma ten
#: orders of magnitude above the best-determined one, which is no determination at all.
RANK_RTOL = 1e-10

#: |correlation| above which TPOINT warns that two terms "cannot reliably be distinguished".
CORRELATION_WARNING_LEVEL = 0.95

# LAD through the LP dual (max y.d subject to A^T d = 0, -1 <= d <= 1: one equality row per
# term). HiGHS solves it for a few thousand rows in 20-70 ms, but its time grows steeply with
# size: 200,000 rows took 100 s with the dual simplex and 3.5 s with the interior point.
# Larger problems are therefore reduced exactly (Koenker & Portnoy 1997, "preprocessing" for
# quantile regression): a LAD fit of a random subsample shows which rows' residual signs are
# certain; those are fixed at their bound and summed into two "globs", HiGHS solves the few
# thousand remaining rows, and the solution is accepted only when every fixed sign is
# confirmed, which makes it the exact optimum of the full problem (else the band widens).
_LAD_DIRECT_ROWS = 3000
_LAD_BAND_ROWS = 3000
_LAD_SEED = 19900208  # fixed: the subsample only affects speed, never the optimum


# ---------------------------------------------------------------------------------------------
# Input data
# ---------------------------------------------------------------------------------------------
def _float_vector(value: Any, name: str) -> np.ndarray:
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError) as err:
        raise ValueError(f"{name} must be numbers; {err}") from None
    arr = np.atleast_1d(arr)
    if arr.ndim != 1:
        raise ValueError(f"{name} must be one-dimensional; it has shape {arr.shape}")
    bad = ~np.isfinite(arr)
    if bad.any():
        first = int(np.flatnonzero(bad)[0])
        raise ValueError(
            f"{name} has {int(bad.sum())} value(s) that are NaN or infinite "
            f"(first at index {first})"
        )
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True)
class PointingData:
    """Measured total pointing errors at known true positions (one row per observation).

    ``az_rad``, ``el_rad``: observed (true) azimuth (North = 0, East = pi/2) and elevation,
    radians. ``xel_arcsec``, ``el_arcsec``: total pointing error, "indicated minus true",
    cross-elevation (dA cos E) and elevation, arcsec. ``weight_xel``, ``weight_el``: optional
    1/sigma^2 weights (1/arcsec^2), used only by ``fit_model(..., weighted=True)``.
    ``t_s``: optional observation times (s); with them the honest error bars allow for
    residuals correlated in time (see :func:`fit_model`). ``feed_rad``: optional feed
    (rotator) angle of each observation (rad), the regressor of feed terms such as ``HSCF``.
    For an equatorial mount ``az_rad``/``el_rad`` hold hour angle and declination and
    ``xel_arcsec`` the cross-declination error dH cos(dec) (see
    :mod:`controller.pointing.equatorial`).

    The arrays are validated on construction (1-D, same length, finite, |el| <= pi/2,
    positive weights) and stored as read-only copies.
    """

    az_rad: np.ndarray
    el_rad: np.ndarray
    xel_arcsec: np.ndarray
    el_arcsec: np.ndarray
    weight_xel: np.ndarray | None = None
    weight_el: np.ndarray | None = None
    t_s: np.ndarray | None = None
    feed_rad: np.ndarray | None = None

    def __post_init__(self) -> None:
        names = ("az_rad", "el_rad", "xel_arcsec", "el_arcsec")
        arrays = {n: _float_vector(getattr(self, n), n) for n in names}
        if (self.weight_xel is None) != (self.weight_el is None):
            raise ValueError("give both weight_xel and weight_el, or neither")
        if self.weight_xel is not None:
            for n in ("weight_xel", "weight_el"):
                w = _float_vector(getattr(self, n), n)
                if (w <= 0).any():
                    first = int(np.flatnonzero(w <= 0)[0])
                    raise ValueError(
                        f"{n} must be positive (1/sigma^2); index {first} is {w[first]}"
                    )
                arrays[n] = w
        if self.t_s is not None:
            arrays["t_s"] = _float_vector(self.t_s, "t_s")
        if self.feed_rad is not None:
            arrays["feed_rad"] = _float_vector(self.feed_rad, "feed_rad")
        lengths = {n: a.size for n, a in arrays.items()}
        if len(set(lengths.values())) > 1:
            detail = ", ".join(f"{n} {k}" for n, k in lengths.items())
            raise ValueError(f"pointing data arrays differ in length: {detail}")
        el = arrays["el_rad"]
        # 1e-12 rad of slack: an elevation of exactly 90 deg converted from degrees may land
        # a rounding error above pi/2.
        outside = np.abs(el) > math.pi / 2 + 1e-12
        if outside.any():
            first = int(np.flatnonzero(outside)[0])
            raise ValueError(
                f"el_rad must lie within +-pi/2 radians; index {first} is {el[first]:.6g} "
                "(degrees given where radians are expected?)"
            )
        for n, a in arrays.items():
            object.__setattr__(self, n, a)

    def __len__(self) -> int:
        return int(self.az_rad.size)

    @property
    def weighted(self) -> bool:
        """Whether weights are present."""
        return self.weight_xel is not None

    def select(self, mask) -> PointingData:
        """A new ``PointingData`` holding the observations where ``mask`` is true."""
        keep = np.asarray(mask, dtype=bool)
        if keep.shape != self.az_rad.shape:
            raise ValueError(f"mask has shape {keep.shape}, the data {self.az_rad.shape}")
        return PointingData(
            self.az_rad[keep], self.el_rad[keep], self.xel_arcsec[keep], self.el_arcsec[keep],
            None if self.weight_xel is None else self.weight_xel[keep],
            None if self.weight_el is None else self.weight_el[keep],
            None if self.t_s is None else self.t_s[keep],
            None if self.feed_rad is None else self.feed_rad[keep],
        )


# ---------------------------------------------------------------------------------------------
# Result
# ---------------------------------------------------------------------------------------------
def _json_float(x: float) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.array(a, copy=True)
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class FitResult:
    """The outcome of :func:`fit_model`. Arrays are read-only; nothing here mutates inputs.

    ``model``: the fitted :class:`~controller.pointing.model.PointingModel` (unconstrained terms 0).
    ``sigma_arcsec``: per term, NaN for unconstrained terms. ``used``: mask of the observations
    in the final fit. ``residual_*_arcsec``: data minus fitted model for ALL observations,
    rejected ones included. ``correlation``: M x M, NaN in rows/columns of unconstrained terms.
    ``condition_number``: 2-norm condition number of the final design matrix of the fitted
    (constrained) terms with columns scaled to unit length. ``warnings``: plain sentences.
    ``sigma_honest_arcsec``: honest error bars of the same coefficients: the cluster
    jackknife (CV3) standard error ``sigma_jackknife_arcsec`` times sqrt(nu / (nu - 2)), nu
    its Satterthwaite degrees of freedom ``honest_dof`` (see :mod:`controller.pointing.jackknife`),
    so that (error / sigma_honest) spreads by 1; ``honest_clusters`` the clusters used,
    ``honest_phases`` the time-block grids averaged. These are computed on first use.
    """

    model: PointingModel
    sigma_arcsec: np.ndarray
    n_input: int
    n_used: int
    n_rejected: int
    used: np.ndarray
    residual_xel_arcsec: np.ndarray
    residual_el_arcsec: np.ndarray
    sky_rms_arcsec: float
    xel_rms_arcsec: float
    el_rms_arcsec: float
    popn_sd_arcsec: float
    condition_number: float
    correlation: np.ndarray
    unconstrained: tuple[str, ...]
    warnings: tuple[str, ...] = ()
    robust: bool = True
    weighted: bool = False
    n_fitted: int = 0
    #: the rms (arcsec, or dimensionless when weighted) that scales sqrt(diag((A^T W A)^-1))
    sigma_scale: float = field(default=float("nan"))
    honest_block_s: float | None = None
    #: computes the honest error bars on first use (they cost about a third of a fit of
    #: 100,000 observations, and many callers need only TPOINT's statistics)
    honest_source: Callable[[], JackknifeResult] | None = field(
        default=None, repr=False, compare=False)

    @cached_property
    def _jackknife(self) -> JackknifeResult | None:
        return None if self.honest_source is None else self.honest_source()

    @property
    def sigma_honest_arcsec(self) -> np.ndarray | None:
        j = self._jackknife
        return None if j is None else _readonly(j.sigma_t_scaled)

    @property
    def sigma_jackknife_arcsec(self) -> np.ndarray | None:
        j = self._jackknife
        return None if j is None else _readonly(j.sigma)

    @property
    def honest_dof(self) -> np.ndarray | None:
        j = self._jackknife
        return None if j is None else _readonly(j.dof)

    @property
    def honest_clusters(self) -> int:
        j = self._jackknife
        return 0 if j is None else j.clusters

    @property
    def honest_phases(self) -> int:
        """Time-block grids whose jackknife variances were averaged (1 without times)."""
        j = self._jackknife
        return 0 if j is None else j.phases

    @property
    def names(self) -> tuple[str, ...]:
        return self.model.names

    @property
    def values_arcsec(self) -> np.ndarray:
        return self.model.values_arcsec

    def to_json(self) -> dict:
        """The ``antsim fit --json`` document (DESIGN section 4): plain types, null for NaN."""
        names = list(self.names)
        return {
            "n_input": int(self.n_input),
            "n_used": int(self.n_used),
            "n_rejected": int(self.n_rejected),
            "model": self.model.name,
            "terms": {
                n: {"value_arcsec": _json_float(v), "sigma_arcsec": _json_float(s),
                    "sigma_honest_arcsec": _json_float(h)}
                for n, v, s, h in zip(names, self.model.values_arcsec, self.sigma_arcsec,
                                      self._honest(), strict=True)
            },
            "sky_rms_arcsec": _json_float(self.sky_rms_arcsec),
            "xel_rms_arcsec": _json_float(self.xel_rms_arcsec),
            "el_rms_arcsec": _json_float(self.el_rms_arcsec),
            "popn_sd_arcsec": _json_float(self.popn_sd_arcsec),
            "condition_number": _json_float(self.condition_number),
            "correlations": {
                "names": names,
                "matrix": [[_json_float(x) for x in row] for row in self.correlation],
            },
            "unconstrained": list(self.unconstrained),
            "honest_sigma": {
                "method": "cluster jackknife (CV3) of the same least-squares coefficients, "
                          "clusters = observations"
                          + (f" within {self.honest_block_s:g} s time blocks"
                             + (f", variances averaged over {self.honest_phases} block grids "
                                f"shifted by 1/{self.honest_phases} block"
                                if self.honest_phases > 1 else "")
                             if self.honest_block_s else "")
                          + (", scaled by the mean variance ratio of replicates that repeat the "
                             "fit's outlier rejection" if self.robust and self.honest_block_s
                             else "")
                          + ", times sqrt(dof/(dof-2)) for its Satterthwaite degrees of freedom",
                "clusters": int(self.honest_clusters),
                "dof": {n: _json_float(v) for n, v in zip(
                    names, self.honest_dof if self.honest_dof is not None
                    else np.full(len(names), np.nan), strict=True)},
            },
        }

    def _honest(self) -> np.ndarray:
        if self.sigma_honest_arcsec is None:
            return np.full(len(self.names), np.nan)
        return self.sigma_honest_arcsec

    def table(self) -> str:
        """Fixed-width text table of term, value and sigma (arcsec) for humans."""
        width = max([8, *(len(n) for n in self.names)])
        value_head, sigma_head = 'value (")', 'sigma (")'
        lines = [f"{'term':<{width}}  {value_head:>12}  {sigma_head:>10}"]
        for n, v, s in zip(self.names, self.model.values_arcsec, self.sigma_arcsec, strict=True):
            sigma = f"{s:10.4f}" if math.isfinite(s) else f"{'not fitted':>10}"
            lines.append(f"{n:<{width}}  {v:+12.4f}  {sigma}")
        return "\n".join(lines)

    def summary(self) -> str:
        """Table plus the TPOINT statistics and the warnings, as printed by ``antsim fit``."""
        how = "robust (LAD, 4x MAD, LSQ, 3x rms, LSQ)" if self.robust else "plain least squares"
        lines = [
            f"model {self.model.name}: {self.n_used} of {self.n_input} observations used, "
            f"{self.n_rejected} rejected; {how}{', weighted' if self.weighted else ''}",
            self.table(),
            f"Sky RMS = {self.sky_rms_arcsec:.3f}\"   Popn SD = {self.popn_sd_arcsec:.3f}\"   "
            f"(xel rms {self.xel_rms_arcsec:.3f}\", el rms {self.el_rms_arcsec:.3f}\")",
            f"condition number {self.condition_number:.3g}",
        ]
        lines += [f"warning: {w}" for w in self.warnings]
        return "\n".join(lines)


# ---------------------------------------------------------------------------------------------
# Linear algebra
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class _Rank:
    """Which columns of a design the data determine, and why the others are not."""

    kept: tuple[int, ...]
    reasons: dict[int, str]


def _rank_analysis(r_unit: np.ndarray, col_norms: np.ndarray, names: Sequence[str]) -> _Rank:
    """Decide, in model order, which columns are independent.

    ``r_unit`` is the R factor of the design with unit-length columns (so column j of R has
    the geometry of column j of the design); ``col_norms`` the columns' original lengths.
    A column is kept when its distance from the span of the kept columns before it exceeds
    ``RANK_RTOL``; terms listed first win: asked for IA then W1 (the same function), IA is
    fitted and W1 reported unconstrained.
    """
    m = r_unit.shape[1]
    biggest = float(col_norms.max()) if m else 0.0
    kept: list[int] = []
    reasons: dict[int, str] = {}
    for j in range(m):
        if biggest == 0.0 or col_norms[j] <= RANK_RTOL * biggest:
            reasons[j] = "its basis is zero at every used observation"
            continue
        v = r_unit[:, j]
        if kept:
            basis = r_unit[:, kept]
            q, _ = np.linalg.qr(basis)
            resid = v - q @ (q.T @ v)
        else:
            resid = v
        if np.linalg.norm(resid) > RANK_RTOL:
            kept.append(j)
            continue
        coef, *_ = np.linalg.lstsq(r_unit[:, kept], v, rcond=None)
        partners = [names[k] for k, c in zip(kept, coef, strict=True) if abs(c) > 1e-6]
        reasons[j] = "it is indistinguishable from " + (
            " and ".join(partners) if len(partners) <= 2 else ", ".join(partners)
        ) + " over the used observations"
    return _Rank(tuple(kept), reasons)


@dataclass(frozen=True)
class _Solution:
    coeffs: np.ndarray  # (M,), 0 for unconstrained
    cov_unscaled: np.ndarray  # (M, M) (A^T W A)^-1, NaN for unconstrained
    rank: _Rank
    condition_number: float


# OpenBLAS multithreads level-2 BLAS calls above ~8000 matrix elements, and its worker threads
# then busy-wait; on the 2-core machine this doubled the wall time of a fit and made it erratic
# (0.6-1.9 s for the benchmark). The large-array products below therefore stay out of BLAS:
# QR in row blocks small enough to run single-threaded, matrix-vector products with einsum.
_QR_BLOCK_ELEMENTS = 6000


def _matvec(a: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``a @ x`` without BLAS (see the note on OpenBLAS threads)."""
    return np.einsum("ij,j...->i...", a, x)


def _r_factor(a: np.ndarray) -> np.ndarray:
    """Upper-triangular R (k x k) of the Householder QR of a tall (rows x k) matrix.

    Tall-skinny QR: LAPACK's geqrf on row blocks of ~6000 elements, then on the stacked
    R factors, recursively. As stable as one Householder QR (each step is one), faster on
    200,000 x 11 designs because blocks stay in cache, and single-threaded in OpenBLAS.
    """
    k = a.shape[1]
    (geqrf,) = scipy.linalg.get_lapack_funcs(("geqrf",), (a,))
    block = max(2 * k, _QR_BLOCK_ELEMENTS // max(k, 1))

    def r_of(part: np.ndarray) -> np.ndarray:
        qr, _tau, _work, info = geqrf(part)
        if info != 0:
            raise ArithmeticError(f"LAPACK geqrf failed (info = {info})")
        return np.triu(qr[: min(part.shape), :])

    current = a
    while current.shape[0] > block:
        current = np.vstack([r_of(current[i:i + block]) for i in range(0, current.shape[0], block)])
    r = r_of(current)
    if r.shape[0] < k:  # fewer rows than columns: pad to square
        r = np.vstack([r, np.zeros((k - r.shape[0], k))])
    return r


def _unit_columns(a: np.ndarray, y: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Fortran-ordered [A / norms | y] and the column norms (zero columns left as they are)."""
    norms = np.linalg.norm(a, axis=0)
    scale = np.where(norms > 0, norms, 1.0)
    out = np.empty((a.shape[0], a.shape[1] + (y is not None)), order="F")
    np.divide(a, scale, out=out[:, : a.shape[1]])
    if y is not None:
        out[:, -1] = y
    return out, norms


def _least_squares(a: np.ndarray, y: np.ndarray, names: Sequence[str]) -> _Solution:
    """Least squares by one Householder QR of [A | y] with unit-scaled columns."""
    m = a.shape[1]
    aug, norms = _unit_columns(a, y)
    scale = np.where(norms > 0, norms, 1.0)
    r_aug = _r_factor(aug)
    r_unit = r_aug[:m, :m]
    z = r_aug[:m, m]
    rank = _rank_analysis(r_unit, norms, names)
    coeffs = np.zeros(m)
    cov = np.full((m, m), np.nan)
    cond = float("nan")
    if rank.kept:
        k = list(rank.kept)
        q2, r2 = np.linalg.qr(r_unit[:, k])
        c_unit = scipy.linalg.solve_triangular(r2, q2.T @ z)
        r2_inv = scipy.linalg.solve_triangular(r2, np.eye(len(k)))
        cov_unit = r2_inv @ r2_inv.T
        coeffs[k] = c_unit / scale[k]
        cov[np.ix_(k, k)] = cov_unit / np.outer(scale[k], scale[k])
        cond = float(np.linalg.cond(r2))
    return _Solution(coeffs, cov, rank, cond)


def _independent_columns(a: np.ndarray, names: Sequence[str]) -> _Rank:
    unit, norms = _unit_columns(a)
    return _rank_analysis(_r_factor(unit), norms, names)


# ---------------------------------------------------------------------------------------------
# Least absolute deviation through the LP dual
# ---------------------------------------------------------------------------------------------
def _lad_lp(a: np.ndarray, y: np.ndarray, lower: np.ndarray, upper: np.ndarray):
    """Solve max y.d subject to A^T d = 0, lower <= d <= upper with HiGHS.

    Returns (coefficients, d). The LAD coefficients are minus HiGHS's equality marginals:
    linprog minimises -y.d, and its marginals are the sensitivities of that objective to the
    equality right-hand sides (checked against a direct evaluation of sum |y - A c|).
    """
    # Interior point (with HiGHS's crossover to a vertex, hence exact marginals) was as fast as
    # the dual simplex on these LPs and much faster on large ones; presolve finds nothing to
    # remove here and only costs time.
    res = linprog(
        -y, A_eq=a.T, b_eq=np.zeros(a.shape[1]), bounds=np.column_stack([lower, upper]),
        method="highs-ipm", options={"presolve": False},
    )
    if res.status != 0:
        raise ArithmeticError(f"the least-absolute-deviation step failed in HiGHS: {res.message}")
    return -np.asarray(res.eqlin.marginals, dtype=float), np.asarray(res.x, dtype=float)


def _lad_full(a: np.ndarray, y: np.ndarray) -> np.ndarray:
    ones = np.ones(a.shape[0])
    return _lad_lp(a, y, -ones, ones)[0]


def _lad_dense(a: np.ndarray, y: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Exact LAD coefficients for a full-column-rank ``a`` (rows x p)."""
    n, p = a.shape
    if n <= max(2 * _LAD_DIRECT_ROWS, 40 * p):
        return _lad_full(a, y)
    # A subsample of m rows gives coefficients good to ~sqrt(p/m) of the residual scale, so
    # the rows whose residual sign is then uncertain number ~kappa sqrt(p/m) n, with kappa ~4
    # found on correlated, misfitted designs (tpoint8 on Ghigo-type errors). Choose m so that
    # this band is ~_LAD_BAND_ROWS (recursively, so every LP stays small); a band that proves
    # too narrow costs one more small LP, never a wrong answer.
    m = int(min(n // 2, max(_LAD_DIRECT_ROWS, 16 * p * (n / _LAD_BAND_ROWS) ** 2)))
    sub = np.sort(rng.choice(n, size=m, replace=False))
    coeffs = _lad_dense(a[sub], y[sub], rng)
    # Prediction scale sqrt(x_i^T (A_S^T A_S)^-1 x_i): how far each row's fitted value can
    # move when the subsample estimate is replaced by the full one. Only a ranking is needed,
    # so the Cholesky factor of the small Gram matrix is accurate enough.
    try:
        a_sub = a[sub]
        chol = scipy.linalg.cholesky(np.einsum("ij,ik->jk", a_sub, a_sub), lower=False)
    except np.linalg.LinAlgError:  # subsample happens to be degenerate: no shortcut
        return _lad_full(a, y)
    leverage = np.linalg.norm(_matvec(a, scipy.linalg.solve_triangular(chol, np.eye(p))), axis=1)
    resid = y - _matvec(a, coeffs)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(leverage > 0, np.abs(resid) / leverage, np.inf)
    tol = 1e-9 * max(1.0, float(np.abs(y).max()))
    band = int(max(_LAD_BAND_ROWS, 40 * p, 4 * math.sqrt(p / m) * n))
    forced = np.zeros(n, dtype=bool)
    # The band stays centred on the subsample estimate: a failed reduced solution can be far
    # off (its globs were wrong), so it is never used to re-centre.
    for _ in range(30):
        if band + forced.sum() >= n // 2:
            break
        kept = forced.copy()
        kept[np.argpartition(z, band - 1)[:band]] = True
        above = ~kept & (resid > 0)
        below = ~kept & ~above
        rows = [a[kept]]
        rhs = [y[kept]]
        n_globs = 0
        for group, sign in ((above, 1.0), (below, -1.0)):
            if group.any():
                rows.append(sign * a[group].sum(axis=0, keepdims=True))
                rhs.append([sign * y[group].sum()])
                n_globs += 1
        k = int(kept.sum())
        lower = np.concatenate([-np.ones(k), np.zeros(n_globs)])
        upper = np.ones(k + n_globs)
        trial, d = _lad_lp(np.vstack(rows), np.concatenate(rhs), lower, upper)
        trial_resid = y - _matvec(a, trial)
        wrong = (above & (trial_resid < -tol)) | (below & (trial_resid > tol))
        if not wrong.any() and bool(np.all(d[k:] >= 1 - 1e-9)):
            return trial  # every fixed sign confirmed: the exact optimum of the full problem
        if 0 < wrong.sum() <= 0.1 * band:
            forced |= wrong
        else:
            band *= 2
    return _lad_full(a, y)


def _lad(a: np.ndarray, y: np.ndarray, n_xel: int | None = None) -> np.ndarray:
    """Exact LAD fit of ``y ~ a @ c``.

    When the first ``n_xel`` rows (cross-elevation) and the rest (elevation) involve disjoint
    sets of columns, the problem separates and each half is solved alone: Ghigo's ten terms
    split into five azimuth and five elevation terms. Rows whose design is zero add a
    constant and are dropped.
    """
    p = a.shape[1]
    nonzero_rows = (a != 0).any(axis=1)
    blocks: list[np.ndarray] = [np.arange(p)]
    if n_xel is not None and 0 < n_xel < a.shape[0]:
        in_xel = (a[:n_xel] != 0).any(axis=0)
        in_el = (a[n_xel:] != 0).any(axis=0)
        if not (in_xel & in_el).any():
            blocks = [np.flatnonzero(in_xel), np.flatnonzero(in_el)]
    rng = np.random.default_rng(_LAD_SEED)
    coeffs = np.zeros(p)
    for cols in blocks:
        if cols.size == 0:
            continue
        rows = (a[:, cols] != 0).any(axis=1) & nonzero_rows
        coeffs[cols] = _lad_dense(a[np.ix_(rows, cols)], y[rows], rng)
    return coeffs


# ---------------------------------------------------------------------------------------------
# The fitter
# ---------------------------------------------------------------------------------------------
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
    """Fit the linear pointing terms ``terms`` to ``data``; see the module docstring.

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
    if not isinstance(data, PointingData):
        raise TypeError(f"data must be a PointingData, not {type(data).__name__}")
    start = _resolve_terms(terms, name)
    names = start.names
    m = len(names)
    n = len(data)
    if m == 0:
        raise ValueError("no terms to fit: give at least one pointing term")
    if n == 0:
        raise ValueError("there are no observations to fit")
    for label, factor in (("lad_factor", lad_factor), ("rms_factor", rms_factor)):
        if not (math.isfinite(factor) and factor > 0):
            raise ValueError(f"{label} must be a positive number, not {factor!r}")
    if isinstance(block_phases, bool) or not isinstance(block_phases, int) or block_phases < 1:
        raise ValueError(f"block_phases must be a whole number >= 1, not {block_phases!r}")
    if weighted and not data.weighted:
        raise ValueError("weighted=True needs weight_xel and weight_el in the data")
    if n < m:
        raise ValueError(f"{n} observations cannot determine {m} terms; observe more positions")

    cos_el = np.cos(data.el_rad)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # checked just below
        basis_az, basis_el = start.design_matrix(data.az_rad, data.el_rad, data.feed_rad)
    design = np.empty((2 * n, m), order="F")  # column-major, as LAPACK works on it
    np.multiply(basis_az, cos_el[:, None], out=design[:n])
    design[n:] = basis_el
    if not np.all(np.isfinite(design)):
        row, col = np.argwhere(~np.isfinite(design))[0]
        obs = row % n
        raise ValueError(
            f"term {names[col]} is infinite at observation {obs} (elevation "
            f"{math.degrees(data.el_rad[obs]):.4f} deg); remove the term or the observation"
        )
    target = -np.concatenate([data.xel_arcsec, data.el_arcsec])
    if weighted:
        root_w = np.sqrt(np.concatenate([data.weight_xel, data.weight_el]))
        a_w = np.asfortranarray(design * root_w[:, None])
        y_w = target * root_w
    else:
        a_w, y_w = design, target

    def normalised_residuals(coeffs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        r = y_w - _matvec(a_w, coeffs)
        return np.abs(r[:n]), np.abs(r[n:])

    def check_enough(used: np.ndarray, stage: str) -> None:
        k = int(used.sum())
        if k < m:
            raise ValueError(
                f"only {k} observations remain after {stage}, fewer than the {m} terms; "
                "the data are too few or too discrepant for this model"
            )

    # Rounding noise must not count as an outlier: on noise-free data the residuals are
    # ~1e-13 and a threshold of 4x their mean would reject at random. No threshold goes
    # below 1e-9 of the largest |datum| (1e-9" on errors of an arcsec).
    floor = 1e-9 * float(np.abs(y_w).max())
    used = np.ones(n, dtype=bool)
    if robust:
        rank = _independent_columns(a_w, names)
        coeffs = np.zeros(m)
        if rank.kept:
            k = list(rank.kept)
            coeffs[k] = _lad(a_w[:, k], y_w, n)
        abs_x, abs_e = normalised_residuals(coeffs)
        used &= ((abs_x <= max(lad_factor * abs_x.mean(), floor))
                 & (abs_e <= max(lad_factor * abs_e.mean(), floor)))
        check_enough(used, "rejecting beyond lad_factor x the mean absolute deviation")
        kept_lad = used.copy()
        rows = np.concatenate([used, used])
        sol = _least_squares(a_w[rows], y_w[rows], names)
        used = within_rms(*normalised_residuals(sol.coeffs), used, rms_factor, floor)
        check_enough(used, "rejecting beyond rms_factor x the rms")

    rows = np.concatenate([used, used])
    sol = _least_squares(a_w[rows], y_w[rows], names)
    coeffs = sol.coeffs
    fitted = _matvec(design, coeffs)  # TPOINT correction rows; the fitted error is minus this
    res_x = data.xel_arcsec + fitted[:n]
    res_e = data.el_arcsec + fitted[n:]

    n_used = int(used.sum())
    n_fitted = len(sol.rank.kept)
    ux, ue = res_x[used], res_e[used]
    sky = math.sqrt(float(np.mean(ux**2 + ue**2)))
    xel_rms = math.sqrt(float(np.mean(ux**2)))
    el_rms = math.sqrt(float(np.mean(ue**2)))
    if weighted:
        scale = math.sqrt(float(np.mean(data.weight_xel[used] * ux**2
                                        + data.weight_el[used] * ue**2)))
    else:
        scale = sky
    popn = sky * math.sqrt(n_used / (n_used - n_fitted)) if n_used > n_fitted else float("nan")
    sigma = np.sqrt(np.diag(sol.cov_unscaled)) * scale
    honest_source = partial(cluster_jackknife, a_w, y_w - _matvec(a_w, coeffs), used,
                            list(sol.rank.kept), n, data.t_s, block_s,
                            Rejection(kept_lad, rms_factor, floor, y_w) if robust else None,
                            block_phases)
    with np.errstate(invalid="ignore", divide="ignore"):
        sd = np.sqrt(np.diag(sol.cov_unscaled))
        corr = sol.cov_unscaled / np.outer(sd, sd)

    unconstrained = tuple(names[j] for j in range(m) if j not in sol.rank.kept)
    messages = [
        f"{names[j]} cannot be determined from these data ({reason}); it was not fitted and "
        "is reported as 0 with no sigma"
        for j, reason in sorted(sol.rank.reasons.items())
    ]
    for i in range(m):
        for j in range(i + 1, m):
            r = corr[i, j]
            if math.isfinite(r) and abs(r) > CORRELATION_WARNING_LEVEL:
                messages.append(
                    f"{names[i]} and {names[j]} cannot reliably be distinguished (r = {r:.2f})"
                )

    return FitResult(
        model=start.with_values(coeffs, name=start.name),
        sigma_arcsec=_readonly(sigma),
        n_input=n,
        n_used=n_used,
        n_rejected=n - n_used,
        used=_readonly(used),
        residual_xel_arcsec=_readonly(res_x),
        residual_el_arcsec=_readonly(res_e),
        sky_rms_arcsec=sky,
        xel_rms_arcsec=xel_rms,
        el_rms_arcsec=el_rms,
        popn_sd_arcsec=popn,
        condition_number=sol.condition_number,
        correlation=_readonly(corr),
        unconstrained=unconstrained,
        warnings=tuple(messages),
        robust=robust,
        weighted=weighted,
        n_fitted=n_fitted,
        sigma_scale=scale,
        honest_block_s=block_s if data.t_s is not None else None,
        honest_source=honest_source,
    )

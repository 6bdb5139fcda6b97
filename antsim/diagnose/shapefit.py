"""A candidate's test from inner products with the model's kept factor: the fast path.

A candidate's test (:meth:`.candidates.base.Candidate.linear_test`) is, by definition, the
added-variable fit of its columns on the scans a model with it keeps
(:meth:`.problem.Problem.mask_fit`: outliers rejected from every valid scan, twice), made
by explicit projections: a QR of the model over those scans, and the columns projected off
it. At 200,000 scans that is a factorization per candidate and shape. :func:`shape_fit`
reaches the same masks and numbers (to rounding) from one pass over the model's factor over
its own used scans, which :class:`.factors.ModelFactors` keeps, or says it cannot (None) and
the explicit path serves.

The algebra (white noise: whitening is a weight per row). With the model in its basis
q = A_U R^-1 over its used scans U and x the whitened columns over U, every row i of the
valid scans has model coordinates g_i (q_i on U, a_i R^-1 elsewhere), the data's residual
e_i of the model's fit over U (z_perp on U) and the columns' part p_i = x_i - g_i^T q^T x
left by that fit. Over U, sum g g^T = I, sum g p^T = 0, sum g e = 0, sum p e = x^T z_perp
and sum p p^T = x^T x - (q^T x)^T (q^T x) (Frisch-Waugh-Lovell from inner products); over
any other set of scans S these sums change by the rows S adds and removes
(:func:`rows_fit`), so the fit of model + columns over S is a small (m + k) system. Its
residuals on U are z_perp_i - x_i c - q_i d (d the change of the model's coordinates):
|q_i d| <= |q_i| |d|, so only rows whose z_perp_i - x_i c lies within that of OUTLIER_Z can
fall on the other side; those rows are computed exactly, and the mask is the same set.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .linalg import gram_solve, near_rows, shape_products
from .problem import OUTLIER_Z, Problem

__all__ = ["ABSORBED_WHOLE_1MR2", "GRAM_1MR2_MIN", "ROW_UPDATE_MAX", "RowsFit", "ShapeFit",
           "ShapeSums", "rows_fit", "shape_fit"]

#: :func:`shape_fit` corrects the model's fit over its used scans by at most this many rows
#: (another set of scans); beyond, the explicit path factors the model over it
ROW_UPDATE_MAX = 4096

#: the least 1 - R^2 of a column on the model at which :func:`shape_fit` takes its norm off
#: the model from x^T x - (q^T x)^T (q^T x): the difference loses log10(1 / (1 - R^2)) of
#: the 16 digits, here at most 5 (11 kept: relative error about 2.2e-16 / (1 - R^2) <=
#: 2.2e-11, far below the 6 significant digits diagnose prints); closer columns take the
#: explicit projection
GRAM_1MR2_MIN = 1e-5

#: a candidate whose every (raw) column has a 1 - R^2 on the model below this is absorbed
#: whole (four decades below the candidates' ABSORBED_1MR2, beyond the Gram's rounding): it
#: tests nothing (0 parameters, as the explicit path finds), so no figure depends on its
#: fit, and :func:`shape_fit` gives it the mask of the model alone (the explicit path's
#: fits the columns' parts off the model, at most 1e-5 of them: the same scans but where a
#: residual lies within about 1e-3 of OUTLIER_Z)
ABSORBED_WHOLE_1MR2 = 1e-10


@dataclass
class ShapeFit:
    """:func:`shape_fit`: the scans a model with the candidate keeps and, over them, the
    candidate's columns (then ``raw``'s) projected off the model as inner products."""

    mask: np.ndarray
    gram: np.ndarray  # (kk, kk) X_perp^T X_perp over ``mask``
    rhs: np.ndarray  # (kk,) X_perp^T z_perp over ``mask``
    chi2_now: float  # z_perp^T z_perp over ``mask`` (the model alone)
    full_sq: np.ndarray  # (kk,) squared norms of the whitened columns over ``mask``
    #: the candidate's coefficients over ``mask``, of the columns the model leaves a part of
    #: (ABSORBED_WHOLE_1MR2; none: the model absorbs its signature whole)
    coef: np.ndarray
    cov: np.ndarray  # (k, k) their covariance (whitened units)
    x: np.ndarray  # (2 n_used, kk) the whitened columns over the model's used scans
    qx: np.ndarray  # (m, kk) q^T x there (q the model's basis)
    #: (m, m) the whitened model's Gram over ``mask`` in q's coordinates (R^-T A^T A R^-1,
    #: R the model's factor over its used scans; the identity over them)
    model_gram: np.ndarray
    #: (m, kk) the columns' least-squares coefficients on the model over ``mask``, in q's
    #: coordinates (R times the model's coefficients; q^T x over the used scans)
    on_model: np.ndarray


@dataclass(frozen=True)
class ShapeSums:
    """The sums over the model's used scans U of the model (basis ``q``), the candidate's
    whitened columns ``x`` and the data, and the other valid scans' rows: what
    :func:`rows_fit` corrects for another set of scans."""

    q: np.ndarray  # (2 n_used, m) the model's basis over U
    x: np.ndarray  # (2 n_used, kk) the whitened columns over U
    qx: np.ndarray  # (m, kk) q^T x
    z_perp: np.ndarray  # (2 n_used,) the data off the model over U
    gram: np.ndarray  # (kk, kk) x^T x - (q^T x)^T (q^T x): the columns off the model
    xz: np.ndarray  # (kk,) x^T z_perp
    xx: np.ndarray  # (kk, kk) x^T x
    zz: float  # z_perp^T z_perp
    coords_o: np.ndarray  # (rows, m) the model's coordinates on the other valid rows
    part_o: np.ndarray  # (rows, kk) the columns' part the model's fit over U leaves there
    x_o: np.ndarray  # (rows, kk) the whitened columns there
    resid_o: np.ndarray  # (rows,) the data's residual there of the model's fit over U


@dataclass(frozen=True)
class RowsFit:
    """:func:`rows_fit`: the fit of model + columns over another set of scans, the model's
    block eliminated."""

    schur: np.ndarray  # (kk, kk) the columns' Gram off the model (Schur complement)
    rhs: np.ndarray  # (kk,) its right-hand side
    chi2_now: float  # chi^2 of the model alone
    full_sq: np.ndarray  # (kk,) squared norms of the whitened columns
    coef: np.ndarray  # the ``fitted`` columns' coefficients
    cov: np.ndarray  # and their covariance
    shift: np.ndarray  # (m,) the change of the model's coordinates with the columns fitted
    model_gram: np.ndarray  # (m, m) the model's Gram in q's coordinates
    on_model: np.ndarray  # (m, kk) the columns' coefficients on the model, q's coordinates


def rows_fit(s: ShapeSums, rm: np.ndarray, ad: np.ndarray, fitted: np.ndarray
             ) -> RowsFit | None:
    """The fit over the used scans less the rows ``rm`` (positions on them) plus the rows
    ``ad`` (positions among the other valid rows): the sums over the used scans corrected
    by those rows, the model's block eliminated. None where the rows removed carry half of
    some direction of the model, or :func:`gram_solve` refuses the columns ``fitted``."""
    q, x, qx = s.q, s.x, s.qx
    m, kk = q.shape[1], x.shape[1]
    full_sq = np.diag(s.xx).copy()
    if rm.size or ad.size:
        q_rm = q[rm]
        g = np.vstack([q_rm, s.coords_o[ad]])
        p = np.vstack([x[rm] - q_rm @ qx, s.part_o[ad]])
        e = np.concatenate([s.z_perp[rm], s.resid_o[ad]])
        sign = np.concatenate([-np.ones(rm.size), np.ones(ad.size)])
        gs = g.T * sign
        w, v = np.linalg.eigh(np.eye(m) + gs @ g)
        if w[0] < 0.5:
            return None
        ps = p.T * sign
        cgp = gs @ p
        model = (v * w) @ v.T
        sg = (v / w) @ (v.T @ np.column_stack([cgp, gs @ e]))
        schur = s.gram + ps @ p - cgp.T @ sg[:, :kk]
        rhs = s.xz + ps @ e - cgp.T @ sg[:, kk]
        chi2_now = s.zz + float((e * sign) @ e) - float((gs @ e) @ sg[:, kk])
        full_sq += np.vstack([x[rm], s.x_o[ad]]).T ** 2 @ sign
    else:
        sg = np.zeros((m, kk + 1))
        schur, rhs, chi2_now, model = s.gram, s.xz, s.zz, np.eye(m)
    solved = gram_solve(schur[np.ix_(fitted, fitted)], rhs[fitted])
    if solved is None:
        return None
    coef, cov = solved
    return RowsFit(schur, rhs, chi2_now, full_sq, coef, cov, sg[:, kk] - sg[:, fitted] @ coef,
                   model, qx + sg[:, :kk])


def shape_fit(problem: Problem, raw: np.ndarray) -> ShapeFit | None:
    """:meth:`.problem.Problem.mask_fit` of the candidate's columns (raw ``raw`` (2n, k),
    scaled by :meth:`.problem.Problem.cand`) and the fit over the mask it returns, from one
    pass over the model's kept basis over its used scans U (``q^T x``), not two factors and
    projections: the same masks and numbers to rounding (see the module docstring), or None
    where the explicit path must serve (correlated noise, dependent model columns, an
    ill-conditioned candidate Gram, more than :data:`ROW_UPDATE_MAX` rows between U and a
    scan set tried; the caller refuses columns within :data:`GRAM_1MR2_MIN` of the span).
    The mask's fits leave out the columns within :data:`ABSORBED_WHOLE_1MR2` of the model's
    span (the explicit path fits their rounding-level remainder). Where the offset scale is
    not 1 the raw columns' norms and norms off the model come beside (the signature's, for
    absorption): x is then [scaled, raw]."""
    used = problem.used
    qr = problem.factors.qr(used) if problem.white(used) else None
    if qr is None:
        return None
    q, zp = qr.q, qr.z_perp
    other = problem.factors.other_rows(used, qr)
    uscan, oscan, idx_o, coords_o, e_o = (other.used_scans, other.other_scans, other.idx,
                                          other.coords, other.resid)
    k = raw.shape[1]
    scaled = not problem.unscaled
    idx, wu = problem.factors.rows_and_weights(used)
    f2u = np.concatenate([problem.offset_scale[uscan]] * 2) if scaled else None
    # whitened over U in Fortran order, the rows gathered once: the scaled columns (raw
    # times the offset scale, as cand() makes them) then the raw ones; the one pass over
    # the model's basis and x's inner products made as it is (shape_products)
    x, qx, xx, xz = shape_products(raw, idx, wu, f2u, q, zp)
    x_o = raw[idx_o]
    if scaled:
        x_o = np.column_stack([x_o * problem.offset_scale[idx_o % problem.n][:, None], x_o])
    x_o = x_o * problem.row_weights[idx_o][:, None]
    gram = xx - qx.T @ qx
    d = np.diag(xx)
    if not np.isfinite(xx).all() or not (d > 0).all():
        return None
    ratio = np.diag(gram) / d  # 1 - R^2 of each column on the model
    if ratio[x.shape[1] - k:].max() < ABSORBED_WHOLE_1MR2:
        fitted = np.arange(0)  # a signature the model absorbs whole: the model alone
    else:
        # the columns the model leaves a part of: one off it by rounding only (a signature
        # partly absorbed, e.g. by an accepted term) is not fitted, as a signature absorbed
        # whole is not (its direction would be rounding)
        fitted = np.flatnonzero(ratio[:k] >= ABSORBED_WHOLE_1MR2)
    # the fitted columns of x and q^T x (a view where they are the first ones)
    cols = fitted if 0 < fitted.size < k else slice(0, fitted.size)
    p_o = x_o - coords_o @ qx
    sums = ShapeSums(q, x, qx, zp, gram, xz, xx, other.chi2_now, coords_o, p_o, x_o, e_o)
    m = problem.current_columns().shape[1] + k
    nu, no = uscan.size, oscan.size

    def fit(scans: np.ndarray) -> tuple[np.ndarray, ShapeFit] | None:
        """The fit over ``scans`` and the scans it keeps (None: the explicit path)."""
        rm = np.searchsorted(uscan, np.flatnonzero(used & ~scans))
        ad = np.flatnonzero(scans[oscan])
        if 2 * (rm.size + ad.size) > ROW_UPDATE_MAX:
            return None
        f = rows_fit(sums, np.concatenate([rm, rm + nu]), np.concatenate([ad, ad + no]),
                     fitted)
        if f is None:
            return None
        # the standardized residuals of model + columns on the used scans' rows are
        # z_perp - x c - q d; |q_i d| <= max_i |q_i| |d| = bound, so only rows whose
        # |z_perp - x c| exceeds OUTLIER_Z - bound can exceed OUTLIER_Z (a margin of 1e-9
        # of both for rounding): those are computed exactly
        dv = f.shift - qx[:, cols] @ f.coef
        bound = other.rn_max * float(np.linalg.norm(dv)) * (1 + 1e-9) + 1e-9
        near, u_near = near_rows(x, cols, f.coef, zp, OUTLIER_Z - bound)
        out_u = near[np.abs(u_near - q[near] @ dv) > OUTLIER_Z]
        out_o = np.flatnonzero(~(np.abs(e_o - coords_o @ f.shift - p_o[:, cols] @ f.coef)
                                 <= OUTLIER_Z))
        keep = problem.valid.copy()
        keep[uscan[out_u % nu]] = False
        keep[oscan[out_o % no]] = False
        return keep, ShapeFit(scans, f.schur, f.rhs, f.chi2_now, f.full_sq, f.coef, f.cov, x,
                              qx, f.model_gram, f.on_model)

    # mask_fit's iterations: from every valid scan, twice
    scans = problem.valid
    for _ in range(2):
        out = fit(scans)
        if out is None:
            return None
        keep, res = out
        if keep.sum() < max(m, 3) or np.array_equal(keep, scans):
            return res
        # the model's own scans as one array, not a copy per result (most candidates keep
        # them: a mask of n bytes each, held by every result of the round)
        scans = used if np.array_equal(keep, used) else keep
    out = fit(scans)
    return None if out is None else out[1]

"""The fitter's linear algebra: least squares by QR with rank analysis, and least absolute
deviation (LAD) by linear programming (HiGHS).

Rank deficiency is reported, never papered over: a term whose design column is zero over the
used observations, or whose unit-scaled column lies within ``RANK_RTOL`` (the sine of the
angle) of the span of the columns of the terms listed before it, is *unconstrained*: it is
not fitted, its value is 0 and its sigma NaN (null in JSON), and a warning names it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg
from scipy.optimize import linprog

__all__ = ["RANK_RTOL", "LadBlock", "Rank", "Solution", "independent_columns", "lad_blocks",
           "least_squares", "matvec"]

#: A term is unconstrained when its unit-length design column is within this distance (the
#: sine of the angle) of the span of the columns before it, or is this small relative to the
#: largest column. Exact dependences (W6 with IA, HESA2 with HESACA, P2's zero column) sit at
#: the 1e-16 level in floating point; a term this close to degenerate would have a sigma ten
#: orders of magnitude above the best-determined one, which is no determination at all.
RANK_RTOL = 1e-10

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
#: the bands about a given centre (each twice the last, from _LAD_BAND_ROWS) tried before a
#: subsample's LAD takes over
_LAD_CENTRE_TRIES = 3


# ---------------------------------------------------------------------------------------------
# least squares
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Rank:
    """Which columns of a design the data determine, and why the others are not."""

    kept: tuple[int, ...]
    reasons: dict[int, str]


def _rank_analysis(r_unit: np.ndarray, col_norms: np.ndarray, names: Sequence[str]) -> Rank:
    """Decide, in model order, which columns are independent.

    ``r_unit`` is the R factor of the design with unit-length columns (so column j of R has
    the geometry of column j of the design); ``col_norms`` the columns' original lengths.
    A column is kept when its distance from the span of the kept columns before it exceeds
    ``RANK_RTOL``; terms listed first win: asked for IA then W6 (the same function), IA is
    fitted and W6 reported unconstrained.
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
    return Rank(tuple(kept), reasons)


@dataclass(frozen=True)
class Solution:
    coeffs: np.ndarray  # (M,), 0 for unconstrained
    cov_unscaled: np.ndarray  # (M, M) (A^T W A)^-1, NaN for unconstrained
    rank: Rank
    condition_number: float


# OpenBLAS multithreads level-2 BLAS calls above ~8000 matrix elements, and its worker threads
# then busy-wait; on the 2-core machine this doubled the wall time of a fit and made it erratic
# (0.6-1.9 s for the benchmark). The large-array products below therefore stay out of BLAS:
# QR in row blocks small enough to run single-threaded, matrix-vector products with einsum.
_QR_BLOCK_ELEMENTS = 6000


def matvec(a: np.ndarray, x: np.ndarray) -> np.ndarray:
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

    below = np.tri(k, k, -1, dtype=bool)

    def r_of(current: np.ndarray) -> np.ndarray:
        """The R factors of ``current``'s row blocks, stacked: each block's upper triangle
        written into one array and the rest zeroed there (np.triu and np.vstack's numbers,
        without a new array per block: ~800 blocks of a 400,000-row design)."""
        starts = range(0, max(current.shape[0], 1), block)  # no rows: geqrf's error
        heights = [min(current.shape[0] - i, block, k) for i in starts]
        out = np.empty((sum(heights), k), dtype=geqrf.dtype)
        at = 0
        for i, h in zip(starts, heights, strict=True):
            qr, _tau, _work, info = geqrf(current[i:i + block])
            if info != 0:
                raise ArithmeticError(f"LAPACK geqrf failed (info = {info})")
            piece = out[at:at + h]
            piece[...] = qr[:h]
            piece[below[:h]] = 0.0
            at += h
        return out

    current = a
    while current.shape[0] > block:
        current = r_of(current)
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


def least_squares(a: np.ndarray, y: np.ndarray, names: Sequence[str]) -> Solution:
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
    return Solution(coeffs, cov, rank, cond)


def independent_columns(a: np.ndarray, names: Sequence[str]) -> Rank:
    unit, norms = _unit_columns(a)
    return _rank_analysis(_r_factor(unit), norms, names)


# ---------------------------------------------------------------------------------------------
# least absolute deviation
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


def _lad_dense(a: np.ndarray, y: np.ndarray, rng: np.random.Generator,
               centre: np.ndarray | None = None, band_rows: int | None = None) -> np.ndarray:
    """Exact LAD coefficients for a full-column-rank ``a`` (rows x p). ``centre``: an
    estimate of them (the LAD of a related problem: diagnose's fit variants centre a day or
    night window's on the fit of every scan), tried first as the band's centre in place of a
    subsample's LAD; where it proves too far off (:data:`_LAD_CENTRE_TRIES` bands), the
    subsample's as without it. ``band_rows``: the first band's rows about the centre
    (default :data:`_LAD_BAND_ROWS`); given, a problem of more than twice as many rows
    starts from the centre too, however small (the plan's growing designs: each LAD centred
    on the one of the design a night shorter). Either way the exact optimum, the rows kept in
    the last LP (and so the rounding of the result: ~1e-13 relative) depending on the
    centre."""
    n, p = a.shape
    direct = n <= max(2 * _LAD_DIRECT_ROWS, 40 * p)
    band = int(max(_LAD_BAND_ROWS if band_rows is None else band_rows, 40 * p))
    if direct and (centre is None or band_rows is None or n <= 2 * band):
        return _lad_full(a, y)
    if centre is not None:
        try:
            chol = scipy.linalg.cholesky(np.einsum("ij,ik->jk", a, a), lower=False)
        except np.linalg.LinAlgError:
            chol = None
        found = None if chol is None else _lad_band(
            a, y, centre, chol, band, min(n // 2, band << _LAD_CENTRE_TRIES))
        if found is not None:
            return found
    if direct:  # a small problem whose centre was too far off
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
    band = int(max(_LAD_BAND_ROWS, 40 * p, 4 * math.sqrt(p / m) * n))
    found = _lad_band(a, y, coeffs, chol, band, n // 2)
    return _lad_full(a, y) if found is None else found


def _lad_band(a: np.ndarray, y: np.ndarray, coeffs: np.ndarray, chol: np.ndarray, band: int,
              limit: int) -> np.ndarray | None:
    """The exact LAD optimum from an LP of the ``band`` rows nearest the fit ``coeffs`` (in
    residual over prediction scale, ``chol`` the Cholesky factor of a Gram matrix of ``a``'s
    rows), the others' signs fixed and confirmed; the band widened while its rows number
    fewer than ``limit``, else None."""
    n, p = a.shape
    leverage = np.linalg.norm(matvec(a, scipy.linalg.solve_triangular(chol, np.eye(p))), axis=1)
    resid = y - matvec(a, coeffs)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(leverage > 0, np.abs(resid) / leverage, np.inf)
    tol = 1e-9 * max(1.0, float(np.abs(y).max()))
    forced = np.zeros(n, dtype=bool)
    # The band stays centred on the estimate: a failed reduced solution can be far off (its
    # globs were wrong), so it is never used to re-centre.
    for _ in range(30):
        if band + forced.sum() >= limit:
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
        trial_resid = y - matvec(a, trial)
        wrong = (above & (trial_resid < -tol)) | (below & (trial_resid > tol))
        if not wrong.any() and bool(np.all(d[k:] >= 1 - 1e-9)):
            return trial  # every fixed sign confirmed: the exact optimum of the full problem
        if 0 < wrong.sum() <= 0.1 * band:
            forced |= wrong
        else:
            band *= 2
    return None


@dataclass(frozen=True)
class LadBlock:
    """One separable block of an exact LAD fit (:func:`lad_blocks`): its rows and columns of
    the design, its data, the centre given, the subsampling generator's state before and
    after its solve, and its coefficients."""

    rows: np.ndarray
    cols: np.ndarray
    y: np.ndarray
    centre: np.ndarray | None
    state_in: dict
    state_out: dict
    coeffs: np.ndarray

    def solves(self, rows: np.ndarray, cols: np.ndarray, y: np.ndarray,
               centre: np.ndarray | None, state_in: dict) -> bool:
        """Whether this block's solve is that of these inputs (the same bytes)."""
        return (self.state_in == state_in and np.array_equal(self.cols, cols)
                and np.array_equal(self.rows, rows) and np.array_equal(self.y, y)
                and ((self.centre is None and centre is None) or (
                    self.centre is not None and centre is not None
                    and np.array_equal(self.centre, centre))))


def _lad(a: np.ndarray, y: np.ndarray, n_xel: int | None = None) -> np.ndarray:
    """Exact LAD fit of ``y ~ a @ c`` (:func:`lad_blocks`)."""
    return lad_blocks(a, y, n_xel)[0]


def lad_blocks(a: np.ndarray, y: np.ndarray, n_xel: int | None = None,
                prior: Sequence[LadBlock | None] | None = None,
                centre: np.ndarray | None = None, band_rows: int | None = None
                ) -> tuple[np.ndarray, list[LadBlock | None]]:
    """Exact LAD fit of ``y ~ a @ c``, and its blocks.

    When the first ``n_xel`` rows (cross-elevation) and the rest (elevation) involve disjoint
    sets of columns, the problem separates and each half is solved alone: Ghigo's ten terms
    split into five azimuth and five elevation terms. Rows whose design is zero add a
    constant and are dropped. ``prior``: the blocks of a fit of the same design ``a`` to
    other data (diagnose's fit variants before and after removing a finding's signal): a
    block whose rows, columns, data and generator state are that fit's is its solution, the
    generator left where its solve left it (the same bytes as solving it again).
    ``centre``, ``band_rows``: an estimate of the coefficients and the band about it
    (:func:`_lad_dense`).
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
    solved: list[LadBlock | None] = []
    for i, cols in enumerate(blocks):
        if cols.size == 0:
            solved.append(None)
            continue
        rows = (a[:, cols] != 0).any(axis=1) & nonzero_rows
        y_block = np.ascontiguousarray(y[rows])
        state_in = rng.bit_generator.state
        block_centre = None if centre is None else centre[cols]
        old = prior[i] if prior is not None and i < len(prior) else None
        if old is None or not old.solves(rows, cols, y_block, block_centre, state_in):
            block_coeffs = _lad_dense(np.ascontiguousarray(a[np.ix_(rows, cols)]), y_block, rng,
                                      block_centre, band_rows)
            old = LadBlock(rows, cols, y_block, block_centre, state_in,
                            rng.bit_generator.state, block_coeffs)
        rng.bit_generator.state = old.state_out
        coeffs[cols] = old.coeffs
        solved.append(old)
    return coeffs, solved

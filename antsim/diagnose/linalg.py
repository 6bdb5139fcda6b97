"""Linear-algebra kernels of diagnosis: least squares, QR, held-out residuals in closed
form, and blocked products over tall matrices.

Nothing here knows about pointing: every function takes arrays and returns arrays. The
statistics (:mod:`.problem`, :mod:`.select`, :mod:`.crossval`, the candidates) call them;
the tall-matrix paths (normal equations where well conditioned, blocked products,
Fortran-ordered gathers) are there for diagnose's designs of 2 n_used rows by a few
columns, and give the numbers of the plain formulas to rounding
(tests/antsim/diagnose/test_diagnose.py compares them).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

__all__ = ["FORTRAN_BLOCK", "FORTRAN_BLOCK_ELEMENTS", "GRAM_MIN_RATIO", "HELDOUT_MIN_EIG",
           "QT_BLOCK", "added_basis", "economic_qr", "gram_inverse", "gram_solve",
           "heldout_lstsq", "lstsq", "near_rows", "qt_dot", "rows_fortran", "shape_products",
           "take_rows_fortran"]


#: the least ratio of the smallest to the largest eigenvalue of a^T a (1 / cond(a)^2) at
#: which :func:`lstsq` solves from the normal equations: their rounding grows as
#: cond(a)^2 eps, here at most 100 x 2.2e-16 (relative), and every singular value is then
#: 1e9 times above the pseudo-inverse's cut, so the rank is the SVD's
GRAM_MIN_RATIO = 1e-2


def lstsq(a: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Least squares with a pseudo-inverse covariance (rank-deficient columns get 0).

    The SVD of ``a`` defines it (singular values below 1e-10 of the largest are dropped).
    A tall ``a`` (diagnose's are 2 n_used rows by a few columns) is not decomposed whole:
    well conditioned (:data:`GRAM_MIN_RATIO`), from its Gram matrix a^T a = V S^2 V^T
    (one pass over ``a``); else from a Householder QR without Q (LAPACK geqrf and ormqr
    applying it to ``z``) and the SVD of the small R, whose singular values and
    pseudo-inverse solution are ``a``'s, to rounding."""
    m, k = a.shape
    if k == 0:
        return np.zeros(0), np.zeros((0, 0))
    if m >= 4 * k:
        g = a.T @ a
        az = a.T @ z
        if np.isfinite(g).all() and np.isfinite(az).all() and np.isfinite(z).all():
            cov = gram_inverse(g)
            if cov is not None:
                return cov @ az, cov
        # a non-finite ``a`` or ``z`` raises here, as the SVD did
        # factored in a Fortran-ordered copy of our own, overwritten (qr_multiply without
        # overwrite_a makes two copies of ``a``); the same LAPACK calls on the same numbers
        qz, r = scipy.linalg.qr_multiply(take_rows_fortran(a), z.T, mode="right",
                                         overwrite_a=True)
        return _svd_lstsq(r, qz.T)
    return _svd_lstsq(a, z)


def _svd_lstsq(a: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`lstsq` by the SVD of ``a`` itself."""
    u, s, vt = scipy.linalg.svd(a, full_matrices=False, lapack_driver="gesdd")
    keep = s > 1e-10 * s[0] if s.size and s[0] > 0 else np.zeros_like(s, dtype=bool)
    inv = np.where(keep, 1.0 / np.where(keep, s, 1.0), 0.0)
    uz = u.T @ z
    coef = vt.T @ ((inv[:, None] if uz.ndim == 2 else inv) * uz)
    cov = (vt.T * inv**2) @ vt
    return coef, cov


def gram_solve(gram: np.ndarray, rhs: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Least-squares coefficients and covariance from the columns' Gram matrix and their
    inner products with the data (the normal equations); None where the columns'
    correlation matrix has an eigenvalue below :data:`GRAM_MIN_RATIO` of its largest (the
    normal equations' rounding grows as its inverse: :func:`lstsq`'s QR then serves)."""
    if not rhs.size:
        return np.zeros(0), np.zeros((0, 0))
    d = np.diag(gram)
    if not (d > 0).all():
        return None
    s = 1.0 / np.sqrt(d)
    inv = gram_inverse(gram * np.outer(s, s))
    if inv is None:
        return None
    cov = inv * np.outer(s, s)
    return cov @ rhs, cov


def gram_inverse(g: np.ndarray) -> np.ndarray | None:
    """The inverse of a Gram matrix ``g`` from its eigendecomposition, or None where its
    smallest eigenvalue is below :data:`GRAM_MIN_RATIO` of its largest (the normal
    equations' rounding grows as the ratio's inverse)."""
    w, v = np.linalg.eigh(g)
    if not w[0] > GRAM_MIN_RATIO * w[-1] > 0.0:
        return None
    return (v / w) @ v.T


def economic_qr(x: np.ndarray, overwrite: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Economic QR (LAPACK through scipy: on a tall matrix several times faster than
    numpy's ``linalg.qr``); ``overwrite``: ``x`` is not needed after (a Fortran-ordered
    ``x`` is then factored in place, not copied)."""
    return scipy.linalg.qr(x, mode="economic", check_finite=False, overwrite_a=overwrite)


def added_basis(q0: np.ndarray, x: np.ndarray
                ) -> tuple[tuple[np.ndarray, np.ndarray], np.ndarray]:
    """An orthonormal basis of [span(q0), x] as its two blocks (q0, q1), not stacked (a copy
    of q0 per call), and the diagonal magnitudes of q1's R (those of a QR of the whole, to
    rounding): ``x`` projected off ``q0`` twice (classical Gram-Schmidt loses orthogonality
    once, not twice) and factored alone."""
    rest = x - q0 @ (q0.T @ x)
    rest -= q0 @ (q0.T @ rest)
    q1, r1 = economic_qr(rest)
    return (q0, q1), np.abs(np.diag(r1))


#: a held-out group whose leverage leaves less than this of some direction of the model to
#: the other groups (an eigenvalue of I - Q_S^T Q_S) is refitted without it instead
HELDOUT_MIN_EIG = 1e-8


def heldout_lstsq(x: np.ndarray | None, z: np.ndarray, labels: np.ndarray,
                  basis: tuple[np.ndarray | tuple[np.ndarray, ...], np.ndarray] | None = None,
                  overwrite: bool = False) -> np.ndarray | None:
    """Residuals (rows as ``z``) of each group of rows (same ``labels``) predicted by a
    least-squares fit of ``z`` on ``x`` to the other groups, from one QR of ``x``: with Q its
    orthonormal basis, e the full fit's residual and S a group's rows, the held-out residual
    is (I - Q_S Q_S^T)^-1 e_S = e_S + Q_S (I - Q_S^T Q_S)^-1 Q_S^T e_S (Woodbury; the
    textbook leave-group-out identity), exactly what refitting without S gives, at a cost in
    the group's rows rather than a factorization of the others per group. ``basis``: Q (or
    its column blocks, stacked a group's rows at a time) and |diag R| when the caller has
    them (:func:`added_basis`). None when ``x`` has dependent
    columns or a group alone determines a direction of the model (the caller then refits
    per group, whose pseudo-inverse handles that). ``overwrite``: ``x`` may be factored in
    place (:func:`economic_qr`)."""
    if basis is None:
        q, r = economic_qr(x, overwrite)
        d = np.abs(np.diag(r))
    else:
        q, d = basis
    if not d.size or d.min() <= 1e-10 * max(float(d.max()), 1e-300):
        return None
    blocks = q if isinstance(q, tuple) else (q,)
    e = z
    for b in blocks:
        e = e - b @ (b.T @ z)
    out = np.empty_like(e)
    # the same order either way; small labels (nights, folds) sort by radix, in one pass
    small = labels.size and labels.min() >= 0 and labels.max() < 2**15
    order = np.argsort(labels.astype(np.int16) if small else labels, kind="stable")
    bounds = np.flatnonzero(np.diff(labels[order])) + 1
    eye = np.eye(sum(b.shape[1] for b in blocks))
    for rows in np.split(order, bounds):
        qs = blocks[0][rows] if len(blocks) == 1 else np.hstack([b[rows] for b in blocks])
        m = eye - qs.T @ qs
        w, v = np.linalg.eigh(m)
        if w.min() < HELDOUT_MIN_EIG:
            return None
        out[rows] = e[rows] + qs @ (v @ ((v.T @ (qs.T @ e[rows])) / w))
    return out


#: rows gathered or copied into Fortran order at a time (:func:`take_rows_fortran`): a
#: block of a few columns stays in cache while it is transposed. Narrow arrays (a shape
#: test's 1-4 columns, :func:`shape_products`' blocks of QT_BLOCK rows) take
#: FORTRAN_BLOCK_ELEMENTS at a time: one ``take`` per block, not eight
FORTRAN_BLOCK = 1024
FORTRAN_BLOCK_ELEMENTS = 16384


def take_rows_fortran(x: np.ndarray, idx: np.ndarray | None = None,
                      scale: np.ndarray | None = None, out: np.ndarray | None = None
                      ) -> np.ndarray:
    """``x[idx]`` (idx row indices; None: every row) in Fortran order, each row times
    ``scale`` when given: what LAPACK factors in place (:func:`economic_qr` with ``overwrite``).
    Gathered a block of rows at a time (the same numbers as gathering, transposing and
    scaling the whole: a copy and one product per element; the whole's transposition
    strides through memory, 2-4 times slower at 400,000 rows). ``out``: written there (a
    Fortran-ordered array of that shape, e.g. some columns of a larger one)."""
    n = x.shape[0] if idx is None else idx.size
    if out is None:
        out = np.empty((n, x.shape[1]), order="F")
    # ``take`` copies a strided ``x`` (a view of the stacked model) whole on every call:
    # indexing reads its rows in place
    contiguous = x.flags.c_contiguous
    block = max(FORTRAN_BLOCK, FORTRAN_BLOCK_ELEMENTS // max(x.shape[1], 1))
    for a in range(0, n, block):
        b = min(a + block, n)
        part = x[a:b] if idx is None else (x.take(idx[a:b], axis=0) if contiguous
                                            else x[idx[a:b]])
        if scale is None:
            out[a:b] = part
        else:
            np.multiply(part, scale[a:b, None], out=out[a:b])
    return out


def rows_fortran(x: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """``x[rows]`` (rows a boolean mask of x's rows) in Fortran order
    (:func:`take_rows_fortran`)."""
    return take_rows_fortran(x, np.flatnonzero(rows))


#: rows of the model's basis read per product in :func:`qt_dot`: the block of q and x
#: (8192 rows of 12 + 4 columns: 1 MiB) stays in cache while BLAS packs and multiplies it
QT_BLOCK = 8192


def qt_dot(q: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``q.T @ x`` for tall ``q`` (N, m) and ``x`` (N, k), summed over blocks of
    :data:`QT_BLOCK` rows: OpenBLAS's one product over 400,000 rows of a thin pair reads
    memory about twice over (2.4-3.0 ms against 1.5-1.8 ms blocked, one thread, m = 12,
    k = 2-4). The same sums in another order: equal to rounding (each entry within
    ~N eps |q_j| |x_l|; tests/antsim/diagnose/test_diagnose.py compares the two)."""
    n = q.shape[0]
    if n <= 2 * QT_BLOCK:
        return q.T @ x
    out = q[:QT_BLOCK].T @ x[:QT_BLOCK]
    for a in range(QT_BLOCK, n, QT_BLOCK):
        out += q[a:a + QT_BLOCK].T @ x[a:a + QT_BLOCK]
    return out


def shape_products(raw: np.ndarray, idx: np.ndarray, wu: np.ndarray, f2u: np.ndarray | None,
                   q: np.ndarray, zp: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`.shapefit.shape_fit`'s whitened columns x over the rows ``idx`` (Fortran order:
    ``raw``'s rows times the offset scale ``f2u`` then times ``wu``, and the same rows times
    ``wu``; without ``f2u`` the latter alone) with q^T x, x^T x and x^T zp, made
    :data:`QT_BLOCK` rows at a time: each block's products while it is in cache (x read
    once, not thrice). x is the whole array's numbers bit for bit (the same products per
    element); the sums are in blocks (:func:`qt_dot`)."""
    k = raw.shape[1]
    kk = k if f2u is None else 2 * k
    n = idx.size
    x = np.empty((n, kk), order="F")
    qx, xx, xz = np.zeros((q.shape[1], kk)), np.zeros((kk, kk)), np.zeros(kk)
    for a in range(0, n, QT_BLOCK):
        b = min(a + QT_BLOCK, n)
        xb = x[a:b]
        take_rows_fortran(raw, idx[a:b], out=xb[:, kk - k:])
        if f2u is not None:
            np.multiply(xb[:, k:], f2u[a:b, None], out=xb[:, :k])
        xb *= wu[a:b, None]
        if a == 0:
            qx, xx, xz = q[:b].T @ xb, xb.T @ xb, xb.T @ zp[:b]
        else:
            qx += q[a:b].T @ xb
            xx += xb.T @ xb
            xz += xb.T @ zp[a:b]
    return x, qx, xx, xz


def near_rows(x: np.ndarray, cols, coef: np.ndarray, zp: np.ndarray, limit: float
              ) -> tuple[np.ndarray, np.ndarray]:
    """The rows i where |u_i| > ``limit``, u = zp - x[:, cols] @ coef, and u there
    (:func:`.shapefit.shape_fit`'s rows near the outlier threshold), made :data:`QT_BLOCK`
    rows at a time: u's block in cache while it is compared (one pass over x and zp, not
    four over u). The same numbers as the whole expression (a row's product does not
    depend on the rows beside it with one BLAS thread, as diagnose runs)."""
    near, u_near = [np.arange(0)], [np.zeros(0)]
    for a in range(0, zp.size, QT_BLOCK):
        u = x[a:a + QT_BLOCK, cols] @ coef
        np.subtract(zp[a:a + QT_BLOCK], u, out=u)
        i = np.flatnonzero(np.abs(u) > limit)
        near.append(i + a)
        u_near.append(u[i])
    return np.concatenate(near), np.concatenate(u_near)

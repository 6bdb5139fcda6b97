"""The shape test's row update (antsim.diagnose.shapefit.rows_fit) against the fit it
replaces, made explicitly on the remaining rows."""

from __future__ import annotations

import numpy as np

from antsim.diagnose.shapefit import ShapeSums, rows_fit


def test_removing_rows_gives_the_fit_over_the_rest():
    """With rows removed from the used ones (none added), the row update's Gram of the
    columns off the model, its right-hand side, the model's chi^2 and the columns'
    coefficients are those of projecting the model out over the remaining rows (1e-9
    relative: the design is well conditioned, rounding is ~1e-14)."""
    rng = np.random.default_rng(8)
    n, m, k = 200, 4, 2
    a = rng.standard_normal((n, m))
    x = rng.standard_normal((n, k)) + 0.3 * a[:, :k]
    z = a @ rng.standard_normal(m) + x @ np.array([0.5, -0.2]) + rng.standard_normal(n)
    q, _ = np.linalg.qr(a)
    qx, qz = q.T @ x, q.T @ z
    zp = z - q @ qz
    none = np.zeros((0, m))
    sums = ShapeSums(q, x, qx, zp, x.T @ x - qx.T @ qx, x.T @ zp, x.T @ x, float(zp @ zp),
                     none, np.zeros((0, k)), np.zeros((0, k)), np.zeros(0))
    rm = np.array([3, 17, 60, 61, 150])
    got = rows_fit(sums, rm, np.arange(0), np.arange(k))
    keep = np.setdiff1d(np.arange(n), rm)
    qs, _ = np.linalg.qr(a[keep])
    xp = x[keep] - qs @ (qs.T @ x[keep])
    zs = z[keep] - qs @ (qs.T @ z[keep])
    np.testing.assert_allclose(got.schur, xp.T @ xp, rtol=1e-9)
    np.testing.assert_allclose(got.rhs, xp.T @ zs, rtol=1e-9)
    assert np.isclose(got.chi2_now, float(zs @ zs), rtol=1e-9)
    np.testing.assert_allclose(got.coef, np.linalg.lstsq(xp, zs, rcond=None)[0], rtol=1e-9)
    same = rows_fit(sums, np.arange(0), np.arange(0), np.arange(k))
    np.testing.assert_allclose(same.schur, sums.gram)  # no rows changed: the sums over U

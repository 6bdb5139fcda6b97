"""controller/pointing/solvers.py: a LAD centred on an estimate, with a small band about it."""

from __future__ import annotations

import numpy as np
import pytest

from controller.pointing import solvers
from controller.pointing.model import PointingModel
from controller.pointing.robust import Equations, lad_fit


def _problem(n: int, seed: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """One axis of a ghigo10 fit (its five cross-elevation terms) to n observations with
    Gaussian noise of 20" and 2% of them 500" off: a LAD whose optimum differs from least
    squares'."""
    rng = np.random.default_rng(seed)
    az = rng.uniform(0.0, 2 * np.pi, n)
    el = np.radians(rng.uniform(10.0, 85.0, n))
    b_az, _ = PointingModel("ghigo10").design_matrix(az, el)
    a = b_az * np.cos(el)[:, None]
    a = a[:, (a != 0).any(axis=0)]
    y = a @ rng.normal(0.0, 100.0, a.shape[1]) + rng.normal(0.0, 20.0, n)
    y[rng.choice(n, n // 50, replace=False)] += 500.0
    return np.ascontiguousarray(a), y


def _lp_rows(monkeypatch) -> list[int]:
    rows: list[int] = []
    real = solvers._lad_lp
    monkeypatch.setattr(solvers, "_lad_lp", lambda *args: rows.append(args[0].shape[0])
                        or real(*args))
    return rows


@pytest.mark.parametrize("offset", [0.0, 0.5])
def test_a_small_band_about_a_close_centre_is_the_exact_optimum_from_smaller_lps(
        monkeypatch, offset):
    """2000 rows, centred on the optimum (or 0.5" off it) with a band of 100 rows: LPs of a
    few hundred rows, never the full 2000, and the optimum of the full LP (its objective to
    1e-9; the coefficients to the LPs' rounding, 1e-6", as diagnose's centred windows)."""
    a, y = _problem(2000)
    full = solvers._lad_full(a, y)
    rows = _lp_rows(monkeypatch)
    warm = solvers._lad_dense(a, y, np.random.default_rng(1), full + offset, band_rows=100)
    assert rows and max(rows) < 1000, rows
    assert np.abs(y - a @ warm).sum() == pytest.approx(np.abs(y - a @ full).sum(), rel=1e-9)
    np.testing.assert_allclose(warm, full, rtol=0, atol=1e-6)


def test_a_far_centre_falls_back_to_the_full_lp(monkeypatch):
    """A centre 1e4" off: the bands about it fail their check and the full LP answers."""
    a, y = _problem(2000)
    full = solvers._lad_full(a, y)
    rows = _lp_rows(monkeypatch)
    far = solvers._lad_dense(a, y, np.random.default_rng(1), full + 1e4, band_rows=100)
    assert rows[-1] == 2000
    np.testing.assert_allclose(far, full, rtol=0, atol=1e-6)


def test_without_band_rows_a_centre_leaves_a_small_problem_to_the_full_lp(monkeypatch):
    """Diagnose's centred windows of a few thousand rows are solved as before: one LP of
    every row (the band about a centre starts at _LAD_BAND_ROWS without ``band_rows``)."""
    a, y = _problem(2000)
    rows = _lp_rows(monkeypatch)
    solvers._lad_dense(a, y, np.random.default_rng(1), np.zeros(a.shape[1]))
    assert rows == [2000]


def test_lad_fit_passes_the_centre_and_band_to_both_axes(monkeypatch):
    """The robust fit's first stage with a centre: each axis' block from small LPs."""
    a_x, y_x = _problem(1500, seed=4)
    a_e, y_e = _problem(1500, seed=5)
    m = a_x.shape[1]
    a = np.zeros((3000, 2 * m))
    a[:1500, :m], a[1500:, m:] = a_x, a_e
    y = np.concatenate([y_x, y_e])
    names = tuple(f"T{i}" for i in range(2 * m))
    eq = Equations(names, 1500, np.asfortranarray(a), y, np.asfortranarray(a), y, 1e-9)
    cold = lad_fit(eq)
    rows = _lp_rows(monkeypatch)
    warm = lad_fit(eq, centre=cold, band_rows=100)
    assert len(rows) >= 2 and max(rows) < 1000, rows
    np.testing.assert_allclose(warm, cold, rtol=0, atol=1e-6)

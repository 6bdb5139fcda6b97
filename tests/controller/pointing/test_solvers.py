"""The solvers (controller.pointing.solvers): the LAD as the exact optimum, blocks of unchanged
data taken from the fit before, a LAD centred on an estimate with a small band about it, and
the blocked QR against LAPACK."""

from __future__ import annotations

import numpy as np
import pytest

from controller.pointing import solvers
from controller.pointing.model import PointingModel
from controller.pointing.robust import Equations, lad_fit
from tests.controller.pointing.test_fitting import ghigo_truth, synthetic


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


@pytest.mark.parametrize("model_name", ["ghigo10", "tpoint8"])
def test_lad_is_the_exact_optimum(model_name):
    """The reduced LP (rows of certain sign fixed at their bound) gives the optimum of the
    full LP: 8000 observations take the reduction path (more than 6000 rows)."""
    rng = np.random.default_rng(12)
    data = synthetic(ghigo_truth(), rng, 8000, 20.0, 30.0)  # tpoint8 misfits Ghigo's errors
    model = PointingModel(model_name)
    b_az, b_el = model.design_matrix(data.az_rad, data.el_rad)
    a = np.vstack([b_az * np.cos(data.el_rad)[:, None], b_el])
    y = -np.concatenate([data.xel_arcsec, data.el_arcsec])
    y[rng.choice(y.size, 300, replace=False)] += rng.normal(0.0, 500.0, 300)
    fast = solvers._lad(a, y, n_xel=8000)  # ghigo10 separates into two halves
    full = solvers._lad_full(a, y)
    objective_fast = np.abs(y - a @ fast).sum()
    objective_full = np.abs(y - a @ full).sum()
    # the optimum is unique for continuous data; 1e-9 relative is LP solver tolerance
    assert objective_fast == pytest.approx(objective_full, rel=1e-9)
    np.testing.assert_allclose(fast, full, rtol=0, atol=1e-4)


def test_a_lad_block_of_unchanged_data_is_taken_from_the_fit_before(monkeypatch):
    """Diagnose's fit variants fit one design before and after removing a finding's signal:
    given the LAD before (``prior``), a block whose data the signal leaves unchanged (the
    cross-elevation one for an elevation-only signal) is that fit's solution, not solved
    again, and the generator is left where its solve left it, so that the next block draws
    the same subsample: the same bytes as solving both; a block of other data is solved."""
    rng = np.random.default_rng(5)
    data = synthetic(ghigo_truth(), rng, 8000, 20.0, 30.0)  # 8000 rows: the subsampled path
    model = PointingModel("ghigo10")
    b_az, b_el = model.design_matrix(data.az_rad, data.el_rad)
    a = np.vstack([b_az * np.cos(data.el_rad)[:, None], b_el])
    y = -np.concatenate([data.xel_arcsec, data.el_arcsec])
    y_el = y.copy()
    y_el[8000:] += 30.0 * np.sin(2 * data.az_rad)  # an elevation-only signal removed
    reference = solvers._lad(a, y_el, n_xel=8000)  # solved alone
    _, blocks = solvers.lad_blocks(a, y, n_xel=8000)
    solved = []
    real = solvers._lad_dense
    monkeypatch.setattr(solvers, "_lad_dense", lambda *args: solved.append(args[1]) or real(*args))
    again, _ = solvers.lad_blocks(a, y_el, n_xel=8000, prior=blocks)
    assert again.tobytes() == reference.tobytes()
    top = [y_block for y_block in solved if y_block.size == 8000]  # not its subsamples
    assert len(top) == 1 and np.array_equal(top[0], y_el[8000:])  # the elevation block
    solved.clear()
    y_both = y_el.copy()
    y_both[:8000] += 1.0  # both blocks' data changed: both solved
    solvers.lad_blocks(a, y_both, n_xel=8000, prior=blocks)
    assert len([y_block for y_block in solved if y_block.size == 8000]) == 2


@pytest.mark.parametrize("offset", [0.3, 1e4])
def test_a_lad_started_from_a_given_centre_is_the_exact_optimum(offset):
    """A centre (diagnose's day and night windows start from the LAD of every scan) gives the
    optimum of the full LP, as the subsample's start does: near it (0.3" off) in one band;
    far off (1e4"), after _LAD_CENTRE_TRIES bands, through the subsample. The rows of the
    last LP differ, so the coefficients only to its rounding (1e-6", far below the 1e-4"
    that the exact-optimum test allows the two solvers)."""
    rng = np.random.default_rng(21)
    data = synthetic(ghigo_truth(), rng, 20000, 20.0, 30.0)
    model = PointingModel("tpoint8")  # misfits Ghigo's errors: a non-trivial LAD
    b_az, b_el = model.design_matrix(data.az_rad, data.el_rad)
    a = np.vstack([b_az * np.cos(data.el_rad)[:, None], b_el])
    y = -np.concatenate([data.xel_arcsec, data.el_arcsec])
    y[rng.choice(y.size, 600, replace=False)] += rng.normal(0.0, 500.0, 600)
    cold = solvers._lad_dense(a, y, np.random.default_rng(1))
    lps = []
    real = solvers._lad_lp
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(solvers, "_lad_lp", lambda *args: lps.append(args[0].shape[0]) or real(*args))
        warm = solvers._lad_dense(a, y, np.random.default_rng(1), cold + offset)
    full = solvers._lad_full(a, y)
    objective = np.abs(y - a @ full).sum()
    assert np.abs(y - a @ warm).sum() == pytest.approx(objective, rel=1e-9)
    np.testing.assert_allclose(warm, cold, rtol=0, atol=1e-6)
    if offset < 1:
        assert len(lps) == 1 and lps[0] < 4000  # one band of ~3000 rows and the globs
    else:
        assert len(lps) > solvers._LAD_CENTRE_TRIES  # the centre's bands, then the subsample's


@pytest.mark.parametrize(("rows", "cols", "rank"), [(20000, 11, 11), (7, 3, 3), (5000, 6, 4)])
def test_blocked_qr_matches_lapack(rows, cols, rank):
    """The tall-skinny QR gives the R of one Householder QR (up to row signs)."""
    rng = np.random.default_rng(rows)
    a = rng.normal(size=(rows, rank)) @ rng.normal(size=(rank, cols))  # rank-deficient if < cols
    r = solvers._r_factor(a)
    reference = np.linalg.qr(a, mode="r")
    np.testing.assert_allclose(np.abs(np.diag(r)), np.abs(np.diag(reference)),
                               rtol=1e-9, atol=1e-9 * np.abs(reference).max())
    np.testing.assert_allclose(r.T @ r, a.T @ a, rtol=1e-10, atol=1e-9 * np.abs(a.T @ a).max())


def _r_factor_reference(a: np.ndarray) -> np.ndarray:
    """solvers._r_factor as first written: np.triu of each block's geqrf, np.vstack."""
    import scipy.linalg

    from controller.pointing.solvers import _QR_BLOCK_ELEMENTS

    k = a.shape[1]
    (geqrf,) = scipy.linalg.get_lapack_funcs(("geqrf",), (a,))
    block = max(2 * k, _QR_BLOCK_ELEMENTS // max(k, 1))

    def r_of(part):
        qr, _tau, _work, info = geqrf(part)
        assert info == 0
        return np.triu(qr[: min(part.shape), :])

    current = a
    while current.shape[0] > block:
        current = np.vstack([r_of(current[i:i + block]) for i in range(0, current.shape[0], block)])
    r = r_of(current)
    if r.shape[0] < k:
        r = np.vstack([r, np.zeros((k - r.shape[0], k))])
    return r


@pytest.mark.parametrize(("rows", "cols"), [(60_001, 13), (20_000, 6), (923, 13), (7, 3),
                                            (30, 40), (1_000, 1)])
def test_blocked_qr_written_in_place_is_the_stacked_triangles(rows, cols):
    """_r_factor's blocks written into one array are the same LAPACK calls on the same
    numbers as np.triu and np.vstack of each: the same bytes (a last block shorter than the
    columns, a wide matrix, one column)."""
    a = np.asfortranarray(np.random.default_rng(rows).normal(size=(rows, cols)))
    assert solvers._r_factor(a).tobytes() == _r_factor_reference(a).tobytes()


def test_lad_coefficients_are_minus_the_marginals():
    """A tiny LAD problem with a known answer: the median. y = c (one column of ones)."""
    y = np.array([1.0, 2.0, 7.0, 100.0, -3.0])
    c = solvers._lad_full(np.ones((5, 1)), y)
    assert c[0] == pytest.approx(2.0, abs=1e-9)

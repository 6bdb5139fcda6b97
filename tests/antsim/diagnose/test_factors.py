"""The model's factorizations kept (antsim.diagnose.factors): the cache's bound and order, the
factors' numbers, and when they are dropped."""

from __future__ import annotations

import numpy as np
import scipy.linalg

from antsim.diagnose.data import Observations
from antsim.diagnose.factors import BoundedCache, kept_sun_grid
from antsim.diagnose.problem import Prediction, Problem


def _problem(n: int = 120) -> Problem:
    """White noise of 5" on both axes, a 20" sin 2A elevation error, the basic terms."""
    rng = np.random.default_rng(3)
    az = rng.uniform(0.0, 2 * np.pi, n)
    obs = Observations(t_s=np.arange(n) * 600.0, az_rad=az,
                       el_rad=np.radians(rng.uniform(15.0, 85.0, n)),
                       xel_arcsec=rng.normal(0.0, 5.0, n),
                       el_arcsec=rng.normal(0.0, 5.0, n) + 20.0 * np.sin(2 * az),
                       good=np.ones(n, dtype=bool))
    pred = Prediction("white", np.zeros(n), np.zeros(n), np.full(n, 5.0), np.full(n, 5.0))
    return Problem(obs, pred, ["IA", "IE", "NPAE", "CA", "AN", "AW", "TF"])


def test_the_cache_lets_the_least_recently_used_go_first_within_its_bound():
    """Entries beyond the byte bound go oldest first (a read makes an entry the newest);
    pinned ones stay whatever their age; an entry's companions go with it."""
    cache = BoundedCache(max_bytes=30, max_entries=10, pinned=lambda key: key == "pin")
    cache.put("pin", 0, 10)
    cache.put("a", 1, 10)
    cache.put("b", 2, 10)
    assert cache.get("a") == 1  # now newer than b
    cache.put("c", 3, 10)  # no room: b (the oldest not pinned) goes
    assert cache.keys() == ["pin", "a", "c"] and cache.nbytes == 30
    cache.put("d", 4, 10, goes_with=lambda key: ["c"] if key == "a" else [])
    assert cache.keys() == ["pin", "d"] and "a" not in cache and cache.get("c") is None


def test_the_kept_factor_is_the_whitened_models_qr_and_goes_when_the_model_changes():
    """The QR kept over the used scans is that of the whitened model's columns (R up to
    the signs of its rows), kept while the model stays; adding a finding drops every factor
    (they were the model's without it) and the next one includes the finding's columns."""
    problem = _problem()
    qr = problem.factors.qr(problem.used)
    a = problem.whiten(problem.current_columns())
    r = scipy.linalg.qr(a, mode="economic")[1]
    np.testing.assert_allclose(np.abs(qr.r), np.abs(r), rtol=1e-10, atol=1e-9)
    np.testing.assert_allclose(qr.q @ qr.r, a, rtol=1e-10, atol=1e-9)
    np.testing.assert_allclose(qr.z_perp, qr.z - qr.q @ (qr.q.T @ qr.z), atol=1e-9)
    assert problem.factors.qr(problem.used) is qr
    az = problem.obs.az_rad
    extra = np.concatenate([np.zeros((problem.n, 2)),
                            np.column_stack([np.sin(2 * az), np.cos(2 * az)])])
    problem.add("az_track_2a", extra, ("HESA2", "HECA2"))
    assert problem.factors.cache.keys() == []
    assert problem.factors.qr(problem.used).q.shape[1] == qr.q.shape[1] + 2


def test_a_sun_grid_is_made_once_per_key():
    """The Sun's elevations on a grid are made once per site, epoch and grid."""
    made = []

    def make():
        made.append(1)
        return np.arange(5.0)

    key = ("test_factors", 1.0, 2.0, 0.0, 4.0, 5)
    first = kept_sun_grid(key, make)
    assert kept_sun_grid(key, make) is first and len(made) == 1

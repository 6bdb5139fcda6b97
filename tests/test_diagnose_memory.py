"""What diagnose keeps between its tests, and that keeping less changes no number (issue 28:
diagnose on 200,000 scans within 600 MiB; ``benchmarks/diagnose_scale.py`` measures it)."""

from __future__ import annotations

import numpy as np

from antsim.diagnose.candidates.thermal import (
    OFF_GRID_LEVELS,
    SunsetCandidate,
    TemperatureCandidate,
)
from antsim.diagnose.data import Observations
from antsim.diagnose.problem import Prediction, Problem


def _week(n: int = 600) -> Observations:
    """A week of scans with air temperatures and Sun elevations (no site: the Sun from the
    recorded column)."""
    rng = np.random.default_rng(34)
    t = np.sort(rng.uniform(0.0, 7 * 86400.0, n))
    day = 2 * np.pi * t / 86400.0
    return Observations(t_s=t, az_rad=rng.uniform(0, 6.28, n),
                        el_rad=np.radians(rng.uniform(15.0, 85.0, n)),
                        xel_arcsec=rng.normal(0.0, 5.0, n), el_arcsec=rng.normal(0.0, 5.0, n),
                        good=np.ones(n, dtype=bool), air_temp_c=5.0 + 8.0 * np.sin(day),
                        sun_el_deg=40.0 * np.sin(day - 1.0))


def test_lagged_candidates_keep_their_grid_and_the_last_few_other_levels():
    """A thermal candidate keeps every level of its time-constant grid (asked for again in
    every round and in the cross-validated stage) and only the last OFF_GRID_LEVELS others
    (a search's points); a level made again after it was let go is the same numbers, and
    release() lets every one go."""
    obs = _week()
    for cand, level in ((SunsetCandidate(), lambda c, tau: c.level(obs, tau)),
                        (TemperatureCandidate(), lambda c, tau: c.structure(obs, tau)[0])):
        first = {tau: level(cand, tau).copy() for tau in cand.TAUS}
        off = [777.0, 1234.5, 4321.0, 9876.0]
        made = {tau: level(cand, tau).copy() for tau in off}
        taus = [key[1] for key in cand._cache]
        assert set(cand.TAUS) <= set(taus)
        assert [tau for tau in taus if tau not in cand.TAUS] == off[-OFF_GRID_LEVELS:]
        for tau in (*cand.TAUS, *off):  # kept or made again: the same bytes
            np.testing.assert_array_equal(level(cand, tau), {**first, **made}[tau])
        assert level(cand, cand.TAUS[0]) is level(cand, cand.TAUS[0])  # a grid level: kept
        cand.release()
        assert not cand._cache


def test_the_models_columns_are_held_once_and_released_factors_are_made_again():
    """Once a finding is accepted the base and the accepted columns are views of the stacked
    model (held once), with the values they had; the cached factors released after the
    selection are made again, equal, when asked for."""
    rng = np.random.default_rng(7)
    n = 200
    obs = _week(n)
    problem = Problem(obs, Prediction("white", np.zeros(n), np.zeros(n), np.full(n, 5.0),
                                      np.full(n, 5.0)), ["IA", "IE", "CA", "AN", "AW"])
    base = problem.base.copy()
    extra = rng.normal(size=(2 * n, 2))
    problem.extra.append(extra.copy())
    whole = problem.current_columns()
    np.testing.assert_array_equal(whole, np.column_stack([base, extra]))
    assert np.shares_memory(problem.base, whole) and np.shares_memory(problem.extra[0], whole)
    np.testing.assert_array_equal(problem.base, base)
    np.testing.assert_array_equal(problem.extra[0], extra)
    before = problem._current_qr(problem.used)
    problem.release()
    assert not problem._perps
    again = problem._current_qr(problem.used)
    assert again is not before
    for a, b in zip(before, again, strict=True):
        np.testing.assert_array_equal(a, b)


def test_release_keeps_only_the_factors_over_the_scans_asked_for_next():
    """Before a finding's simplest form, the selection lets go of every cached factor and
    projector but those over the finding's scans (``release(keep=...)``): the model's used
    scans' go, the finding's stay (the same objects, not made again)."""
    n = 200
    problem = Problem(_week(n), Prediction("white", np.zeros(n), np.zeros(n),
                                           np.full(n, 5.0), np.full(n, 5.0)),
                      ["IA", "IE", "CA", "AN", "AW"])
    mask = problem.used.copy()
    mask[:7] = False
    problem.perp_for(problem.used)
    kept = problem.perp_for(mask)
    factor = problem._current_qr(mask)
    assert len(problem._perps) >= 4
    problem.release(keep=mask)
    assert problem._perps and all(mask.tobytes() in k for k in problem._perps)
    assert set(problem._perps) == set(problem._perp_bytes)
    assert problem.perp_for(mask) is kept and problem._current_qr(mask) is factor
    problem.release()
    assert not problem._perps and not problem._perp_bytes


def test_a_shape_mask_equal_to_the_models_scans_is_that_array():
    """A candidate's outlier mask that keeps the model's own scans is the model's array, not
    a copy per result (every result of a round holds its mask: n bytes each)."""
    from antsim.diagnose.candidates.library import CANDIDATES

    n = 300
    obs = _week(n)
    el = obs.el_arcsec.copy()
    el[::50] += 200.0  # six outliers: the masks differ from every valid scan
    obs = Observations(t_s=obs.t_s, az_rad=obs.az_rad, el_rad=obs.el_rad,
                       xel_arcsec=obs.xel_arcsec, el_arcsec=el, good=obs.good)
    problem = Problem(obs, Prediction("white", np.zeros(n), np.zeros(n), np.full(n, 5.0),
                                      np.full(n, 5.0)), ["IA", "IE", "CA", "AN", "AW"])
    problem.update_outliers()
    assert not problem.used[::50].any()
    c = next(c for c in CANDIDATES if c.name == "az_track_2a")
    raw, names = c.columns(obs, None)
    res = c._linear_xp(problem, raw, names, None)[0]
    assert np.array_equal(res.mask, problem.used) and res.mask is problem.used


def test_trim_heap_gives_freed_heap_pages_back_where_the_c_library_can(monkeypatch):
    """glibc keeps freed heap pages resident; :func:`trim_heap` gives them back (RSS falls by
    most of 96 MB freed below the top of the heap), and is a no-op where there is no
    ``malloc_trim`` (another platform)."""
    import sys
    from pathlib import Path

    from antsim import heap

    monkeypatch.setattr(sys, "platform", "darwin")
    assert heap._malloc_trim() is None
    monkeypatch.undo()
    if not heap.trim_heap():
        return  # no glibc here: nothing to give back by this route

    def rss_mib() -> float:
        return int(Path("/proc/self/statm").read_text().split()[1]) * 4096 / 2**20

    # 1,000 arrays of 96 KB (below glibc's mmap threshold: on the heap), the last one kept
    # so that the freed ones lie below the heap's top (not returned by free itself)
    parts = [np.ones(12_000) for _ in range(1000)]
    top = parts.pop()
    del parts
    before = rss_mib()
    assert heap.trim_heap()
    assert before - rss_mib() > 48.0  # half of what was freed, whatever else the heap holds
    del top


def _lagged_problem(cand, tau_s: float, n: int = 3000):
    """A week of scans whose elevation residuals are ``cand``'s signal of time constant
    ``tau_s`` (40" of it, 5" noise, fixed seed), and the grid's best test of it."""
    clean = _week(n)
    signal = 40.0 * cand.unit_signal(clean, {"tau_s": tau_s})
    noise = np.random.default_rng(5).normal(0.0, 5.0, 2 * n)
    obs = Observations(t_s=clean.t_s, az_rad=clean.az_rad, el_rad=clean.el_rad,
                       xel_arcsec=signal[:n] + noise[:n], el_arcsec=signal[n:] + noise[n:],
                       good=clean.good, air_temp_c=clean.air_temp_c,
                       sun_el_deg=clean.sun_el_deg)
    problem = Problem(obs, Prediction("white", np.zeros(n), np.zeros(n), np.full(n, 5.0),
                                      np.full(n, 5.0)), ["IA", "IE", "CA", "AN", "AW"])
    perp, z_perp = problem.perp_for(problem.used)
    tests = [cand._linear(problem, perp, z_perp, *cand.columns(obs, tau), tau)
             for tau in cand.TAUS]
    return problem, perp, z_perp, max(tests, key=lambda res: res.delta_chi2)


def test_a_time_constant_at_a_bound_is_the_bound_within_the_searchs_tolerance():
    """Where the grid's best is its end, the search tests the bound past it and a point
    XATOL_LOG_THETA inside: a fit at least as good at the bound ends it there, within the
    bounded search's tolerance of that search's answer (which creeps to the bound), and no
    worse; an optimum inside leaves the bounded search's answer as it was."""
    import math

    from antsim.diagnose.candidates.thermal import XATOL_LOG_THETA, SunsetTransientCandidate

    cand = SunsetTransientCandidate()
    problem, perp, z_perp, best = _lagged_problem(cand, 300.0)  # below the bound (400 s)
    assert best.theta == cand.TAUS[0]
    lo, b = math.log(cand.TAUS[0] / 1.5), math.log(cand.TAUS[1])
    old = cand._refine_log_theta(problem, perp, z_perp, best, lo, b)
    new = cand._refine_log_theta(problem, perp, z_perp, best, lo, b, lo)
    assert math.isclose(new.theta, cand.TAUS[0] / 1.5, rel_tol=1e-12)  # exp(log(400 s))
    assert new.theta != old.theta
    # the bounded search stops within its tolerance of the bound (2x: Brent's stopping
    # rule bounds the distance to the optimum by twice its tolerance)
    assert abs(math.log(old.theta) - lo) <= 2 * XATOL_LOG_THETA
    assert new.delta_chi2 >= old.delta_chi2

    cand = TemperatureCandidate()
    problem, perp, z_perp, best = _lagged_problem(cand, 26000.0)  # inside (21600, 32400)
    assert best.theta == cand.TAUS[-1]
    a, hi = math.log(cand.TAUS[-2]), math.log(cand.TAUS[-1] * 1.5)
    old = cand._refine_log_theta(problem, perp, z_perp, best, a, hi)
    new = cand._refine_log_theta(problem, perp, z_perp, best, a, hi, hi)
    assert new.theta == old.theta < cand.TAUS[-1] * 1.5
    assert new.delta_chi2 == old.delta_chi2

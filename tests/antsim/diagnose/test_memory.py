"""What diagnose keeps between its tests, and that keeping less changes no number (diagnose
on 200,000 scans within 700 MiB; ``benchmarks/diagnose_scale.py`` measures it)."""

from __future__ import annotations

import numpy as np

from antsim.diagnose.candidates.thermal import (
    SunsetCandidate,
    SunsetTransientCandidate,
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
    before = problem.factors.qr(problem.used)
    problem.factors.clear()
    again = problem.factors.qr(problem.used)
    assert again is not before
    for a, b in zip(before, again, strict=True):
        np.testing.assert_array_equal(a, b)


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


def _lagged_problem(cand, tau_s: float, n: int = 3000):
    """A week of scans whose elevation residuals are ``cand``'s signal of time constant
    ``tau_s`` (40" of it, 5" noise, fixed seed), the grid's best test of it and the grid's
    delta chi^2 by time constant."""
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
    tests = [cand.linear_test(problem, perp, z_perp, *cand.columns(obs, tau), tau)
             for tau in cand.TAUS]
    grid = {tau: res.delta_chi2 for tau, res in zip(cand.TAUS, tests, strict=True)}
    return problem, perp, z_perp, max(tests, key=lambda res: res.delta_chi2), grid


def _bounded_search(cand, problem, perp, z_perp, best, log_lo: float, log_hi: float):
    """The search the thermal candidates made before they started on a grid (the reference
    the grid-started one is tested against): scipy's bounded Brent search in log theta
    between the bounds, to XATOL_LOG_THETA, its best test or ``best`` if that fits better;
    and its number of tests."""
    import math

    from scipy import optimize

    from antsim.diagnose.candidates.thermal import XATOL_LOG_THETA

    obs = problem.obs
    tests: dict[float, object] = {}

    def neg(log_theta: float) -> float:
        theta = math.exp(log_theta)
        tests[log_theta] = cand.linear_test(problem, perp, z_perp, *cand.columns(obs, theta), theta)
        return -tests[log_theta].delta_chi2

    opt = optimize.minimize_scalar(neg, bounds=(log_lo, log_hi), method="bounded",
                                   options={"xatol": XATOL_LOG_THETA})
    res = tests[float(opt.x)]
    return (best if res.delta_chi2 < best.delta_chi2 else res), len(tests)


def _counted(cand, monkeypatch) -> list:
    """The time constants ``cand`` tests off its grid from now on."""
    seen: list = []
    linear = type(cand).linear_test

    def count(self, problem, perp, z_perp, cols, names, theta):
        seen.append(theta)
        return linear(self, problem, perp, z_perp, cols, names, theta)

    monkeypatch.setattr(type(cand), "linear_test", count)
    return seen


def test_a_time_constant_at_a_bound_is_the_bound_within_the_searchs_tolerance():
    """Where the grid's best is its end, the search tests the bound past it and a point
    XATOL_LOG_THETA inside: a fit at least as good at the bound ends it there, within the
    bounded search's tolerance of that search's answer (which creeps to the bound), and no
    worse; an optimum inside is found as the bounded search finds it (within its
    tolerance)."""
    import math

    from antsim.diagnose.candidates.thermal import XATOL_LOG_THETA

    cand = SunsetTransientCandidate()
    problem, perp, z_perp, best, grid = _lagged_problem(cand, 300.0)  # below the bound
    assert best.theta == cand.TAUS[0]
    lo, b = math.log(cand.TAUS[0] / 1.5), math.log(cand.TAUS[1])
    old, _ = _bounded_search(cand, problem, perp, z_perp, best, lo, b)
    new = cand._refine_log_theta(problem, perp, z_perp, best, grid, lo, b, lo)
    assert math.isclose(new.theta, cand.TAUS[0] / 1.5, rel_tol=1e-12)  # exp(log(400 s))
    assert new.theta != old.theta
    # the bounded search stops within its tolerance of the bound (2x: Brent's stopping
    # rule bounds the distance to the optimum by twice its tolerance)
    assert abs(math.log(old.theta) - lo) <= 2 * XATOL_LOG_THETA
    assert new.delta_chi2 >= old.delta_chi2

    cand = TemperatureCandidate()
    problem, perp, z_perp, best, grid = _lagged_problem(cand, 26000.0)  # in (21600, 32400)
    assert best.theta == cand.TAUS[-1]
    a, hi = math.log(cand.TAUS[-2]), math.log(cand.TAUS[-1] * 1.5)
    old, _ = _bounded_search(cand, problem, perp, z_perp, best, a, hi)
    new = cand._refine_log_theta(problem, perp, z_perp, best, grid, a, hi, hi)
    assert new.theta < cand.TAUS[-1] * 1.5
    # both within XATOL_LOG_THETA of the optimum (their own stopping rules)
    assert abs(math.log(new.theta / old.theta)) <= 2 * XATOL_LOG_THETA
    assert math.isclose(new.delta_chi2, old.delta_chi2, rel_tol=1e-4)


def test_a_search_from_the_grid_finds_the_bounded_searchs_time_constant_in_fewer_tests(
        monkeypatch):
    """A time constant between grid points: the search started from the grid's best point
    and its neighbours (their tests this round) ends within XATOL_LOG_THETA of where scipy's
    bounded search (the reference, which ignores the grid) ends, each within that of the
    optimum (2x between them), their fits' delta chi^2 equal to 1e-5 (measured: 4e-6 at
    most; over 1% of tau a fit's delta chi^2 changes by about that), never in more tests
    and in fewer in all (measured: 21 against 32 here; the asymmetric temperature lag's
    as many); both inside the bracket."""
    import math

    from antsim.diagnose.candidates.thermal import XATOL_LOG_THETA

    counts = []
    for cand, tau in ((SunsetCandidate(), 2900.0), (SunsetCandidate(), 7900.0),
                      (SunsetTransientCandidate(), 5000.0), (TemperatureCandidate(), 4400.0),
                      (TemperatureCandidate(), 9000.0)):
        problem, perp, z_perp, best, grid = _lagged_problem(cand, tau)
        i = cand.TAUS.index(best.theta)
        a, b = math.log(cand.TAUS[i - 1]), math.log(cand.TAUS[i + 1])
        old, n_old = _bounded_search(cand, problem, perp, z_perp, best, a, b)
        seen = _counted(cand, monkeypatch)
        new = cand.refine(problem, perp, z_perp, best, grid)
        monkeypatch.undo()
        assert a < math.log(new.theta) < b and new.theta != best.theta
        assert abs(math.log(new.theta / old.theta)) <= 2 * XATOL_LOG_THETA
        assert math.isclose(new.delta_chi2, old.delta_chi2, rel_tol=1e-5)
        assert 0 < len(seen) <= n_old
        counts.append((len(seen), n_old))
    assert sum(c[0] for c in counts) < sum(c[1] for c in counts)


def test_the_next_point_stays_inside_the_bracket_and_off_the_tested_points():
    """:func:`_next_point`: the parabola's vertex where it lies inside the bracket at least
    XATOL_LOG_THETA from the points tested, a golden-section step where there is no vertex
    (collinear points) or the bracket has not halved in two steps, and always into a side
    wider than XATOL_LOG_THETA."""
    from antsim.diagnose.candidates.thermal import _GOLDEN, XATOL_LOG_THETA, _next_point

    tol = XATOL_LOG_THETA
    f = {0.0: -1.0, 0.4: 0.0, 1.0: -1.0}  # -(x - 0.5)^2 shape through three points
    u = _next_point(0.0, 0.4, 1.0, {x: -((x - 0.5) ** 2) for x in f}, [])
    assert abs(u - 0.5) < 1e-12  # a parabola's vertex is exact
    flat = {0.0: 1.0, 0.4: 1.0, 1.0: 1.0}  # no vertex: the wider side's golden section
    assert abs(_next_point(0.0, 0.4, 1.0, flat, []) - (0.4 + _GOLDEN * 0.6)) < 1e-12
    slow = {x: -((x - 0.5) ** 2) for x in (0.0, 0.4, 1.0)}  # the bracket not halved
    assert abs(_next_point(0.0, 0.4, 1.0, slow, [1.0, 0.9, 0.8]) - (0.4 + _GOLDEN * 0.6)) \
        < 1e-12
    near = {x: -((x - 0.405) ** 2) for x in (0.0, 0.4, 1.0)}  # a vertex too near x
    assert abs(_next_point(0.0, 0.4, 1.0, near, []) - (0.4 + tol)) < 1e-12
    narrow = {x: -((x - 0.399) ** 2) for x in (0.395, 0.4, 1.0)}  # its side done already
    assert abs(_next_point(0.395, 0.4, 1.0, narrow, []) - (0.4 + tol)) < 1e-12
    edge = {x: -((x - 0.999) ** 2) for x in (0.0, 0.4, 1.0)}  # within tol of the end
    assert abs(_next_point(0.0, 0.4, 1.0, edge, []) - (1.0 - tol)) < 1e-12
    assert _next_point(None, 0.0, 1.0, {0.0: 0.0, 1.0: -1.0}, []) == _GOLDEN  # at a bound

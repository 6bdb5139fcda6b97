"""antsim/diagnose/decide.py: the decision, one function of a set of scans.

It is repeated inside folds and resamples on columns made once per file: a decision on
some of the scans must be the decision on those scans alone, a bootstrap count must weigh
a scan as its copies would, and its test must be the candidates' own.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from antsim.diagnose import diagnose
from antsim.diagnose.baseline import resolve_baseline, white_prediction
from antsim.diagnose.candidates.library import CANDIDATES, candidate
from antsim.diagnose.decide import Design, decide, parameter_bound, sigma_from_p
from antsim.diagnose.problem import Problem
from tests.conftest import tpoint_like

#: a twice-per-turn track and a once-per-turn runout in 1" noise: two findings
EFFECTS = {"HESA2": 1.2, "HECA2": 0.6, "HASA": 1.5, "HACA": -0.8}


def design_of(obs, n_family: int = 15) -> Design:
    """The design diagnose makes of a TPOINT-like file (no noise prediction)."""
    spec = resolve_baseline(obs, None, None)
    problem = Problem(obs, white_prediction(obs), spec.terms)
    problem.update_outliers()
    usable = [c for c in CANDIDATES if c.applicable(obs, False)]
    return Design(problem, usable, n_family)


def _picks(design: Design, path) -> list[tuple[str, float]]:
    return [(design.options[p.option].label, p.delta_chi2) for p in path.picks]


def test_a_decision_on_some_scans_is_the_decision_on_those_scans_alone():
    """Columns made once per file and sliced per fold: the same choices, chi^2 decreases
    to rounding (1e-9 relative; the same least-squares problems) and stop as a design
    made of those scans alone."""
    obs = tpoint_like(n=120, seed=5, extra=EFFECTS)
    whole = design_of(obs)
    train = np.arange(obs.n) % 4 != 0
    sliced = decide(whole, train.astype(float))
    alone = design_of(obs.select(train))
    fresh = decide(alone, np.ones(alone.u))
    assert len(sliced.picks) >= 2
    got, want = _picks(whole, sliced), _picks(alone, fresh)
    assert [g[0] for g in got] == [w[0] for w in want]
    np.testing.assert_allclose([g[1] for g in got], [w[1] for w in want], rtol=1e-9)
    assert sliced.stop == fresh.stop
    np.testing.assert_allclose(sliced.scale, fresh.scale, rtol=1e-9)


def test_a_bootstrap_count_weighs_a_scan_as_its_copies():
    """A resample's counts (a scan drawn twice counts twice, one not drawn not at all) make
    the decision that the file with those copies would."""
    obs = tpoint_like(n=100, seed=6, extra=EFFECTS)
    whole = design_of(obs)
    counts = np.random.default_rng(1).multinomial(obs.n, np.full(obs.n, 1.0 / obs.n))
    weighted = decide(whole, counts.astype(float))
    idx = np.repeat(np.arange(obs.n), counts)
    copies = design_of(replace(obs, t_s=np.arange(idx.size, dtype=float), az_rad=obs.az_rad[idx],
                               el_rad=obs.el_rad[idx], xel_arcsec=obs.xel_arcsec[idx],
                               el_arcsec=obs.el_arcsec[idx], good=obs.good[idx]))
    fresh = decide(copies, np.ones(copies.u))
    assert len(weighted.picks) >= 1
    got, want = _picks(whole, weighted), _picks(copies, fresh)
    assert [g[0] for g in got] == [w[0] for w in want]
    np.testing.assert_allclose([g[1] for g in got], [w[1] for w in want], rtol=1e-9)


def test_the_decisions_test_is_the_candidates_own():
    """The first pick's chi^2 decrease is the candidate's own added-variable test of the
    same scans (Candidate.test on the problem), and its significance the family-corrected
    one select reports (the same F test, 15 candidates)."""
    obs = tpoint_like(n=160, seed=3, extra={"HESA2": 1.2, "HECA2": 0.9})
    d = design_of(obs, n_family=15)
    pick = decide(d, np.ones(d.u)).picks[0]
    assert d.options[pick.option].label == "az_track_2a"
    problem = d.problem
    perp, z_perp = problem.perp_for(problem.used)
    own = candidate("az_track_2a").test(problem, perp, z_perp, float(z_perp @ z_perp))
    assert pick.delta_chi2 == pytest.approx(own.delta_chi2, rel=1e-9)
    assert pick.log_p == pytest.approx(math.log(min(1.0, own.p * 15)), rel=1e-6)
    assert pick.significance == pytest.approx(sigma_from_p(own.p * 15), rel=1e-6)


def test_the_model_stays_within_the_parameters_the_data_carry():
    """A fifth of the numbers fitted: 18 stars (36 numbers) carry 7 parameters, fewer than
    the eight terms, and an 8" harmonic (some 15 sigma) is not added; 30 stars carry 12,
    room for a pair beside the eight terms, not for a four-term pair of orders."""
    assert parameter_bound(18) == 7 and parameter_bound(30) == 12
    small = tpoint_like(n=18, seed=4, extra={"HESA2": 8.0})
    d = design_of(small)
    path = decide(d, np.ones(d.u))
    assert path.picks == [] and "the next finding would exceed the 7 parameters" in path.stop
    words = diagnose(small).support_words()
    assert words[0].startswith("the 8 base terms exceed the 7 parameters these 18 scans carry")
    enough = tpoint_like(n=30, seed=4, extra={"HESA2": 8.0})
    d = design_of(enough)
    path = decide(d, np.ones(d.u))
    assert [d.options[p.option].label for p in path.picks] == ["az_track_2a"]
    assert d.m + sum(d.options[p.option].q for p in path.picks) <= 12


def test_the_exact_tilts_decision_shape_is_its_second_order_signature():
    """The exact tilt's decision columns are its even part to second order: at a tilt of
    10' and a collimation of 4' they give (e(t) + e(-t)) / 2 to 1e-3 of its largest value
    (the fourth order is (t tan E)^2 of it: 1e-3 at 85 deg, the stars' highest)."""
    tilt = candidate("exact_tilt_collimation")
    obs = tpoint_like(n=60, seed=2)
    (_, cols, names), = tilt.options(obs)
    t = np.array([10.0 * math.cos(0.7), 10.0 * math.sin(0.7), 4.0])
    monomials = np.array([t[0] ** 2, t[1] ** 2, t[2] ** 2, t[0] * t[1], t[0] * t[2],
                          t[1] * t[2]])
    even = 0.5 * (tilt.error(obs, t) + tilt.error(obs, -t))
    assert len(names) == 6 == cols.shape[1]
    np.testing.assert_allclose(cols @ monomials, even, atol=1e-3 * np.abs(even).max())

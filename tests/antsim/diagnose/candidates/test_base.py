"""The candidate interface (antsim.diagnose.candidates.base): candidates keep nothing between
runs, so that diagnosing the same recordings twice gives the same answer."""

from __future__ import annotations

import json

import numpy as np

from antsim.diagnose import diagnose
from antsim.diagnose.baseline import white_prediction
from antsim.diagnose.candidates.base import Candidate
from antsim.diagnose.candidates.library import CANDIDATES
from antsim.diagnose.data import Observations
from antsim.diagnose.problem import Problem


def _week_with_a_sunset_drift(n: int = 400) -> Observations:
    """A week of scans with Sun elevations and air temperatures (the thermal candidates are
    searched over their time constants), 5" noise and a 30" elevation drift after sunset."""
    rng = np.random.default_rng(44)
    t = np.sort(rng.uniform(0.0, 7 * 86400.0, n))
    day = 2 * np.pi * t / 86400.0
    sun = 40.0 * np.sin(day - 1.0)
    return Observations(t_s=t, az_rad=rng.uniform(0, 2 * np.pi, n),
                        el_rad=np.radians(rng.uniform(15.0, 85.0, n)),
                        xel_arcsec=rng.normal(0.0, 5.0, n),
                        el_arcsec=rng.normal(0.0, 5.0, n) + 30.0 * (sun < 0.0),
                        good=np.ones(n, dtype=bool), air_temp_c=5.0 + 8.0 * np.sin(day),
                        sun_el_deg=sun)


def _state() -> dict[str, str]:
    return {c.name: repr(sorted(vars(c).items())) for c in CANDIDATES}


def test_candidates_keep_nothing_between_tests_or_runs():
    """Every candidate of the library is as it was after its test (its attributes are its
    description, set when the library is made: no levels, grids or search points kept) and
    after a whole diagnosis, and a second diagnosis of the same recordings gives the same
    JSON."""
    before = _state()
    obs = _week_with_a_sunset_drift()
    problem = Problem(obs, white_prediction(obs), ["IA", "IE", "NPAE", "CA", "AN", "AW", "TF"])
    problem.update_outliers()
    perp, z_perp = problem.perp_for(problem.used)
    tested = [c.test(problem, perp, z_perp, float(z_perp @ z_perp)) for c in CANDIDATES
              if c.applicable(obs, False)]
    assert {"sunset_drift", "temperature_drift"} <= {r.name for r in tested}
    assert _state() == before
    first = json.dumps(diagnose(obs).to_json(), sort_keys=True)
    assert _state() == before
    assert json.dumps(diagnose(obs).to_json(), sort_keys=True) == first
    assert "sunset" in first  # the thermal candidates were tested (and searched)


def test_every_candidate_declares_its_signature():
    """The one abstract method of the interface is the signature's columns: every candidate
    of the library can be made (each family says its columns, or why it has none)."""
    assert Candidate.__abstractmethods__ == frozenset({"columns"})
    assert all(isinstance(c, Candidate) for c in CANDIDATES)

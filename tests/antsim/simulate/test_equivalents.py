"""The recoverable truth of a campaign: what its fit A should recover (truth.json)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from antsim.run.outputs import run_fits
from antsim.scenario import load_scenario
from antsim.simulate.equivalents import (
    equivalent_arcsec,
    recoverable_truth,
    refraction_equivalent_arcsec,
)
from antsim.simulate.runner import simulate
from tests.conftest import REPO

PARTS = ("mount", "refraction", "heating", "irregularities")


@pytest.fixture(scope="module")
def campaign():
    """The 1990 campaign at seed 1 (the run the README and docs/results.md quote), fit A."""
    scenario = load_scenario(REPO / "scenarios" / "ghigo1990.toml")
    result = simulate(scenario, seed=1)
    return scenario, result, run_fits(result)["A"]


def _honest_pull(fit, name: str, truth_arcsec: float) -> float:
    j = fit.names.index(name)
    return (float(fit.values_arcsec[j]) - truth_arcsec) / float(fit.sigma_honest_arcsec[j])


def test_w5_is_recovered_against_the_recoverable_truth_not_the_mount(campaign):
    """The 1990 program left the atmosphere's refraction uncorrected (docs/physics.md,
    Refraction), so fit A's W5 is the mount's (zero) plus the refraction's cot E share
    (about 0.9'). Against the mount alone W5 is beyond 3 honest sigma (measured at seed 1:
    +14.4), against the recoverable truth within 3 (measured +0.06); 3 sigma is the report's
    own bound for a pull. Every other W is within 3 of it too (measured at most 0.9)."""
    _, result, fit = campaign
    recoverable = result.truth["recoverable"]["terms"]
    mount = result.truth["terms"]
    assert abs(_honest_pull(fit, "W5", mount["W5"]["value_arcsec"])) > 3.0
    for name in fit.names:
        pull = _honest_pull(fit, name, recoverable[name]["value_arcsec"])
        assert abs(pull) < 3.0, (name, pull)


def test_the_parts_sum_to_the_recoverable_value(campaign):
    _, result, fit = campaign
    terms = result.truth["recoverable"]["terms"]
    assert list(terms) == list(fit.names)
    for name, entry in terms.items():
        total = sum(entry[f"{part}_arcsec"] for part in PARTS)
        assert entry["value_arcsec"] == pytest.approx(total, abs=1e-9), name
    # the refraction goes to the cot E term and the elevation terms it resembles, never to
    # the azimuth ones (dA cos E has no refraction); W5's share is of the atmosphere's size
    assert 40.0 < terms["W5"]["refraction_arcsec"] < 70.0
    assert all(abs(terms[f"W{i}"]["refraction_arcsec"]) < 1e-6 for i in range(6, 11))


def test_the_mount_keys_are_unchanged(campaign):
    """``terms`` still holds the mount's injected values, as before the recoverable truth
    (readers of truth.json keep working), and the mount part is the same values."""
    scenario, result, _ = campaign
    injected = scenario.truth_model.as_dict()
    assert result.truth["terms"] == {n: {"value_arcsec": float(v)}
                                     for n, v in injected.items()}
    parts = result.truth["recoverable"]["terms"]
    assert {n: parts[n]["mount_arcsec"] for n in parts} == \
        {n: float(injected[n]) for n in parts}
    json.dumps(result.truth)  # the document stays plain JSON


def test_a_controller_that_corrects_refraction_leaves_no_refraction_part(campaign):
    """With the controller correcting refraction from its weather, only an anomaly's excess
    over the formula would be left; the 1990 world has none."""
    scenario, result, _ = campaign
    from dataclasses import replace

    corrected = replace(scenario, controller=replace(scenario.controller,
                                                     refraction="weather"))
    truth = recoverable_truth(result.rows, corrected, result.world)
    assert all(v == 0.0 for v in truth.refraction.values())
    uncorrected = recoverable_truth(result.rows, scenario, result.world)
    assert uncorrected.refraction == refraction_equivalent_arcsec(
        result.rows, list(uncorrected.mount), scenario.receiver.frequency_ghz)


def test_an_error_of_a_terms_shape_is_that_term():
    """The projection of an exact W5 cot E error on the ten terms is W5 alone."""
    el = np.radians([20.0, 35.0, 50.0, 65.0, 80.0, 30.0, 45.0, 60.0])
    az = np.radians([10.0, 80.0, 150.0, 220.0, 300.0, 350.0, 120.0, 200.0])
    rows = [{"polarization": "AVG", "good": True, "az_deg": np.degrees(a),
             "el_deg": np.degrees(e)} for a, e in zip(az, el, strict=True)]
    terms = [f"W{i}" for i in range(1, 11)]
    got = equivalent_arcsec(rows, terms, np.zeros(el.size), 60.0 / np.tan(el))
    assert got["W5"] == pytest.approx(60.0)
    assert all(abs(got[n]) < 1e-6 for n in terms if n != "W5")

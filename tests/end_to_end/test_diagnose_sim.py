"""antsim diagnose against simulations: the 1990 scenario cut to 11 hours (17:00-04:00 UTC,
noon to five hours after sunset; the after-sunset case uses the whole 24 hours, as the
issue asks), its noise predicted by 4 baseline simulations (cached in pytest's cache
directory, keyed by the code), effects hidden in recordings of fixed seeds.

Tolerances: amplitudes within 3 sigma of the hidden value; the after-sunset time constant
within 30%; the re-simulation's scan-by-scan test must pass (p > 0.01)
after and fail (p < 1e-3) before.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from antsim.cli import main as cli
from antsim.diagnose import diagnose
from antsim.diagnose.baseline import SimulatedBaseline
from antsim.diagnose.data import from_rows
from antsim.scenario import EffectSpec, load_scenario
from antsim.simulate.runner import recording_meta, run_campaign, simulate
from tests.conftest import edit_text

ELEVEN_HOURS = (("duration_h = 24.0", "duration_h = 11.0"),)
N_SIMS = 4


@pytest.fixture(scope="module")
def short(tmp_path_factory, ghigo_text):
    path = tmp_path_factory.mktemp("diag") / "short.toml"
    path.write_text(edit_text(ghigo_text, ELEVEN_HOURS), encoding="utf-8")
    return load_scenario(path)


@pytest.fixture(scope="module")
def cache(diagnose_cache):
    return diagnose_cache


@pytest.fixture(scope="module")
def baseline(short, cache):
    return SimulatedBaseline(short, short.controller.fit_terms, N_SIMS, cache_dir=cache)


def recordings(scenario, seed, effect=None, params=None, model=None):
    if effect is not None:
        scenario = scenario.with_effects((*scenario.effects, EffectSpec(effect, params)))
    if model is not None:
        scenario = scenario.with_controller_model(model)
    res = simulate(scenario, seed)
    return from_rows(res.rows, recording_meta(scenario, seed, res.model))


def test_recordings_of_the_scenario_itself_show_no_mismatch(short, baseline):
    d = diagnose(recordings(short, 11), short, sim_baseline=baseline)
    doc = d.to_json()
    assert doc["mismatch"] is False and doc["findings"] == []
    assert set(doc) >= {"mismatch", "findings"}
    gof = d.summary["gof_before"]
    assert 0.85 < gof["xel"]["ratio"] < 1.15 and 0.85 < gof["el"]["ratio"] < 1.15


def test_a_hidden_track_unevenness_is_named_modelled_and_resimulated(short, baseline, cache,
                                                                     tmp_path):
    from antsim.diagnose.modelit import write_outputs

    hidden = {"amplitude_arcsec": 45.0, "phase_deg": 120.0}
    obs = recordings(short, 12, "az_track_2a", hidden)
    d = diagnose(obs, short, sim_baseline=baseline)
    first = d.findings[0]
    assert first.effect == "az_track_2a" and first.terms == ["HESA2", "HECA2"]
    r = first.result
    assert abs(r.amplitude - 45.0) < 3 * r.amplitude_sigma
    out = write_outputs(d, tmp_path, short, resim=2, cache_dir=cache)
    assert (tmp_path / "scenario_updated.toml").exists()
    again = load_scenario(tmp_path / "scenario_updated.toml")
    assert again.effects[-1].name == "az_track_2a"
    assert "HESA2" in (tmp_path / "model_updated.dat").read_text()
    assert out["plots"]
    res = out["resimulation"]
    assert res["before"]["paired"]["el"]["p"] < 1e-3
    assert res["after"]["paired"]["el"]["p"] > 0.01
    doc = json.loads((tmp_path / "diagnose.json").read_text())
    assert doc["findings"][0]["effect"] == "az_track_2a"


def test_fomalont_after_sunset_drift(ghigo_path, cache):
    """The 24-hour 1990 campaign with 1' in elevation over the 4 hours after sunset
    (Fomalont 1973) hidden; the scenario's own seed."""
    full = load_scenario(ghigo_path)
    base = SimulatedBaseline(full, full.controller.fit_terms, N_SIMS, cache_dir=cache)
    obs = recordings(full, 1, "sunset_drift", {"amplitude_arcsec": 60.0, "tau_s": 5400.0})
    d = diagnose(obs, full, sim_baseline=base)
    first = d.findings[0].result
    assert first.name == "sunset_drift"
    assert abs(first.params["tau_s"] / 5400.0 - 1.0) <= 0.3
    assert abs(first.amplitude - 60.0) < 3 * first.amplitude_sigma
    night = d.variants["A:E"]
    assert night["after"]["el"] < night["before"]["el"]
    assert "after sunset" in d.findings[0].where


def test_a_large_exact_tilt_is_named(short, baseline):
    from antsim.diagnose.blind import absorb_linear

    params = {"tilt_arcmin": 40.0, "tilt_az_deg": 60.0, "collimation_arcmin": 5.0}
    s2 = short.with_effects((*short.effects, EffectSpec("exact_tilt_collimation", params)))
    obs = recordings(short, 13, "exact_tilt_collimation", params, absorb_linear(s2, params))
    d = diagnose(obs, short, sim_baseline=baseline)
    first = d.findings[0].result
    assert first.name == "exact_tilt_collimation"
    assert abs(first.amplitude - 40.0) < 3 * first.amplitude_sigma


def test_diagnose_command_with_a_scenario(short, cache, tmp_path, capsys):
    squint = EffectSpec("polarization_squint", {"separation_arcsec": 20.0, "angle_deg": 90.0})
    s2 = short.with_effects((*short.effects, squint))
    run_campaign(s2, tmp_path / "run", seed=14, show_progress=False)
    code = cli(["diagnose", str(tmp_path / "run" / "recordings.ecsv"), "--scenario",
                short.path, "--json", "--sims", str(N_SIMS), "--cache", str(cache)])
    assert code == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["mismatch"] is True
    f = doc["findings"][0]
    assert f["effect"] == "polarization_squint"
    assert f["params"]["separation_arcsec"] == pytest.approx(20.0, abs=6.0)
    assert f["params"]["angle_deg"] == pytest.approx(90.0, abs=25.0)
    assert np.isfinite(f["significance"])


#: a step of 45" at an unknown time (a held-out case, once named temperature_drift),
#: in either axis: 7-11 sigma on the 24-hour campaign, 6-8 here
STEPS = [("el", 16200.0, 15), ("az", 21600.0, 16)]


@pytest.mark.parametrize(("axis", "t_s", "seed"), STEPS)
def test_a_step_is_named_a_step_and_located(short, baseline, axis, t_s, seed):
    params = {"t_s": t_s, "az_arcsec": 45.0 if axis == "az" else 0.0,
              "el_arcsec": 45.0 if axis == "el" else 0.0}
    d = diagnose(recordings(short, seed, "step", params), short, sim_baseline=baseline)
    first = d.findings[0]
    r = first.result
    assert r.candidate.label(r.theta) == f"step[{axis}]"
    p = r.params
    assert abs(p["step_arcsec"] - 45.0) < 3 * r.amplitude_sigma
    # the change lies between two scans: the 95% interval of change times holds the truth
    assert p["t_low_s"] - 600.0 <= t_s <= p["t_high_s"] + 600.0
    assert p["t_high_s"] - p["t_low_s"] < 3 * 3600.0
    assert "a step, not a drift" in first.where and "UTC" in first.where
    assert "temperature_drift" not in [f.effect for f in d.findings]


def test_a_transient_after_sunset_is_found(short, baseline):
    """100" at sunset dying away over 1.4 h: about 6 sigma of matched filter on the 11-hour
    campaign (the benchmark's 70", about 4.4 sigma, is found on 11 of 16 seeds of the 24-hour
    one: benchmarks/blind.py --changes); named, with its amplitude within 3 sigma."""
    hidden = {"amplitude_arcsec": 100.0, "tau_s": 5040.0, "shape": "transient"}
    d = diagnose(recordings(short, 17, "sunset_drift", hidden), short, sim_baseline=baseline)
    first = d.findings[0].result
    assert first.name == "sunset_transient"
    assert abs(first.amplitude - 100.0) < 3 * first.amplitude_sigma
    assert "dies away" in d.findings[0].where

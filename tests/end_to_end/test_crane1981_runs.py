"""The NRAO 140-ft (Crane 1981): the three scenarios end to end, a noise-free equatorial
campaign, and bad equatorial input.

Each scenario (the memo's three runs of 72, 96 and 72 hours) is run once through the command
line (``antsim run ... --no-report``, seed 3, 2-3 s each) and checked against its own
truth.json: every injected term (Table 4) within 3 sigma, the harmonic gain curve (Table 5)
within 3 sigma, the 10500 MHz tipping opacity within 10%. The memo's own figures are compared
in tests/end_to_end/test_crane1981.py.

Which sigma: TPOINT's (coefficient sigma scaled by the Sky RMS). Measured at seed 3: the
largest pull 1.9 (C2 at 4990 MHz); the noise-free closure test below shows that no bias of
that size exists.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from antsim.cli import main as cli
from controller.pointing.equatorial import (
    EQUATORIAL_MODELS,
    equatorial_term,
)
from controller.pointing.fitting import fit_model
from controller.pointing.model import PointingModel
from controller.units import ARCSEC_PER_RAD

REPO = Path(__file__).resolve().parents[2]
FREQUENCIES = (3245, 4990, 10500)
LAT = 38.437611  # the 140-ft (scenarios: SLALIB GBVA140)


def _scenario(freq: int) -> Path:
    return REPO / "scenarios" / f"crane1981_140ft_{freq}.toml"


# --------------------------------------------------------------------------- a noise-free world
def test_noise_free_equatorial_campaign_recovers_the_model(tmp_path):
    # no noise, no jitter, no atmosphere: the controller's scans in hour angle and declination
    # and the world's beam (converted to az/el for the sky) must agree. 0.5" + 1% of the
    # offset: each axis is measured in its own half of the scan, about a minute before or
    # after the scan's middle where the row (and this comparison) is referenced, while the
    # error changes with hour angle and elevation: up to ~1% of the offsets the model in use
    # leaves, most at low elevation. The model in use is the 3245 MHz one (off by 3.7' in C1
    # and C6) with the truth's C1 and C6, so that the offsets left are tens of arcsec
    from antsim.scenario import load_scenario
    from antsim.simulate.runner import simulate
    from antsim.world.atmosphere import AtmosphereConfig
    from controller.pointing.variants import VARIANTS, columns, pointing_data, variant_mask

    sc = load_scenario(_scenario(4990))
    channels = tuple(replace(c, gain_fluctuation=0.0) for c in sc.receiver.channels)
    receiver = replace(sc.receiver, gain_fluctuation=0.0, bandwidth_mhz=1e12,
                       channels=channels)
    in_use = sc.controller.model.with_values({n: sc.truth_model[n] for n in ("C1", "C6")})
    controller = replace(sc.controller, duration_s=6 * 3600.0, tipping=None, model=in_use,
                         scan=replace(sc.controller.scan, overhead_s=8.0),
                         scheduler=replace(sc.controller.scheduler, min_revisit_s=300.0))
    sc = replace(sc, duration_s=6 * 3600.0, effects=(), receiver=receiver,
                 atmosphere=AtmosphereConfig(zenith_opacity=0.0), controller=controller)
    result = simulate(sc, seed=3)
    cols = columns(result.rows)
    # above 15 deg: lower, the refraction (6-9' at 5-8 deg, in the C5 term) changes by
    # several arcsec between the scan's halves (2.7" seen at 6-8 deg)
    data = pointing_data(cols, variant_mask(cols, VARIANTS[0])
                         & (cols["el_deg"].astype(float) > 15.0))
    assert len(data) >= 30
    assert "ha_deg" in result.rows[0] and "dec_deg" in result.rows[0]
    # without the refraction_anomaly effect the sky refracts by the reference refraction:
    # Crane's C5 (controller.crane) is then exactly 1 (60 in the model's arcsec)
    truth = sc.truth_model.with_values({"C5": 60.0})
    d_h, d_d = truth.offset_rad(data.az_rad, data.el_rad)
    np.testing.assert_allclose(data.xel_arcsec, d_h * np.cos(data.el_rad) * ARCSEC_PER_RAD,
                               atol=0.5, rtol=0.01)
    np.testing.assert_allclose(data.el_arcsec, d_d * ARCSEC_PER_RAD, atol=0.5, rtol=0.01)
    # the fit of the whole model recovers every term to 0.6": in these six hours most sources
    # set, so the smearing has one sign and moves the correlated IH, CH, ME, FO by 0.3-0.4"
    fit = fit_model(data, truth.terms, robust=False)
    np.testing.assert_allclose(fit.values_arcsec, truth.values_arcsec, atol=0.6)


# --------------------------------------------------------------------------- the scenarios
@pytest.fixture(scope="module", params=FREQUENCIES)
def crane_run(request, tmp_path_factory) -> tuple[int, Path]:
    out = tmp_path_factory.mktemp(f"crane{request.param}")
    assert cli(["run", str(_scenario(request.param)), "--out", str(out), "--no-report"]) == 0
    return request.param, out


def test_crane_run_recovers_every_injected_term(crane_run):
    freq, out = crane_run
    truth = json.loads((out / "truth.json").read_text())
    fit = json.loads((out / "fit.json").read_text())
    assert truth["seed"] == 3 and truth["model"] == "crane1981" == fit["model"]
    assert truth["mount"] == "equatorial"
    assert list(fit["terms"]) == list(EQUATORIAL_MODELS["crane1981"]) == list(truth["terms"])
    assert fit["n_used"] > 150 and not fit["unconstrained"]
    scale = next(e["params"]["scale"] for e in truth["effects"]
                 if e["effect"] == "refraction_anomaly")
    for name, entry in fit["terms"].items():
        # C5 is the sky's refraction scale (the effect), the others the telescope's terms
        true = 60.0 * scale if name == "C5" else truth["terms"][name]["value_arcsec"]
        assert abs(entry["value_arcsec"] - true) < 3.0 * entry["sigma_arcsec"], (freq, name)
    # day and night fits (Crane; the 1990 report's D and E) exist and agree with fit A
    variants = json.loads((out / "fit_variants.json").read_text())
    for v in ("D", "E"):
        assert variants[v] is not None and variants[v]["n_used"] > 60
    # the injected wander (Table 4's rms per point, RA ~20", Dec ~11") and nothing more
    assert 15.0 < fit["xel_rms_arcsec"] < 28.0 and 8.0 < fit["el_rms_arcsec"] < 14.0


def test_crane_run_measures_opacity_and_gain_curve(crane_run):
    freq, out = crane_run
    truth = json.loads((out / "truth.json").read_text())
    cal = json.loads((out / "gaincurve.json").read_text())
    if freq == 10500:
        # tipping scans (Crane section IV) every 3 h; the opacity within 10%: the observer's
        # assumed 260 K against the true 265 K makes it ~2% high, the scans' noise is smaller
        assert len(cal["tippings"]) >= 20
        assert cal["zenith_opacity"]["from"].startswith("tipping")
        tau = cal["zenith_opacity"]["value"]
        assert tau == pytest.approx(truth["zenith_opacity"], rel=0.10)
        assert tau > truth["zenith_opacity"]  # the sign of the 260 K assumption
    else:  # Crane corrected for the atmosphere only at 10500 MHz
        assert cal["tippings"] == [] and cal["zenith_opacity"]["value"] == 0.0
    # the gain curve's harmonics (Table 5 as the truth) within 3 of their HC1 errors
    gain = cal["gain_curve"]
    for name, true in truth["gain_curve"]["coefficients_k_per_jy"].items():
        value = gain["coefficients_k_per_jy"][name]
        sigma = gain["sigma_k_per_jy"][name]
        assert abs(value - true) < 3.0 * sigma, (freq, name, value, true, sigma)


def test_crane_recordings_carry_hour_angle_and_declination(crane_run):
    from controller.program.recordings import read_recordings

    _, out = crane_run
    table = read_recordings(out / "recordings.ecsv")
    assert table.meta["mount"] == "equatorial"
    assert "ha_deg" in table.colnames and "dec_deg" in table.colnames
    assert np.all(np.abs(np.asarray(table["ha_deg"])) <= 90.0)  # the mount's hour-angle range
    # antsim fit reads them back in hour angle and declination with the equatorial model
    assert cli(["fit", str(out / "recordings.ecsv"), "--json"]) == 0


def test_fitted_model_files_load_back_for_the_closed_loop(crane_run):
    # antsim run --model DIR/model.dat (or fit.json) on an equatorial scenario
    from antsim.scenario import load_scenario
    from controller.errors import InputError
    from controller.pointing.equatorial import load_equatorial_model

    freq, out = crane_run
    fit = json.loads((out / "fit.json").read_text())
    from_mod = load_equatorial_model(str(out / "model.dat"), LAT)
    from_json = load_equatorial_model(str(out / "fit.json"), LAT)
    assert from_mod.names == from_json.names == EQUATORIAL_MODELS["crane1981"]
    np.testing.assert_allclose(from_json.values_arcsec,
                               [t["value_arcsec"] for t in fit["terms"].values()])
    np.testing.assert_allclose(from_mod.values_arcsec, from_json.values_arcsec, atol=1e-4)
    assert from_mod.terms[4] is equatorial_term("C5", LAT)  # Crane's C5
    scenario = load_scenario(_scenario(freq))
    # a model named by TPOINT names only (as modelio would read it) is re-bound too
    rebound = scenario.with_controller_model(PointingModel(["TF"], [5.0]))
    assert rebound.controller.model.terms[0] == equatorial_term("TF", scenario.site.latitude_deg)
    with pytest.raises(InputError, match="unknown equatorial term"):
        bad = out / "bad.mod"
        bad.write_text("caption\nT 1 1 0 0\n  IA   1.0\nEND\n")
        load_equatorial_model(str(bad), LAT)


# --------------------------------------------------------------------------- bad input
@pytest.mark.parametrize("edit, field", [
    (("[[truth.effects]]\neffect = \"tracking_jitter\"",
      "[[truth.effects]]\neffect = \"thermal\"\n\n[[truth.effects]]\n"
      "effect = \"tracking_jitter\""), "effect"),
    (("C10 = -0.15\nC11 = -0.16", "C10 = -0.15\nC11 = -0.16\nIA = 1.0"), "truth.terms.IA"),
    (('model = "crane1981"\nunits = "arcmin"\n[truth.terms]',
      'model = "ghigo10"\nunits = "arcmin"\n[truth.terms]'), "truth.model"),
    (("min_deg = -90.0\nmax_deg = 90.0", "min_deg = 10.0\nmax_deg = 90.0"), "mount.ha"),
])
def test_bad_equatorial_input_is_one_line(tmp_path, capsys, edit, field):
    text = _scenario(4990).read_text()
    old, new = edit
    assert text.count(old) == 1
    path = tmp_path / "bad.toml"
    path.write_text(text.replace(old, new))
    assert cli(["run", str(path), "--out", str(tmp_path / "out"), "--no-report"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and field in err and "bad.toml" in err

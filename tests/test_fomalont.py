"""Fomalont 1973's feed terms: the feed angle as a regressor, the feed box, and the scenario.

The 45-ft's feed box is turned to several feed angles f; the feed adds C6 cos(f - C7) to the
cross-elevation error and D6 cos(f - D7) to the elevation error. Written as a cos f + b sin f
these are the feed terms HSCF, HSSF (cross-elevation) and HECF, HESF (elevation), fitted
with the feed angle recorded per scan.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from antsim.cli import main as cli
from antsim.world.effects import EFFECTS, PointingState
from controller.pointing.data import PointingData
from controller.pointing.fitting import fit_model
from controller.pointing.model import NAMED_MODELS, PointingModel
from controller.pointing.terms import get_term
from controller.units import ARCSEC_PER_RAD, RAD_PER_ARCSEC

REPO = Path(__file__).resolve().parents[1]
SCENARIO = REPO / "scenarios" / "fomalont1973.toml"


def test_feed_terms_need_and_use_the_feed_angle():
    az, el, f = np.array([0.3, 2.0]), np.array([0.5, 1.0]), np.array([0.4, -1.2])
    model = PointingModel(["HSCF", "HSSF", "HECF", "HESF"], [1.0, 2.0, 3.0, 4.0])
    assert model.needs_feed and not PointingModel("ghigo10").needs_feed
    # indicated - true = minus the correction; the correction is dA cos E = -(HSCF cos f +
    # HSSF sin f) (the harmonic generator's sign for dA cos E) and dE = +(HECF cos f + ...)
    d_az, d_el = model.offset_rad(az, el, f)
    np.testing.assert_allclose(d_az * np.cos(el) * ARCSEC_PER_RAD,
                               np.cos(f) + 2.0 * np.sin(f), atol=1e-12)
    np.testing.assert_allclose(d_el * ARCSEC_PER_RAD, -(3.0 * np.cos(f) + 4.0 * np.sin(f)),
                               atol=1e-12)
    assert model.offset_scalar_rad(0.3, 0.5, 0.4)[1] == pytest.approx(d_el[0], abs=1e-18)
    with pytest.raises(ValueError, match="feed angle"):
        model.offset_rad(az, el)
    assert "dA cos E" in get_term("HSCF").description
    assert NAMED_MODELS["fomalont14"][-4:] == ("HSCF", "HSSF", "HECF", "HESF")


def test_feed_offset_effect_forms_and_their_coefficients():
    state = PointingState(t_s=0.0, az_rad=1.0, el_rad=0.6, feed_angle_rad=math.radians(70.0))
    fomalont = EFFECTS["feed_offset"](offset_arcsec=30.0, angle_deg=35.0, form="fomalont",
                                      el_offset_arcsec=24.0, el_angle_deg=120.0)
    d_az, d_el = fomalont.pointing_error(state)
    assert d_az * math.cos(0.6) / RAD_PER_ARCSEC == pytest.approx(30 * math.cos(math.radians(35)))
    assert d_el / RAD_PER_ARCSEC == pytest.approx(24 * math.cos(math.radians(-50)))
    # the feed terms with the effect's coefficients reproduce the error exactly
    coeffs = fomalont.coefficients()
    model = PointingModel(list(coeffs), list(coeffs.values()))
    m_az, m_el = model.offset_scalar_rad(1.0, 0.6, state.feed_angle_rad)
    assert (m_az, m_el) == pytest.approx((d_az, d_el), abs=1e-15)
    # the rigid (default) form is D6 = C6, D7 = C7 + 90 and keeps its old behaviour
    rigid = EFFECTS["feed_offset"](offset_arcsec=30.0, angle_deg=35.0)
    _, r_el = rigid.pointing_error(state)
    ang = state.feed_angle_rad - math.radians(35.0)
    assert r_el == 30.0 * RAD_PER_ARCSEC * math.sin(ang)
    assert rigid.coefficients()["HECF"] == pytest.approx(-30 * math.cos(math.radians(125)))
    assert rigid.truth()["terms"] == ["CA", "IE"]
    assert fomalont.truth()["terms"] == ["HSCF", "HSSF", "HECF", "HESF"]
    # feed terms given directly as truth terms turn with the feed angle as well
    terms = EFFECTS["terms"](terms_arcsec=coeffs)
    assert terms.pointing_error(state) == pytest.approx((d_az, d_el), abs=1e-15)


def test_pointing_data_carries_the_feed_angle_through_selection():
    rng = np.random.default_rng(2)
    n = 200
    az, el = rng.uniform(0, 2 * math.pi, n), rng.uniform(0.2, 1.4, n)
    f = np.radians(rng.choice([0.0, 60.0, 120.0, 180.0, 240.0, 300.0], n))
    truth = PointingModel(["IA", "IE", "CA", "HSCF", "HSSF", "HECF", "HESF"],
                          [20.0, -30.0, 10.0, 24.6, 17.2, 12.0, -20.8])
    d_az, d_el = truth.offset_rad(az, el, f)
    data = PointingData(az, el, d_az * np.cos(el) * ARCSEC_PER_RAD, d_el * ARCSEC_PER_RAD,
                        feed_rad=f)
    half = data.select(np.arange(n) < 150)
    assert half.feed_rad.shape == (150,)
    fit = fit_model(half, truth.names, robust=False)
    np.testing.assert_allclose(fit.values_arcsec, truth.values_arcsec, atol=1e-9)
    with pytest.raises(ValueError, match="feed angle"):
        fit_model(PointingData(az, el, data.xel_arcsec, data.el_arcsec), truth.names)


def test_the_feed_box_turns_through_the_protocol(quiet_path):
    import simpy

    from antsim.scenario import load_scenario
    from antsim.world.world import World
    from controller.protocol import FeedAntenna

    scenario = load_scenario(quiet_path)
    env = simpy.Environment()
    world = World(scenario, env)
    antenna = world.antenna
    assert isinstance(antenna, FeedAntenna)
    env.run(until=antenna.set_feed_angle(90.0))
    # 90 deg at the default 2 deg/s, then the settle time
    assert env.now == pytest.approx(45.0 + scenario.mount.settle_s)
    assert antenna.feed_angle_deg() == 90.0


@pytest.fixture(scope="module")
def fomalont_run(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("fomalont")
    assert cli(["run", str(SCENARIO), "--out", str(out), "--no-report"]) == 0
    return out


def test_fomalont_run_recovers_every_injected_term(fomalont_run):
    truth = json.loads((fomalont_run / "truth.json").read_text())
    fit = json.loads((fomalont_run / "fit.json").read_text())
    assert truth["seed"] == 3 and fit["model"] == "fomalont14"
    feed = next(e for e in truth["effects"] if e["effect"] == "feed_offset")
    expected = {n: v["value_arcsec"] for n, v in truth["terms"].items()}
    expected.update(feed["coefficients_arcsec"])
    assert set(expected) == set(fit["terms"])
    # TPOINT's sigma (see the module docstring of tests/test_equatorial.py); here the honest
    # sigma passes as well (largest pull 2.1)
    for name, entry in fit["terms"].items():
        assert abs(entry["value_arcsec"] - expected[name]) < 3.0 * entry["sigma_arcsec"], name
    # Fomalont's own parameters back from the linear coefficients
    t = fit["terms"]
    c6 = math.hypot(t["HSCF"]["value_arcsec"], t["HSSF"]["value_arcsec"])
    c7 = math.degrees(math.atan2(t["HSSF"]["value_arcsec"], t["HSCF"]["value_arcsec"]))
    d6 = math.hypot(t["HECF"]["value_arcsec"], t["HESF"]["value_arcsec"])
    d7 = math.degrees(math.atan2(-t["HESF"]["value_arcsec"], -t["HECF"]["value_arcsec"]))
    p = feed["params"]
    # 1.2" sigma per coefficient: 3 sigma is ~4" in amplitude and ~8 deg in phase at 24-30"
    assert c6 == pytest.approx(p["offset_arcsec"], abs=4.0)
    assert d6 == pytest.approx(p["el_offset_arcsec"], abs=4.0)
    assert (c7 - p["angle_deg"] + 180) % 360 - 180 == pytest.approx(0.0, abs=8.0)
    assert (d7 - p["el_angle_deg"] + 180) % 360 - 180 == pytest.approx(0.0, abs=8.0)


def test_fomalont_recordings_record_the_feed_angles(fomalont_run):
    from controller.program.recordings import read_recordings

    table = read_recordings(fomalont_run / "recordings.ecsv")
    assert table.meta["feed_angles_deg"] == [0.0, 60.0, 120.0, 180.0, 240.0, 300.0]
    angles = np.asarray(table["feed_angle_deg"])
    scans = np.asarray(table["scan"])
    first = np.unique(scans, return_index=True)[1]
    # one angle per scan, cycling through the list
    np.testing.assert_array_equal(angles[first][:12], [0, 60, 120, 180, 240, 300] * 2)
    assert table.meta["refraction"] == "standard"  # Fomalont's fixed refraction
    # antsim fit reads the feed angles back
    assert cli(["fit", str(fomalont_run / "recordings.ecsv"), "--model", "fomalont14",
                "--json"]) == 0


def test_bad_feed_form_is_one_line(tmp_path, capsys):
    text = SCENARIO.read_text().replace('form = "fomalont"', 'form = "elliptic"')
    path = tmp_path / "bad.toml"
    path.write_text(text)
    assert cli(["run", str(path), "--out", str(tmp_path / "out"), "--no-report"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "form" in err and "elliptic" in err

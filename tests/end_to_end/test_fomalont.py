"""Fomalont 1973 (the 1990 report's Appendix A): the feed terms, the feed box, and the memo's
survey of 28 February - 2 March 1973 at S- and X-band re-created from the memo.

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
from antsim.documents import (
    FOMALONT1973,
    FOMALONT1973_COEFFICIENTS,
    FOMALONT1973_DATES,
    FOMALONT1973_EFFICIENCY,
    FOMALONT1973_SOURCES,
    GHIGO1990_GAIN_CURVE,
)
from antsim.world.effects import EFFECTS, PointingState
from controller.pointing.data import PointingData
from controller.pointing.fitting import fit_model
from controller.pointing.model import NAMED_MODELS, PointingModel
from controller.pointing.terms import get_term
from controller.units import ARCSEC_PER_RAD, RAD_PER_ARCSEC

REPO = Path(__file__).resolve().parents[2]
SCENARIOS = {band: REPO / "scenarios" / f"fomalont1973_{band}.toml" for band in ("x", "s")}


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


@pytest.mark.parametrize("band", ["x", "s"])
def test_the_scenarios_follow_the_memo(band):
    """Memo, introduction: "between February 28 and March 2, 1973", the eight sources, "at
    both S-Band and X-Band"; section II: one polarization per band (SR, XL) and the mean
    efficiencies; section I: the feed terms' C6, C7, D6, D7 and D5 held at 1'.1."""
    from antsim.scenario import load_scenario

    s = load_scenario(SCENARIOS[band])
    import datetime as dt

    start = dt.datetime.fromisoformat(s.epoch_utc[:19])
    end = start + dt.timedelta(seconds=s.duration_s)
    assert start.date().isoformat() == FOMALONT1973_DATES[0]
    assert end.isoformat() == FOMALONT1973_DATES[1] + "T23:00:00"  # 18:00 EST on 2 March
    assert tuple(src.name for src in s.sources) == FOMALONT1973_SOURCES
    assert [c.name for c in s.receiver.channels] == (["XL"] if band == "x" else ["SR"])
    efficiency = 0.376 if band == "x" else 0.386
    # K/Jy = eta pi (13.7 m / 2)^2 / 2k, rounded to 0.1 mK/Jy
    assert s.beam.gain_k_per_jy == pytest.approx(efficiency * math.pi * 6.85**2 * 1e-26
                                                  / (2 * 1.380649e-23), abs=6e-5)
    assert set(s.beam.efficiency) == {1.0}
    feed = next(e for e in s.effects if e.name == "feed_offset").params
    assert (feed["offset_arcsec"], feed["angle_deg"], feed["el_offset_arcsec"],
            feed["el_angle_deg"]) == pytest.approx((0.71 * 60, 152.0, 0.76 * 60, 250.0))
    assert dict(s.controller.fit_fixed) == {"W5": pytest.approx(66.0)}
    assert s.controller.model.as_dict()["W5"] == pytest.approx(66.0)
    assert s.controller.refraction == "none"


@pytest.fixture(scope="module")
def fomalont_runs(tmp_path_factory) -> dict[str, Path]:
    """The memo's run at both bands (58 h each, seed 3)."""
    runs = {}
    for band in ("x", "s"):
        out = tmp_path_factory.mktemp(f"fomalont_{band}")
        assert cli(["run", str(SCENARIOS[band]), "--out", str(out), "--no-report",
                    "--no-progress"]) == 0
        runs[band] = out
    return runs


def _fits(run: Path) -> tuple[dict, dict, dict]:
    truth = json.loads((run / "truth.json").read_text())
    variants = json.loads((run / "fit_variants.json").read_text())
    return truth, variants["A"], variants["F"]


def _memo_arcsec() -> dict[str, float]:
    """The memo's coefficients on our terms (arcsec): C1..C5, D1..D5 as W's, C6/C7, D6/D7 as
    the linear feed terms."""
    return {name: 60.0 * value for name, (value, _) in FOMALONT1973.terms.items()}


@pytest.mark.parametrize("band", ["x", "s"])
def test_the_memos_coefficients_are_recovered(fomalont_runs, band):
    """The injected truth is the memo's fit (section I); fit A recovers every coefficient
    within 3 of its TPOINT sigma at both bands (seed 3: largest 2.6, W1 at X, the night of
    28 February's drift), D5 held at 1'.1 as the memo held it."""
    truth, fit, _ = _fits(fomalont_runs[band])
    memo = _memo_arcsec()
    feed = next(e for e in truth["effects"] if e["effect"] == "feed_offset")
    # the truth is the memo: its W's (W5 is the atmosphere's, 0 as a term) and feed terms
    for name, value in memo.items():
        injected = (feed["coefficients_arcsec"] if name.startswith("H") else
                    {k: v["value_arcsec"] for k, v in truth["terms"].items()})[name]
        assert injected == pytest.approx(0.0 if name == "W5" else value, abs=1e-9), name
    assert fit["model"] == "fomalont14" and fit["fixed"] == ["W5"]
    assert fit["terms"]["W5"] == {"value_arcsec": pytest.approx(66.0), "sigma_arcsec": None,
                                  "sigma_honest_arcsec": None}
    for name, value in memo.items():
        if name == "W5":
            continue
        entry = fit["terms"][name]
        assert abs(entry["value_arcsec"] - value) < 3.0 * entry["sigma_arcsec"], name
    # C6, C7, D6, D7 back from the linear terms (sigma ~4.6" per term: 3 sigma is ~14" in
    # amplitude and ~19 deg of phase at 43")
    t = {k: v["value_arcsec"] for k, v in fit["terms"].items()}
    c6, c7 = math.hypot(t["HSCF"], t["HSSF"]), math.degrees(math.atan2(t["HSSF"], t["HSCF"]))
    d6 = math.hypot(t["HECF"], t["HESF"])
    d7 = math.degrees(math.atan2(-t["HESF"], -t["HECF"]))
    assert c6 / 60.0 == pytest.approx(0.71, abs=14.0 / 60.0)
    assert d6 / 60.0 == pytest.approx(0.76, abs=14.0 / 60.0)
    assert (c7 - 152.0 + 180.0) % 360.0 - 180.0 == pytest.approx(0.0, abs=19.0)
    assert (d7 - 250.0 + 180.0) % 360.0 - 180.0 == pytest.approx(0.0, abs=19.0)


@pytest.mark.parametrize("band", ["x", "s"])
def test_the_memos_rms_per_point(fomalont_runs, band):
    """Memo, section I: "The rms deviation in azimuth of a data point from the best fit is
    0'.49; for elevation the rms deviation is 0'.84". The memo's fit used every point (no
    filter is described): our fit F, within 25% (seed 3: X 30.9"/51.6", S 27.4"/42.2", against
    29.4"/50.4"; the jitter was calibrated on X)."""
    _, _, fit_f = _fits(fomalont_runs[band])
    xel, el = FOMALONT1973.rms_arcsec
    assert fit_f["xel_rms_arcsec"] == pytest.approx(xel, rel=0.25)
    assert fit_f["el_rms_arcsec"] == pytest.approx(el, rel=0.25)


def test_x_and_s_band_agree(fomalont_runs):
    """Memo: "Good agreement between X-Band And S-Band pointing": every fitted coefficient
    of the two bands within 3 of their combined TPOINT sigma (seed 3: at most 1.2)."""
    _, fx, _ = _fits(fomalont_runs["x"])
    _, fs, _ = _fits(fomalont_runs["s"])
    for name, x in fx["terms"].items():
        s = fs["terms"][name]
        if name == "W5":
            assert x["value_arcsec"] == s["value_arcsec"] == pytest.approx(66.0)
            continue
        combined = math.hypot(x["sigma_arcsec"], s["sigma_arcsec"])
        assert abs(x["value_arcsec"] - s["value_arcsec"]) < 3.0 * combined, name


def _recordings(run: Path):
    from controller.pointing.variants import VARIANTS, columns, variant_mask
    from controller.program.recordings import read_recordings

    table = read_recordings(run / "recordings.ecsv")
    cols = columns(table)
    return table, cols, variant_mask(cols, VARIANTS[0])


@pytest.mark.parametrize("band", ["x", "s"])
def test_the_elevation_changed_after_sunset_on_28_february(fomalont_runs, band):
    """Memo: "For a period of 4 hours after sunset on February 28, the elevation appeared to
    change systematically by 1'.0 at both S and X-Band." Fit A's elevation residuals 3-4 h
    after that sunset, less those of the 2 h before it, are 1'.0 within 25" (about 10 and 20
    scans, jitter ~40" each: ~15" of noise); after the next sunset the change is within 30" of
    none (seed 3: X +59.7" and +19.3", S +47.2" and +13.2")."""
    import simpy

    from antsim.scenario import load_scenario
    from antsim.world.world import World
    from controller.astro.sun import sunset_times_s
    from controller.pointing.variants import pointing_data

    table, cols, mask = _recordings(fomalont_runs[band])
    fit = fit_model(pointing_data(cols, mask), "fomalont14", fixed={"W5": 66.0})
    t = cols["t_s"][mask].astype(float)
    world = World(load_scenario(SCENARIOS[band]), simpy.Environment())
    first, second = sunset_times_s(world.ephemeris, horizon_deg=0.0)[:2]
    res = fit.residual_el_arcsec

    def change(t_set: float) -> float:
        before = (t > t_set - 7200.0) & (t < t_set)
        after = (t > t_set + 3 * 3600.0) & (t < t_set + 4 * 3600.0)
        assert before.sum() >= 10 and after.sum() >= 5
        return float(res[after].mean() - res[before].mean())

    assert table.meta["epoch_utc"].startswith("1973-02-28")
    assert (first - 0.0) / 3600.0 < 24.0  # the first sunset is 28 February's
    assert change(first) == pytest.approx(60.0, abs=25.0)
    assert abs(change(second)) < 30.0


def test_the_drift_follows_the_first_sunset_only():
    """The scenario's sunset drift (nights = 1): 1'.0 (a (1 - e^-4) with tau = 1 h) four
    hours after 28 February's sunset, nothing four hours after 1 March's, nothing before the
    first (the spin-up day's nights do not count)."""
    import simpy

    from antsim.scenario import load_scenario
    from antsim.world.world import World
    from controller.astro.sun import sunset_times_s

    world = World(load_scenario(SCENARIOS["x"]), simpy.Environment())
    drift = next(e for e in world.effects if e.name == "sunset_drift")
    first, second = sunset_times_s(world.ephemeris, horizon_deg=0.0)[:2]
    # the model's night indicator switches on the 60-s grid: 1 min of 1 h, 1.7% of a
    assert float(drift.error_arcsec(first + 4 * 3600.0)) == pytest.approx(
        60.0 * (1.0 - math.exp(-4.0)), rel=0.02)
    assert float(drift.error_arcsec(second + 4 * 3600.0)) < 1e-3
    assert float(drift.error_arcsec(first - 60.0)) == 0.0


def test_low_elevation_points_were_difficult_to_fit(fomalont_runs):
    """Memo: "Low elevation points were difficult to fit to the elevation data. Pointing
    residuals of 1 to 2 arc minutes were common." Below 10 deg (Cen A, which culminates near
    9 deg here, and the rising and setting sources) real refraction falls short of the 1'.1
    cot E the fit holds (by 0.3' at 10 deg, 1.2' at 6 deg). At X, fit F's elevation residuals
    there have 1.5 times or more the rms of those above 20 deg, and residuals beyond 1'.5 are
    three times as frequent (seed 3: 83" against 43", 12% against 4%, the largest 2'.6).
    At S the scans stop at 6.5 deg and the effect is milder (45" against 42")."""
    from controller.pointing.fitting import fit_model
    from controller.pointing.variants import VARIANTS, columns, pointing_data, variant_mask
    from controller.program.recordings import read_recordings

    table = read_recordings(fomalont_runs["x"] / "recordings.ecsv")
    cols = columns(table)
    mask = variant_mask(cols, VARIANTS[5])
    fit = fit_model(pointing_data(cols, mask), "fomalont14", robust=False, fixed={"W5": 66.0})
    el = cols["el_deg"][mask].astype(float)
    res = fit.residual_el_arcsec
    low, high = el < 10.0, el > 20.0
    assert low.sum() >= 30

    def rms(sel):
        return float(np.sqrt(np.mean(res[sel] ** 2)))

    assert rms(low) > 1.5 * rms(high)
    beyond = np.abs(res) > 90.0
    assert beyond[low].mean() > 3 * beyond[high].mean()
    assert np.abs(res[low]).max() > 120.0


def test_the_axis_orientation_remark():
    """Memo, comment 2: "The solutions of the antenna axis alignment from the azimuth and
    elevation solutions are consistent. The axis orientation is 0'.8 north and 0'.5 east of
    zenith." On the report's functions a tilt t_N towards north and t_E towards east is
    W2 = W8 = t_N (D2 = C3) and W3 = -W7 = t_E (D3 = -C2): the memo's D2, C3 give 0.68' and
    0.94' north, D3, -C2 0.61' and 0.40' east, means 0.81' and 0.505'. The direction is
    checked against the world's exact tilt, rotated about the horizontal axis: a tilt of
    0.943' towards azimuth 32 deg (0.8' N, 0.5' E), fitted with the ten terms, gives
    W2 = W8 = 0.8' and W3 = -W7 = 0.5' (to 0.001': the small-angle terms are exact to
    second order, 1e-7 rad here)."""
    f = FOMALONT1973_COEFFICIENTS
    north = (f["D2"] + f["C3"]) / 2.0
    east = (f["D3"] - f["C2"]) / 2.0
    assert round(north, 1) == 0.8 and round(east, 1) == 0.5
    # each pair agrees within 0.3': "consistent"
    assert abs(f["D2"] - f["C3"]) < 0.3 and abs(f["D3"] + f["C2"]) < 0.3
    tilt = EFFECTS["exact_tilt_collimation"](tilt_arcmin=math.hypot(0.8, 0.5),
                                             tilt_az_deg=math.degrees(math.atan2(0.5, 0.8)))
    az, el = np.meshgrid(np.radians(np.arange(0.0, 360.0, 15.0)),
                         np.radians(np.arange(10.0, 81.0, 10.0)))
    az, el = az.ravel(), el.ravel()
    enc_az, enc_el = tilt.encoder_from_true(az, el)
    d_az = (enc_az - az + math.pi) % (2 * math.pi) - math.pi
    data = PointingData(az, el, d_az * np.cos(el) * ARCSEC_PER_RAD,
                        (enc_el - el) * ARCSEC_PER_RAD)
    fit = fit_model(data, "ghigo10", robust=False)
    w = {n: v / 60.0 for n, v in zip(fit.names, fit.values_arcsec, strict=True)}
    for name, want in (("W2", 0.8), ("W8", 0.8), ("W3", 0.5), ("W7", -0.5)):
        assert w[name] == pytest.approx(want, abs=1e-3), name


@pytest.mark.parametrize("band", ["x", "s"])
def test_the_fitted_axis_orientation(fomalont_runs, band):
    """The simulated survey's own axis orientation, from its fitted D2, C3, D3, C2, is the
    memo's 0'.8 north and 0'.5 east within 0'.2 (TPOINT sigmas of those terms ~0.08'; seed
    3: X 0.73'/0.46', S 0.77'/0.51')."""
    _, fit, _ = _fits(fomalont_runs[band])
    v = {k: e["value_arcsec"] / 60.0 for k, e in fit["terms"].items()}
    assert (v["W2"] + v["W8"]) / 2.0 == pytest.approx(0.8, abs=0.2)
    assert (v["W3"] - v["W7"]) / 2.0 == pytest.approx(0.5, abs=0.2)


def _trend(el: np.ndarray, eff: np.ndarray) -> tuple[float, float]:
    """Least-squares slope of efficiency against elevation, relative to the mean (per
    degree), and its standard error from the table's own scatter about the line."""
    a = np.vstack([np.ones_like(el), el]).T
    coef, *_ = np.linalg.lstsq(a, eff, rcond=None)
    r = eff - a @ coef
    cov = (r @ r) / (el.size - 2) * np.linalg.inv(a.T @ a)
    return coef[1] / eff.mean(), math.sqrt(cov[1, 1]) / eff.mean()


def test_the_memos_efficiency_table_against_our_gain_curve():
    """Memo, section II: "no systematic changes of efficiency with elevation"; the 1990
    report (section V, our gain curve) has 95% at 20 deg and 90% at 10 deg. Over the memo's
    elevations (13-65 deg) that curve rises by 0.13-0.14% per degree. At S-band the table's
    trend, +0.10 +- 0.19 %/deg, is consistent with both none and the curve; at X-band it
    falls, -0.35 +- 0.12 %/deg: no loss at low elevation in 1973 (the 13 deg point is the
    highest), 4 sigma from the 1990 curve. So the 1973 scenarios keep a flat efficiency (the
    memo's statement) and the 1990 one the report's curve; the surface was changed between
    them (memo: "recent changes of the antenna surface panels"; report: readjustments)."""
    curve = np.array(GHIGO1990_GAIN_CURVE)
    for band, column, mean in (("S", 3, 38.6), ("X", 4, 37.6)):
        rows = [r for r in FOMALONT1973_EFFICIENCY if r[column] is not None]
        el = np.array([r[1] for r in rows])
        eff = np.array([r[column] for r in rows], dtype=float)
        assert eff.mean() == pytest.approx(mean, abs=0.1)  # the memo's <eta> (37.67: 37.6)
        slope, se = _trend(el, eff)
        expected = np.polyfit(el, np.interp(el, curve[:, 0], curve[:, 1]), 1)[0]
        assert 0.0012 < expected < 0.0015
        if band == "S":
            assert abs(slope) < 2 * se and abs(slope - expected) < 2 * se
        else:
            assert slope < -2 * se and (expected - slope) > 3.5 * se


def test_recordings_record_the_feed_angles(fomalont_runs):
    from controller.program.recordings import read_recordings

    table = read_recordings(fomalont_runs["x"] / "recordings.ecsv")
    assert table.meta["feed_angles_deg"] == [0.0, 60.0, 120.0, 180.0, 240.0, 300.0]
    angles = np.asarray(table["feed_angle_deg"])
    scans = np.asarray(table["scan"])
    first = np.unique(scans, return_index=True)[1]
    # one angle per scan, cycling through the list
    np.testing.assert_array_equal(angles[first][:12], [0, 60, 120, 180, 240, 300] * 2)
    assert table.meta["refraction"] == "none"  # the model in use carries it (D5)
    assert table.meta["model"]["terms_arcsec"]["W5"] == pytest.approx(66.0)
    # antsim fit reads the feed angles back, and holds D5 as the memo did
    assert cli(["fit", str(fomalont_runs["x"] / "recordings.ecsv"), "--model", "fomalont14",
                "--fixed", "W5=66", "--json"]) == 0


def test_bad_feed_form_is_one_line(tmp_path, capsys):
    text = SCENARIOS["x"].read_text().replace('form = "fomalont"', 'form = "elliptic"')
    path = tmp_path / "bad.toml"
    path.write_text(text)
    assert cli(["run", str(path), "--out", str(tmp_path / "out"), "--no-report"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "form" in err and "elliptic" in err


def _published_row(text: str, band: str) -> list[str]:
    """The cells of a ``| X | ... |`` row of the seed-3 results table."""
    line = next(line for line in text.splitlines() if line.startswith(f"| {band} | "))
    return [c.strip() for c in line.strip("|").split("|")]


@pytest.mark.parametrize("band", ["x", "s"])
def test_the_published_seed_3_numbers_are_the_runs(fomalont_runs, band):
    """docs/telescopes.md (and docs/results.md's row) quote the runs of this module: each number
    as the run gives it, rounded as printed."""
    _, fit_a, fit_f = _fits(fomalont_runs[band])
    table, _, _ = _recordings(fomalont_runs[band])
    t = {k: v["value_arcsec"] for k, v in fit_a["terms"].items()}
    c6, c7 = math.hypot(t["HSCF"], t["HSSF"]) / 60, math.degrees(math.atan2(t["HSSF"], t["HSCF"]))
    d6 = math.hypot(t["HECF"], t["HESF"]) / 60
    d7 = math.degrees(math.atan2(-t["HESF"], -t["HECF"])) % 360.0
    scans = int((np.asarray(table["polarization"]) == "AVG").sum())
    want = [band.upper(), f"{scans}",
            f'{fit_f["xel_rms_arcsec"]:.1f}"/{fit_f["el_rms_arcsec"]:.1f}"',
            f"{c6:.2f}' at {c7:.0f} deg", f"{d6:.2f}' at {d7:.0f} deg",
            f"{(t['W2'] + t['W8']) / 120:.2f}', {(t['W3'] - t['W7']) / 120:.2f}'"]
    docs = (REPO / "docs" / "telescopes.md").read_text(encoding="utf-8")
    assert _published_row(docs, band.upper()) == want
    results = (REPO / "docs" / "results.md").read_text(encoding="utf-8")
    row = next(line for line in results.splitlines()
               if line.startswith("| `fomalont1973_x.toml`, `fomalont1973_s.toml`"))
    assert f"{scans} scans" in row and want[2] in row and want[3] in row and want[4] in row

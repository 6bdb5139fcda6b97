"""The 1990 run end to end: its tables, the run's fit files, and the closed loop."""

from __future__ import annotations

import html
import json
import math
from pathlib import Path

import numpy as np
import pytest

from antsim.documents import GHIGO1990
from antsim.run.inuse import pointing_in_use
from antsim.run.outputs import run_fits, write_outputs
from antsim.scenario import load_scenario
from antsim.simulate.runner import run_campaign, simulate
from controller.pointing.model import PointingModel
from controller.pointing.modelio import load_model
from controller.pointing.terms import GHIGO_EQUIVALENTS
from controller.pointing.thermal import PROXY_TERMS
from controller.pointing.tpoint import TPointModel, write_mod
from controller.pointing.vocabulary import in_tpoint_terms

ROOT = Path(__file__).resolve().parents[2]
GHIGO = ROOT / "scenarios" / "ghigo1990.toml"
#: the page that quotes this campaign (the README's long sections moved there)
RESULTS_MD = (ROOT / "docs" / "results.md").read_text(encoding="utf-8")


@pytest.fixture(scope="module")
def ghigo():
    return load_scenario(GHIGO)


@pytest.fixture(scope="module")
def campaign(ghigo):
    """The 1990 campaign at seed 1 and its fits A-F."""
    result = simulate(ghigo, seed=1)
    return result, run_fits(result)


def test_table2_of_the_1990_report_is_reproduced(campaign):
    _, fits = campaign
    a, b, c, d, e, f = (fits[k] for k in "ABCDEF")
    # Ghigo (1990) Table 2, fit A: 23" in cross-elevation, 38" in elevation; the scenario's
    # physics was calibrated to land within 30%, seed 1 is not tuned separately
    assert a.xel_rms_arcsec == pytest.approx(23.0, rel=0.30)
    assert a.el_rms_arcsec == pytest.approx(38.0, rel=0.30)
    # the report's orderings: night elevation rms below day, XL worse than XR, the
    # unfiltered fit F no better than A
    assert e.el_rms_arcsec < d.el_rms_arcsec
    assert c.sky_rms_arcsec > b.sky_rms_arcsec
    assert f.sky_rms_arcsec >= a.sky_rms_arcsec
    assert f.n_used > a.n_used
    # the fitted model is the one the report fits, and the scan count is the run's
    assert a.names == tuple(f"W{i}" for i in range(1, 11))
    assert 250 <= a.n_input <= 350


def test_table3_of_the_1990_report_is_reproduced(ghigo, campaign):
    """Ghigo (1990) Table 3 on the report's own functions (section II). The injected truth
    is Table 3's values, and fit A's TPOINT sigmas (the report's kind of standard error) are
    the report's within 25% term by term: the same ten functions, a similar spread of ~280
    scans on the sky and a similar rms give the same formal errors (measured at seed 1:
    0.80-0.97 times the report's, as docs/results.md says; W6, W9, W10, the terms that cannot
    reliably be distinguished, 0.90, 0.87, 0.90).

    With the Sun on the antenna (report section IV; since the thermal recalibration the
    heating makes the day's excess) "fit A within 3 sigma of the truth" is not the physics: fit A
    fits the day and the night mixed with no thermal term, so every campaign shares the
    heating's shift of W1, +33" against a TPOINT sigma of ~9.5" (within 3 sigma in 30% of
    200 seeds, docs/results/recovery.txt). Seed 1's W1 is 3.6 sigma off and its W3 3.1. Fit
    A's day-minus-night warning is no guarantee either: it compares fits D and E, whose W1
    is four times less certain, and fires for W1 in 53% of heated seeds, not at seed 1
    (+42" +- 20", 2.1 sigma). What the physics guarantees is that the shift is the heating's:
    fit T, fit A plus the thermal proxies the data support (the Sun, no sensors in 1990),
    recovers every W within 3 of its TPOINT sigma (100% of the 200 seeds of recovery.txt, so
    a fixed seed is a fair test), and every W of fit A beyond 3 sigma is one that fit T moves
    towards the truth; W1's shift is positive (+33" +- 9" over 200 seeds). This fails if the
    proxies are lost or mis-signed, if fit A is off for a reason other than the heating, or
    if the heating's sign or size changes."""
    _, fits = campaign
    a, t = fits["A"], fits["T"]
    truth = ghigo.truth_model.as_dict()
    for name, (value_arcmin, se_arcmin) in GHIGO1990.terms.items():
        j, k = a.names.index(name), t.names.index(name)
        assert truth[name] == pytest.approx(60.0 * value_arcmin)
        assert a.sigma_arcsec[j] / 60.0 == pytest.approx(se_arcmin, rel=0.25), name
        off_a = a.values_arcsec[j] - truth[name]
        off_t = t.values_arcsec[k] - truth[name]
        assert abs(off_t) < 3.0 * t.sigma_arcsec[k], name
        if abs(off_a) >= 3.0 * a.sigma_arcsec[j]:
            assert abs(off_t) < abs(off_a), name
    added = set(t.names) - set(a.names)
    assert added and added <= set(PROXY_TERMS), t.names
    assert a.values_arcsec[a.names.index("W1")] - truth["W1"] > 0.0
    ratio = [a.sigma_arcsec[a.names.index(n)] / 60.0 / se for n, (_, se) in
             GHIGO1990.terms.items()]
    assert f"{min(ratio):.2f}-{max(ratio):.2f} of them at seed 1" in " ".join(RESULTS_MD.split())


def test_the_readme_quotes_table2_of_seed_1(campaign):
    """docs/results.md's Table 2 rows are this campaign's fits, as fit.txt prints them."""
    _, fits = campaign
    labels = {"A": "XR and XL averaged, filtered", "B": "XR", "C": "XL", "D": "day",
              "E": "night", "F": "unfiltered"}
    for name, label in labels.items():
        fit = fits[name]
        x, e = GHIGO1990.table2[name]
        row = (f"| {name} | {label} | {fit.n_used} | {fit.xel_rms_arcsec:.1f} | "
               f"{fit.el_rms_arcsec:.1f} | {GHIGO1990.points[name]}, {x:.0f}, {e:.0f} |")
        assert row in RESULTS_MD.splitlines(), row


def test_table1_points_per_source(ghigo, campaign):
    """Ghigo (1990) Table 1, points per source in fit A. The spread scheduler visits every
    source about equally often per hour it is up (2.6-2.9 scans per hour at seed 1, within
    20% of their mean here); six of the eight counts are then within 30% of the report's. The
    1990 observers visited 3C84 (1.5 per visible hour) and Orion A (2.0) least and Cygnus A
    (3.7) most, for reasons the report does not give: our 3C84 and Orion A counts are the two
    more than 30% above it (docs/facts.md). Table 1 itself adds up to 282, its fit A to 285."""
    from antsim.run.sources import points_per_source, visible_hours

    result, fits = campaign
    points = points_per_source(result.rows, fits["A"])
    report = GHIGO1990.source_points
    assert sum(report.values()) == 282 and GHIGO1990.points["A"] == 285
    hours = visible_hours(ghigo)
    ours = {n: points[n] / hours[n] for n in report}
    mean = sum(ours.values()) / len(ours)
    assert all(abs(r / mean - 1.0) < 0.2 for r in ours.values()), ours
    ratio = {n: points[n] / report[n] for n in report}
    outside = sorted(n for n, r in ratio.items() if abs(r - 1.0) > 0.30)
    assert outside == ["3C84", "Orion A"], ratio
    by_report_rate = sorted(report, key=lambda n: report[n] / hours[n])
    assert sorted(by_report_rate[:2]) == outside


def test_fig2a_azimuth_error_follows_elevation(campaign):
    """Ghigo (1990) section IV: "a large azimuth encoder offset (W6) of 12 arcmin. This is
    probably why Figure 2a shows a strong dependence of azimuth error with elevation". The
    total cross-elevation error our Fig. 2a draws falls with elevation as W6 cos E does:
    correlated with cos E (r > 0.9, 0.97 at seed 1; the other azimuth terms and the scatter
    keep it below 1), and its least-squares slope against cos E is within 40% of W6 (15.5' at
    seed 1: W9 sin E and W10 are not orthogonal to cos E over 10-85 deg)."""
    from antsim.figures.run import _Observations

    result, _ = campaign
    obs = _Observations.from_rows(result.rows, "AVG")
    keep = obs.good & np.isfinite(obs.xel_arcsec)
    cos_e = np.cos(np.radians(obs.el_deg[keep]))
    xel = obs.xel_arcsec[keep]
    assert np.corrcoef(cos_e, xel)[0, 1] > 0.9
    slope = np.polyfit(cos_e, xel, 1)[0]
    assert slope == pytest.approx(12.24 * 60.0, rel=0.4)


def test_run_writes_fit_files_that_round_trip(ghigo, tmp_path):
    result = run_campaign(ghigo, tmp_path, show_progress=False)
    write_outputs(result)
    fit = json.loads((tmp_path / "fit.json").read_text())
    variants = json.loads((tmp_path / "fit_variants.json").read_text())
    # fits A-F of the report, and T: A with the thermal terms the data support (the 1990
    # antenna had no structure sensors: proxies for them)
    assert set(variants) == set("ABCDEFT")
    assert variants["A"] == fit
    assert list(variants["T"]["terms"])[:10] == [f"W{i}" for i in range(1, 11)]
    assert variants["T"]["notes"][0].startswith("thermal terms tested: TESUN")
    for key in ("n_input", "n_used", "n_rejected", "model", "terms", "sky_rms_arcsec",
                "xel_rms_arcsec", "el_rms_arcsec", "popn_sd_arcsec", "condition_number",
                "correlations", "unconstrained"):
        assert key in fit
    assert fit["model"] == "ghigo10" and list(fit["terms"]) == [f"W{i}" for i in range(1, 11)]
    text = (tmp_path / "fit.txt").read_text()
    assert "Table 2" in text and "Table 3" in text and "Table 1" in text
    # one unit in every table, stated, with the sign of the coefficients
    assert "Units: arcsec in every table. Sign of the coefficients: W1..W10 (Ghigo 1990, " \
        "NRAO EDIR 288, section II): indicated minus true" in text
    # the report's numbers beside ours: Table 3's W6 row ends with 12.24' = 734.4" and its
    # s.e. 0.55' = 33.0"; before them fit A's TPOINT sigma and honest sigma
    w6 = next(line for line in text.splitlines() if line.startswith("W6 ")).split()
    assert w6[-2:] == ["+734.4", "33.0"]
    terms = fit["terms"]["W6"]
    assert w6[1] == f"{terms['value_arcsec']:+.2f}"
    assert w6[-4:-2] == [f"{terms['sigma_arcsec']:.2f}", f"{terms['sigma_honest_arcsec']:.2f}"]
    assert terms["sigma_honest_arcsec"] != pytest.approx(terms["sigma_arcsec"], rel=0.05)
    assert next(line for line in text.splitlines() if line.startswith("Cassiopeia A")
                ).split()[-1] == "64"
    for name in "ABCDEF":
        assert f"\n{name} " in text
    # model.dat is fit A as a TPOINT .mod file in TPOINT's names and signs (W1 = -IE, ...),
    # which the controller loads back: the same corrections everywhere
    model = load_model(tmp_path / "model.dat")
    assert model.names == tuple(GHIGO_EQUIVALENTS[f"W{i}"][0] for i in range(1, 11))
    for name, entry in fit["terms"].items():
        twin, sign = GHIGO_EQUIVALENTS[name]
        # the .mod format prints 4 decimals of an arcsec
        assert model[twin] == pytest.approx(sign * entry["value_arcsec"], abs=6e-5)
    assert model.fit_sky_rms_arcsec == pytest.approx(fit["sky_rms_arcsec"], abs=5e-4)
    az, el = (a.ravel() for a in np.meshgrid(np.radians(np.arange(0.0, 360.0, 15.0)),
                                             np.radians(np.arange(10.0, 90.0, 5.0))))
    fitted = PointingModel(list(fit["terms"]),
                           [t["value_arcsec"] for t in fit["terms"].values()])
    sky = np.array([np.cos(el), np.ones_like(el)]) * 206264.8  # (dA cos E, dE) in arcsec
    # each value is rounded to 5e-5"; on the sky the ten functions are at most 1, except
    # W5's cot E (5.7 at 10 deg): at most 5e-5" x (9 + 5.7) = 7e-4"
    np.testing.assert_allclose(sky * model.offset_rad(az, el), sky * fitted.offset_rad(az, el),
                               rtol=0, atol=1e-3)
    assert "W6 = IA (azimuth encoder offset" in (tmp_path / "model.dat").read_text()


def sky_rms_of_pointing(rows) -> float:
    """rms of the measured corrections (the pointing error left by the model in use)."""
    good = [r for r in rows if r["polarization"] == "AVG" and r["good"]]
    xel = np.array([r["xel_arcmin"] + r["applied_xel_arcmin"] for r in good]) * 60.0
    el = np.array([r["el_arcmin"] + r["applied_el_arcmin"] for r in good]) * 60.0
    return math.sqrt(float(np.mean(xel ** 2 + el ** 2)))


def test_closed_loop_second_campaign_points_well(ghigo, campaign, tmp_path):
    """The model fitted from one campaign, used in the next through its model.dat, leaves
    pointing errors close to the first fit's residuals (at most 1.3 times); the
    second run says so in one line, in fit.txt and in its report."""
    _, fits = campaign
    first = fits["A"]
    path = tmp_path / "model.dat"
    write_mod(in_tpoint_terms(TPointModel.from_fit(first, caption="first: fit A")), path)
    second = run_campaign(ghigo, tmp_path / "second", seed=2, model=load_model(path),
                          show_progress=False)
    ratio = sky_rms_of_pointing(second.rows) / first.sky_rms_arcsec
    assert ratio <= 1.3, ratio
    assert second.program.searches == 0
    in_use = pointing_in_use(second.rows, second.model)
    assert in_use.ratio == pytest.approx(ratio, rel=1e-4)  # model.dat's rms has 3 decimals
    line = (f"pointing with the model in use (first: fit A): Sky RMS "
            f"{sky_rms_of_pointing(second.rows):.1f}\"")
    assert in_use.line().startswith(line)
    assert in_use.line().endswith(f", {ratio:.2f} times the {first.sky_rms_arcsec:.1f}\" of "
                                  f"the fit it came from ({first.n_used} points)")
    summary = write_outputs(second, report=True)
    assert in_use.line() in summary.splitlines()
    assert in_use.line()[1:] + "." in (tmp_path / "second" / "fit.txt").read_text()
    assert html.escape(in_use.line()[1:]) in (tmp_path / "second" / "report.html").read_text()


def test_cold_start_converges_within_three_campaigns(ghigo):
    """No model at all: the 12.24' azimuth encoder offset (W6) is W6 cos E on the sky, beyond
    the 11' beam low in the sky, so scans there miss; the controller searches, adopts a
    correction (an azimuth offset), and the fitted model closes the loop."""
    model = PointingModel()
    history = []
    previous_fit_rms = float("nan")  # no fit before the first campaign
    for campaign_number, seed in enumerate((11, 12, 13), start=1):
        result = simulate(ghigo, seed=seed, model=model)
        fit = run_fits(result)["A"]
        pointing = sky_rms_of_pointing(result.rows)
        history.append((campaign_number, result.program.searches, pointing,
                        fit.sky_rms_arcsec))
        if campaign_number == 1:
            # it must have found its sources anyway: a full campaign over all 8 sources
            assert result.program.searches > 0
            assert {r["source"] for r in result.rows} == {s.name for s in ghigo.sources}
        if pointing <= 1.3 * previous_fit_rms:
            break
        previous_fit_rms = fit.sky_rms_arcsec
        model = fit.model
    else:
        pytest.fail(f"no convergence in 3 campaigns: {history}")
    assert campaign_number <= 3

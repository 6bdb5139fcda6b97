"""Crane (1981, NRAO Engineering Memo 147): the memo's figures from the three simulated runs.

The runs are the scenarios at seed 3 (2-3 s each); benchmarks/crane1981.py prints the same
comparisons beside the memo's numbers. Figures quoted in comments were measured at seed 3.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from antsim.cli import main as cli
from antsim.scenario import load_scenario
from antsim.studies.crane1981 import (
    BANDS,
    TABLE4,
    TABLE5,
    channel_gain,
    difference_chi2,
    good_rows,
    rounding_ratio,
    search_declination_terms,
    sigma_pattern,
    table4_datasets,
    worst_factor,
)
from controller.pointing.crane import CANDIDATES, CRANE_NAMES
from controller.program.recordings import read_recordings

REPO = Path(__file__).resolve().parents[2]


def _scenario(band: int) -> Path:
    return REPO / "scenarios" / f"crane1981_140ft_{band}.toml"


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> dict:
    out = {}
    for band in BANDS:
        d = tmp_path_factory.mktemp(f"crane{band}")
        assert cli(["run", str(_scenario(band)), "--out", str(d), "--no-report"]) == 0
        table = read_recordings(d / "recordings.ecsv")
        out[band] = {"fit": json.loads((d / "fit.json").read_text()),
                     "variants": json.loads((d / "fit_variants.json").read_text()),
                     "cols": {c: np.asarray(table[c]) for c in table.colnames}}
    return out


def _night_deg(band: int) -> float:
    return load_scenario(_scenario(band)).controller.night_sun_max_deg


def test_points_and_rms_per_point_are_table4s(runs):
    # within 20%, all data and night (the Sun below the horizon): measured
    # 396/400, 332/353, 174/182 points; RA rms 18.3/18.2, 20.9/20.7, 25.1/22.4"; Dec rms
    # 11.8/11.9, 11.0/11.0, 10.6/10.8"; night 164/172 and 149/139 points, RA 18.6/18.2 and
    # 17.4/17.4", Dec 9.1/9.3 and 8.8/9.0"
    for band, r in runs.items():
        for which in TABLE4[band]:
            memo = TABLE4[band][which]
            fit = r["fit"] if which == "all" else r["variants"]["E"]
            assert fit["n_used"] == pytest.approx(memo["n"], rel=0.20), (band, which)
            assert fit["xel_rms_arcsec"] == pytest.approx(memo["rms"][0], rel=0.20), band
            assert fit["el_rms_arcsec"] == pytest.approx(memo["rms"][1], rel=0.20), band
            # RA about twice Dec (summary item 3)
            assert 1.4 < fit["xel_rms_arcsec"] / fit["el_rms_arcsec"] < 2.6
    # the night: the Sun below the horizon, not -12 deg, whose 3245 MHz count (126) misses
    # the memo's 172 by 27%
    assert _night_deg(3245) == 0.0
    twilight = int(np.sum(good_rows(runs[3245]["cols"], -12.0)))
    assert twilight < 0.8 * TABLE4[3245]["night"]["n"]


def test_night_is_quieter_by_day_scatter(runs):
    # Table 4: the night rms is the smaller (Dec 9.3 against 11.9", 9.0 against 11.0"); the
    # simulated by-day scatter (tracking_jitter's day factors) gives the same order
    for band in (3245, 4990):
        night, day = runs[band]["variants"]["E"], runs[band]["variants"]["D"]
        assert night["el_rms_arcsec"] < 0.8 * day["el_rms_arcsec"], band


def test_standard_error_pattern_of_the_chosen_definitions(runs):
    # the chosen C1..C11 give Table 4's standard errors (outside the rounding of its last
    # digit) within 30% for every term of the all-data fits but C6, which comes out 1.43-1.61
    # times the memo's (C11 0.75-0.76); at night C9-C11 come out smaller (0.55-0.75) and C6
    # 1.16-1.57. The textbook reading is off by up to 12x (C8 0.08-0.12 of the memo's)
    lat = load_scenario(_scenario(3245)).site.latitude_deg
    data = table4_datasets(runs, {b: _night_deg(b) for b in BANDS})
    for d in data:
        chosen = rounding_ratio(sigma_pattern(d.ha_rad, d.dec_rad, d.xel_rms_arcsec,
                                              d.dec_rms_arcsec, lat), d.memo_sigma)
        c6 = chosen[CRANE_NAMES.index("C6")]
        if d.label.endswith("all"):
            others = np.delete(chosen, CRANE_NAMES.index("C6"))
            assert np.all((others >= 0.7) & (others <= 1.3)), (d.label, np.round(chosen, 2))
            assert 1.3 < c6 < 1.8, d.label
        textbook = rounding_ratio(sigma_pattern(d.ha_rad, d.dec_rad, d.xel_rms_arcsec,
                                                d.dec_rms_arcsec, lat, "textbook"), d.memo_sigma)
        assert worst_factor(textbook) > 5.0
    # no other five of the declination functions does better on all five columns (worst
    # factor 1.82 for the chosen; the next 1.94)
    best = search_declination_terms(data, lat, top=2)
    assert best[0][1] == CANDIDATES["crane1981"] and best[1][0] > best[0][0]


def test_no_day_night_difference(runs):
    # Crane: "no significant difference between the two fits" (sections II, III; summary 2).
    # Memo's own night-minus-all chi-square (11 dof, night errors): 7.3 and 19.6 (P 0.77,
    # 0.05); ours 4.8 and 1.4: no thermal effect is simulated, the nights agree
    for band in (3245, 4990):
        r = runs[band]
        all_fit = [(r["fit"]["terms"][n]["value_arcsec"], r["fit"]["terms"][n]["sigma_arcsec"])
                   for n in CRANE_NAMES]
        night = r["variants"]["E"]["terms"]
        night_fit = [(night[n]["value_arcsec"], night[n]["sigma_arcsec"]) for n in CRANE_NAMES]
        assert difference_chi2(all_fit, night_fit)[2] > 0.05, band
    memo = difference_chi2(TABLE4[3245]["all"]["c"], TABLE4[3245]["night"]["c"])
    assert memo[0] == pytest.approx(7.3, abs=0.05)


def test_subreflector_offset_moves_c1_and_c6_at_4990(runs):
    # section III: the offset applied with the wrong sign moved C1 and C6 (5.83' and -5.16'
    # against ~2' and -1.7'); the fitted shift is many sigma, the other bands agree
    fits = {b: r["fit"]["terms"] for b, r in runs.items()}
    for name, sign in (("C1", 1.0), ("C6", -1.0)):
        shift = (fits[4990][name]["value_arcsec"] - fits[3245][name]["value_arcsec"]) * sign
        sigma = np.hypot(fits[4990][name]["sigma_arcsec"], fits[3245][name]["sigma_arcsec"])
        assert shift > 5.0 * sigma and 150.0 < shift < 290.0, name  # 3.7' and 3.5' injected
        other = abs(fits[10500][name]["value_arcsec"] - fits[3245][name]["value_arcsec"])
        assert other < 60.0  # 10500 "nearly the same as measured at 3245 MHz"


def test_no_pointing_above_72_deg(runs):
    # section II: "No data were available above 72 deg" (the control program); 8 of the
    # tables' sources lie above it and are never pointed at
    for band, r in runs.items():
        assert np.max(r["cols"]["dec_deg"].astype(float)) <= 72.0
        above = [s.name for s in load_scenario(_scenario(band)).sources if s.dec_deg > 72.0]
        assert above and not set(above) & set(r["cols"]["source"].astype(str))


def test_gain_per_feed_and_uncorrected_10500_are_table5s(runs):
    # 3245 MHz: the computer's F1 carries feed 2 and F2 feed 1 (swapped cables, section II):
    # each channel's constant within 3 of its error (measured 0.2610 and 0.2464 K/Jy)
    r = runs[3245]
    flux = {s.name: s.flux_jy for s in load_scenario(_scenario(3245)).sources}
    for key, channel in (("3245 feed 1", "F2"), ("3245 feed 2", "F1")):
        fit = channel_gain(r["cols"], channel, flux, 8.93)
        value, _ = TABLE5[key]["y"][0]
        assert abs(fit.values[0] - value) < 3.0 * fit.sigma[0], key
        assert np.all(np.abs(fit.values[1:]) < 3.0 * fit.sigma[1:] + 1e-3)  # constants
    # 10500 MHz without the tipping correction: Table 5's "Uncorrected" curve within 3 of
    # the two errors combined (measured pulls 1.2-1.9: the memo's curve is the atmosphere
    # folded into a fit of one realisation; ours another)
    r = runs[10500]
    flux = {s.name: s.flux_jy for s in load_scenario(_scenario(10500)).sources}
    fit = channel_gain(r["cols"], "AVG", flux, 2.76, 0.0)
    for k, (value, sigma) in enumerate(TABLE5["10500 uncorrected"]["y"]):
        assert abs(fit.values[k] - value) < 3.0 * np.hypot(fit.sigma[k], sigma), k
    # and it lies below the corrected one at the zenith (the atmosphere's 2.3%)
    corrected = fit.values[0] + fit.values[1]
    assert corrected < TABLE5["10500 corrected"]["y"][0][0] + TABLE5["10500 corrected"]["y"][1][0]


def test_crane_benchmark_prints_the_memo_beside_ours(capsys):
    import runpy

    module = runpy.run_path(str(REPO / "benchmarks" / "crane1981.py"))
    assert module["main"](["--no-coverage"]) == 0
    out = capsys.readouterr().out
    for text in ("Points and rms per point", "Standard errors against Table 4's",
                 "Day and night", "subreflector", "above +72 deg", "tipping opacity"):
        assert text in out

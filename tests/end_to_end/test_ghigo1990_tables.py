"""The 1990 report's Tables 1-3 against the simulated campaign, as means over seeds 1-4: the
suite's reduced version of ``python benchmarks/ghigo1990_tables.py`` (seeds 1-20; its
output is ``docs/results/ghigo1990_tables.txt``).

Tolerances: the criterion (25% of Table 2, 20% for the day and night counts, 30% for Table 1)
widened by three standard errors of a 4-seed mean, from the seed-to-seed standard deviations
the benchmark measured over seeds 1-20 (:data:`SPREAD`). They are small: the heating of a
clear February day and the antenna's repeatable irregularities are the same in every seed,
only the noise differs. What the physics does not reach (fit C; docs/physics.md) is
not held to the report: its own physics is tested instead.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from antsim.documents import GHIGO1990
from antsim.run.outputs import run_fits
from antsim.run.sources import points_per_source, visible_hours
from antsim.scenario import load_scenario
from antsim.simulate.runner import simulate
from antsim.studies.ghigo1990 import (
    COUNTS_TOLERANCE,
    TABLE1_TOLERANCE,
    TABLE2_TOLERANCE,
    campaign_statistics,
    w5_of_atmosphere,
)
from tests.conftest import REPO

SEEDS = (1, 2, 3, 4)
#: seed-to-seed standard deviations over seeds 1-20 (benchmarks/ghigo1990_tables.py): per
#: fit (xel rms, el rms, points)
SPREAD = {"A": (0.2, 0.5, 0.9), "B": (0.2, 0.5, 0.8), "C": (0.2, 0.5, 0.9),
          "D": (0.9, 1.3, 1.3), "E": (1.0, 0.5, 1.3), "F": (0.2, 0.2, 0.0)}


@pytest.fixture(scope="module")
def scenario():
    return load_scenario(REPO / "scenarios" / "ghigo1990.toml")


@pytest.fixture(scope="module")
def runs(scenario):
    out = []
    for seed in SEEDS:
        result = simulate(scenario, seed=seed)
        fits = run_fits(result)
        out.append(campaign_statistics(result, fits, points_per_source(result.rows,
                                                                       fits["A"])))
    return out


def _margin(sd: float) -> float:
    """Three standard errors of a mean over :data:`SEEDS`."""
    return 3.0 * sd / math.sqrt(len(SEEDS))


@pytest.mark.parametrize("fit", ["A", "B", "D", "E", "F"])
def test_table2_fits_within_the_criterion(runs, fit):
    """Fits A, B (XR), D (day), E (night) and F (unfiltered): both rms within 25% of Table 2,
    the points of A, B and F within 25%, the day's and night's counts within 20% (the report
    does not say where its day ends: docs/physics.md, Day and night)."""
    got = np.array([r["rms"][fit] for r in runs]).mean(axis=0)
    x, e = GHIGO1990.table2[fit]
    n = GHIGO1990.points[fit]
    for j, (ref, tol) in enumerate(((x, TABLE2_TOLERANCE), (e, TABLE2_TOLERANCE),
                                    (n, COUNTS_TOLERANCE if fit in "DE" else TABLE2_TOLERANCE))):
        assert abs(got[j] - ref) <= tol * ref + _margin(SPREAD[fit][j]), (fit, j, got[j], ref)


def test_the_day_is_worse_than_the_night_by_the_heating(runs):
    """Section IV: "daytime differential thermal effects are a major cause of elevation
    pointing errors": fit D's elevation rms exceeds fit E's in every seed, by more in
    elevation than in cross-elevation (the report: 40"/26" against 24"/18")."""
    for r in runs:
        (dx, de, _), (ex, ee, _) = r["rms"]["D"], r["rms"]["E"]
        assert de > ee
        assert de * de - ee * ee > dx * dx - ex * ex


def test_xl_differs_from_xr_by_its_system_temperature(runs):
    """XL's Tsys is 15% above XR's (section IV), their gain stability alike: fit C's sky rms
    over fit B's cannot exceed 1.15 (what it would be if the receiver's noise were all of
    each scan's error) and is near 1 here (measured 1.000 over seeds 1-20). The report's
    1.22 is a gap (docs/physics.md, Receiver), not held here."""
    ratio = np.mean([np.hypot(*r["rms"]["C"][:2]) / np.hypot(*r["rms"]["B"][:2]) for r in runs])
    assert 0.97 < ratio < 1.15


def test_table1_points_differ_where_the_observers_chose(runs, scenario):
    """Table 1's points per source: the scheduler visits every source about equally often
    per hour it is up (each within 20% of their mean rate), so the sources more than 30% off
    the report are among those the 1990 observers visited least or most per visible hour
    (the two at either end of the report's rates; 3C84 and Orion A, least: docs/facts.md),
    and the others, at least five of the eight, are within 30%."""
    hours = visible_hours(scenario)
    report = GHIGO1990.source_points
    ours = {n: np.mean([r["points"].get(n, 0) for r in runs]) for n in report}
    rate = {n: ours[n] / hours[n] for n in report}
    mean_rate = np.mean(list(rate.values()))
    assert all(abs(v / mean_rate - 1.0) < 0.2 for v in rate.values()), rate
    by_report_rate = sorted(report, key=lambda n: report[n] / hours[n])
    extremes = set(by_report_rate[:2]) | set(by_report_rate[-2:])
    outside = [n for n in report if abs(ours[n] / report[n] - 1.0) > TABLE1_TOLERANCE]
    assert len(outside) <= 3
    assert set(outside) <= extremes, (outside, by_report_rate)


def test_table3_recovered_on_the_reports_functions(runs, scenario):
    """Fit A's mean over the seeds recovers the mount's W's plus what the fit makes of the
    refraction, of the repeatable irregularities and of the Sun's heating (the campaign's
    recoverable truth; the feed legs and the yoke at their equilibrium) within 3 TPOINT
    sigma: the noise's share of the mean is 1.5 sigma at most (three standard errors of a
    4-seed mean), the rest is the equilibrium approximation's, the same in every seed
    (measured at most 1.8 sigma, W2, over seeds 1-4). The heating's share tilts the azimuth
    axis north (W2, W8 positive: the pedestal bends away from its sunlit south face). The
    TPOINT sigmas are the report's standard errors within 25% term by term."""
    truth = scenario.truth_model.as_dict()
    names = runs[0]["names"]
    values = np.array([r["values"] for r in runs])
    sigma = np.array([r["sigma"] for r in runs])
    expected = np.array([[truth[n] + r["refraction"][n] + r["pattern"][n] + r["heating"][n]
                          for n in names] for r in runs])
    pull = (values - expected).mean(axis=0) / sigma.mean(axis=0)
    for j, n in enumerate(names):
        assert sigma[:, j].mean() / 60.0 == pytest.approx(GHIGO1990.terms[n][1], rel=0.25), n
        assert abs(pull[j]) < 3.0, (n, pull[j])
    for n in ("W2", "W8"):
        assert all(r["heating"][n] > 0.0 for r in runs), n


def test_w5_is_the_atmospheres_refraction(runs, scenario):
    """The control program did not correct refraction, so W5 is the atmosphere's. What the
    study makes of the world's refraction (ERFA's, inverted as eraAtioq does) equals, to 1%,
    an independent least-squares fit of the report's elevation terms (1, cos A, sin A, cos E,
    cot E) to ERFA's A cot E + B cot^3 E with refco's constants for each scan's weather
    (the two differ by the inversion, ~0.1" at 10 deg); it is ~5% below A itself (the
    tan^3 z term and W1, W4 share the rest) and rises with humidity (water vapour refracts at
    radio wavelengths). The report's 0.80' +- 0.05' lies below it for every humidity of
    20-95%: a gap (docs/physics.md, Refraction)."""
    import erfa

    from controller.units import ARCSEC_PER_RAD

    result = simulate(scenario, seed=SEEDS[0])
    good = [r for r in result.rows if r["polarization"] == "AVG" and r["good"]]
    az = np.radians([r["az_deg"] for r in good])
    el = np.radians([r["el_deg"] for r in good])
    constants = np.array([erfa.refco(r["pressure_hpa"], r["air_temp_c"], 0.5,
                                     299792.458 / 8.4) for r in good])
    cot = 1.0 / np.tan(el)
    target = (constants[:, 0] * cot + constants[:, 1] * cot ** 3) * ARCSEC_PER_RAD / 60.0
    design = np.column_stack([np.ones_like(el), np.cos(az), np.sin(az), np.cos(el), cot])
    independent = np.linalg.lstsq(design, target, rcond=None)[0][4]
    w5 = w5_of_atmosphere(result.rows, 8.4)
    assert w5 == pytest.approx(independent, rel=0.01)
    assert 0.9 < w5 / (np.mean(constants[:, 0]) * ARCSEC_PER_RAD / 60.0) < 1.0
    dry, wet = (w5_of_atmosphere(result.rows, 8.4, h) for h in (0.2, 0.95))
    assert dry < w5 < wet
    assert dry > GHIGO1990.terms["W5"][0] + GHIGO1990.terms["W5"][1]
    mean = np.mean([r["refraction"]["W5"] for r in runs]) / 60.0
    assert mean == pytest.approx(w5, rel=0.01)  # the seeds' schedules are alike


def test_the_lowest_snr_is_the_weakest_sources_low_in_the_sky(runs, scenario):
    """Section VI's S/N (amplitude over the samples' standard deviation) is lowest where a
    real 45-ft's is: on the weakest sources (3C273, Virgo A, 3C84: 40-50 Jy) low in the sky
    (the efficiency and the atmosphere's transmission fall there): every one of the
    lowest 1% of scans is one of them below 20 deg."""
    flux = {s.name: s.flux_jy for s in scenario.sources}
    weakest = sorted(flux, key=flux.get)[:3]
    snr = sorted(s for r in runs for s in r["snr"])
    lowest = snr[:max(1, len(snr) // 100)]
    assert all(source in weakest and el < 20.0 for _, source, el in lowest), lowest[:5]

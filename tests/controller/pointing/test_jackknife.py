"""The honest sigma (controller.pointing.jackknife, through fit_model): the exact
leave-one-block-out jackknife, its coverage of hour-correlated errors, the robust fit's replayed
rejection, the block grids, and the degrees of freedom of the t-scaled sigma.

Seeds are fixed; every tolerance says why it is what it is.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from controller.pointing.data import PointingData
from controller.pointing.fitting import fit_model
from controller.pointing.jackknife import JackknifeResult

HONEST_TERMS = ["IA", "IE", "CA", "NPAE", "AN", "AW", "TF", "TX"]


def _hourly_wander_campaign(rng, n=280, hours=24, wander=8.0, white=5.0) -> PointingData:
    """Zero true model; errors = an offset shared within each clock hour (slow wander, as
    thermal drifts and wind give) plus white noise, elevation noisier than cross-elevation."""
    t = np.sort(rng.uniform(0.0, hours * 3600.0, n))
    hour = np.floor(t / 3600.0).astype(int)
    az = rng.uniform(0.0, 2 * np.pi, n)
    el = np.radians(rng.uniform(10.0, 85.0, n))
    xel = rng.normal(0, wander, hours)[hour] + rng.normal(0, white, n)
    eln = rng.normal(0, wander, hours)[hour] + rng.normal(0, 1.5 * white, n)
    return PointingData(az, el, xel, eln, t_s=t)


def _leave_one_block_out_variance(data: PointingData, fit, block: np.ndarray) -> np.ndarray:
    """Brute-force CV3 jackknife variance of ``fit``'s (non-robust) coefficients over the
    time blocks labelled ``block``."""
    deltas = []
    for h in np.unique(block):
        keep = block != h
        sub = PointingData(data.az_rad[keep], data.el_rad[keep], data.xel_arcsec[keep],
                           data.el_arcsec[keep], t_s=data.t_s[keep])
        deltas.append(fit_model(sub, HONEST_TERMS, robust=False).values_arcsec
                      - fit.values_arcsec)
    g = len(deltas)
    return (g - 1) / g * np.sum(np.array(deltas) ** 2, axis=0)


def test_honest_sigma_is_the_exact_leave_one_hour_out_jackknife():
    """One block grid: the brute-force jackknife over clock hours. Four grids (the default):
    the mean of the brute-force variances over the hour grids shifted by 0, 15, 30 and 45
    minutes; the shifted grids' own variances differ from the clock hours' by several percent
    here, so the test tells one grid from four."""
    data = _hourly_wander_campaign(np.random.default_rng(3))
    one = fit_model(data, HONEST_TERMS, robust=False, block_phases=1)
    hour = np.floor(data.t_s / 3600.0)
    assert one.honest_clusters == 24 and one.honest_phases == 1
    np.testing.assert_allclose(one.sigma_jackknife_arcsec,
                               np.sqrt(_leave_one_block_out_variance(data, one, hour)),
                               rtol=1e-9)
    four = fit_model(data, HONEST_TERMS, robust=False)
    assert four.honest_phases == 4 and four.honest_clusters == 24
    grids = [_leave_one_block_out_variance(data, four, np.floor((data.t_s - s) / 3600.0))
             for s in (0.0, 900.0, 1800.0, 2700.0)]
    np.testing.assert_allclose(four.sigma_jackknife_arcsec, np.sqrt(np.mean(grids, axis=0)),
                               rtol=1e-9)
    assert np.max(np.abs(four.sigma_jackknife_arcsec / one.sigma_jackknife_arcsec - 1)) > 0.05


def test_honest_sigma_covers_hour_correlated_errors():
    """300 campaigns with errors correlated within each hour: the pulls (fitted - 0)/sigma
    must spread by 1 with the honest sigma. With 300 fits a sample spread has a relative
    standard error of 1/sqrt(600) = 4%, so 0.88..1.12 is a 3-sigma band (measured at this
    seed: 0.93-1.04). TPOINT's Sky-RMS sigma, blind to the axes' different scatter, spreads
    the cross-elevation terms' pulls by ~0.7 (measured 0.65-0.75): it must stay below 0.85,
    which shows the test can tell the two apart."""
    rng = np.random.default_rng(7)
    values, tpoint, honest = [], [], []
    for _ in range(300):
        fit = fit_model(_hourly_wander_campaign(rng), HONEST_TERMS, robust=False)
        values.append(fit.values_arcsec)
        tpoint.append(fit.sigma_arcsec)
        honest.append(fit.sigma_honest_arcsec)
    values, tpoint, honest = map(np.array, (values, tpoint, honest))
    spread = np.std(values / honest, axis=0)
    assert np.all((spread > 0.88) & (spread < 1.12)), dict(zip(HONEST_TERMS, spread, strict=True))
    xel_terms = [HONEST_TERMS.index(t) for t in ("IA", "CA", "NPAE")]
    assert np.all(np.std(values / tpoint, axis=0)[xel_terms] < 0.85)


def test_honest_sigma_without_times_is_the_leave_one_observation_out_jackknife():
    # the Woodbury fast path for one-observation clusters against brute force
    full = _hourly_wander_campaign(np.random.default_rng(5), n=40)
    data = PointingData(full.az_rad, full.el_rad, full.xel_arcsec, full.el_arcsec)
    fit = fit_model(data, HONEST_TERMS, robust=False)
    deltas = []
    for i in range(len(data)):
        keep = np.arange(len(data)) != i
        sub = PointingData(data.az_rad[keep], data.el_rad[keep], data.xel_arcsec[keep],
                           data.el_arcsec[keep])
        deltas.append(fit_model(sub, HONEST_TERMS, robust=False).values_arcsec
                      - fit.values_arcsec)
    deltas = np.array(deltas)
    expected = np.sqrt((len(data) - 1) / len(data) * np.sum(deltas**2, axis=0))
    assert fit.honest_clusters == len(data)
    np.testing.assert_allclose(fit.sigma_jackknife_arcsec, expected, rtol=1e-8)


def _subset(data: PointingData, keep: np.ndarray) -> PointingData:
    return PointingData(data.az_rad[keep], data.el_rad[keep], data.xel_arcsec[keep],
                        data.el_arcsec[keep], t_s=data.t_s[keep])


def test_robust_honest_sigma_replays_the_rejection_in_every_hour_block():
    """A robust fit's jackknife is the linear one on the kept observations, scaled by the
    mean over terms of (variance with the fit's rms rejection replayed without each hour) /
    (linear variance). Brute force with fit_model itself: the LAD stage is switched off by a
    huge lad_factor, so the last stage is all that is replayed. Heavy-tailed errors make
    observations cross the 3-rms threshold from replicate to replicate; the factor must then
    differ from 1 (measured 1.10 here), or the test could not tell a missing replay."""
    rng = np.random.default_rng(21)
    data = _hourly_wander_campaign(rng, wander=2.0)
    heavy = PointingData(data.az_rad, data.el_rad,
                         data.xel_arcsec + 6.0 * rng.standard_t(3, len(data)),
                         data.el_arcsec + 6.0 * rng.standard_t(3, len(data)), t_s=data.t_s)
    fit = fit_model(heavy, HONEST_TERMS, lad_factor=1e6, block_phases=1)
    assert 0 < fit.n_rejected < 20
    hour = np.floor(heavy.t_s / 3600.0)

    def jackknife_var(subset_fit, base, keep_all):
        deltas = [subset_fit(_subset(base, keep_all & (hour != h))) - fit.values_arcsec
                  for h in np.unique(hour[keep_all])]
        g = len(deltas)
        return (g - 1) / g * np.sum(np.array(deltas) ** 2, axis=0)

    replayed = jackknife_var(
        lambda d: fit_model(d, HONEST_TERMS, lad_factor=1e6).values_arcsec,
        heavy, np.ones(len(heavy), dtype=bool))
    linear = jackknife_var(
        lambda d: fit_model(d, HONEST_TERMS, robust=False).values_arcsec, heavy, fit.used)
    factor = np.mean(replayed / linear)
    assert abs(factor - 1.0) > 0.02, factor
    np.testing.assert_allclose(fit.sigma_jackknife_arcsec, np.sqrt(linear * factor), rtol=1e-7)


def test_robust_honest_sigma_on_four_grids_is_the_mean_of_shifted_single_grids():
    """The default (four block grids) equals the mean of the variances of one-grid fits
    whose times are shifted by 0, 1/4, 1/2 and 3/4 of a block, the rejection replayed in
    each grid; the dof are their mean."""
    rng = np.random.default_rng(21)
    data = _hourly_wander_campaign(rng, wander=2.0)
    heavy = PointingData(data.az_rad, data.el_rad,
                         data.xel_arcsec + 6.0 * rng.standard_t(3, len(data)),
                         data.el_arcsec + 6.0 * rng.standard_t(3, len(data)), t_s=data.t_s)
    four = fit_model(heavy, HONEST_TERMS, lad_factor=1e6)
    grids = [fit_model(PointingData(heavy.az_rad, heavy.el_rad, heavy.xel_arcsec,
                                    heavy.el_arcsec, t_s=heavy.t_s - shift),
                       HONEST_TERMS, lad_factor=1e6, block_phases=1)
             for shift in (0.0, 900.0, 1800.0, 2700.0)]
    np.testing.assert_allclose(
        four.sigma_jackknife_arcsec,
        np.sqrt(np.mean([g.sigma_jackknife_arcsec**2 for g in grids], axis=0)), rtol=1e-9)
    np.testing.assert_allclose(four.honest_dof, np.mean([g.honest_dof for g in grids], axis=0),
                               rtol=1e-9)
    assert four.honest_phases == 4 and grids[0].honest_phases == 1
    assert "averaged over 4 block grids" in four.to_json()["honest_sigma"]["method"]


@pytest.mark.parametrize("phases", [0, -1, 2.5, True])
def test_bad_block_phases_is_a_plain_error(phases):
    data = _hourly_wander_campaign(np.random.default_rng(3), n=60)
    with pytest.raises(ValueError, match="block_phases must be a whole number >= 1"):
        fit_model(data, HONEST_TERMS, block_phases=phases)


def _few_cluster_campaign(rng, n=96, hours=8):
    """Fixed positions and times (8 one-hour clusters), independent errors per draw."""
    t = np.sort(rng.uniform(0.0, hours * 3600.0, n))
    az = rng.uniform(0.0, 2 * np.pi, n)
    el = np.radians(rng.uniform(15.0, 80.0, n))

    def draw(noise):
        return PointingData(az, el, noise.normal(0, 2.0, n), noise.normal(0, 5.0, n), t_s=t)
    return draw


def test_jackknife_dof_and_the_t_scaled_sigma_over_1500_campaigns():
    """With Gaussian errors the jackknife variance V is a quadratic form with E[V] = tr K and
    Var[V] = 2 tr K^2 exactly, so 2 E[V]^2 / Var[V] over many draws must equal the reported
    Satterthwaite dof. 1500 draws estimate it with a relative standard error of about
    sqrt((kurtosis - 1) / 1500) = 5% at dof ~ 6: 18% is 3.5 of those. With 8 clusters the
    raw jackknife pulls spread by sqrt(dof/(dof-2)) ~ 1.2 (measured 1.14-1.19 over 4000
    draws) and the t-scaled sigma brings them to 0.91-0.99 (below 1 because CV3 overstates
    the variance a little); a spread's standard error here is ~3%, hence 0.85..1.08 for the
    scaled and > 1.1 for the mean raw spread.

    Four block grids on the same draws: the mean of the grids' variances has the same
    expectation (measured ratio 1.00-1.02; 5% is over 3 standard errors of a ratio of two
    such closely tied means) and less spread, i.e. more effective dof (measured 1.43-1.55
    times one grid's; the ratio of two 5%-error estimates has ~7%, so > 1.25 is 2.5 of them
    below the lowest), and fewer pulls beyond 3 sigma (measured 0.35% pooled against 0.85%)."""
    terms = ["IA", "IE", "CA", "NPAE", "AN", "AW"]
    draw = _few_cluster_campaign(np.random.default_rng(11))
    noise = np.random.default_rng(12)
    values, var, dof, honest, var4, honest4 = [], [], [], [], [], []
    for _ in range(1500):
        data = draw(noise)
        fit = fit_model(data, terms, robust=False, block_phases=1)
        values.append(fit.values_arcsec)
        var.append(fit.sigma_jackknife_arcsec**2)
        dof.append(fit.honest_dof)
        honest.append(fit.sigma_honest_arcsec)
        four = fit_model(data, terms, robust=False)
        var4.append(four.sigma_jackknife_arcsec**2)
        honest4.append(four.sigma_honest_arcsec)
    values, var, dof, honest, var4, honest4 = map(np.array, (values, var, dof, honest, var4,
                                                            honest4))
    assert fit.honest_clusters == 8
    assert np.all((dof > 3) & (dof < 9))  # few clusters: a small dof is the point of the test
    dof_mc = 2 * var.mean(axis=0) ** 2 / var.var(axis=0)
    np.testing.assert_allclose(dof.mean(axis=0), dof_mc, rtol=0.18)
    scaled = np.std(values / honest, axis=0)
    assert np.all((scaled > 0.85) & (scaled < 1.08)), scaled
    assert np.mean(np.std(values / np.sqrt(var), axis=0)) > 1.1
    np.testing.assert_allclose(honest, np.sqrt(var * dof / (dof - 2)), rtol=1e-12)

    np.testing.assert_allclose(var4.mean(axis=0) / var.mean(axis=0), 1.0, atol=0.05)
    dof4_mc = 2 * var4.mean(axis=0) ** 2 / var4.var(axis=0)
    assert np.all(dof4_mc / dof_mc > 1.25), dof4_mc / dof_mc
    assert np.mean(np.abs(values / honest4) > 3) < np.mean(np.abs(values / honest) > 3)


def test_jackknife_dof_is_the_same_on_the_one_observation_fast_path():
    # t_s=None takes the Woodbury path; distinct times with a tiny block give the same
    # one-observation clusters through the general path
    full = _hourly_wander_campaign(np.random.default_rng(5), n=40)
    fast = fit_model(PointingData(full.az_rad, full.el_rad, full.xel_arcsec, full.el_arcsec),
                     HONEST_TERMS, robust=False)
    general = fit_model(full, HONEST_TERMS, robust=False, block_s=1e-3)
    assert fast.honest_clusters == general.honest_clusters == 40
    np.testing.assert_allclose(fast.honest_dof, general.honest_dof, rtol=1e-9)
    np.testing.assert_allclose(fast.sigma_honest_arcsec, general.sigma_honest_arcsec, rtol=1e-9)
    # 1 <= nu <= the number of clusters; TX (cot E) rests on the few lowest observations,
    # so its jackknife has the fewest effective degrees of freedom
    assert np.all((fast.honest_dof >= 1) & (fast.honest_dof <= 40))
    assert np.argmin(fast.honest_dof) == HONEST_TERMS.index("TX")


def test_t_scaled_sigma_is_unbounded_at_two_or_fewer_degrees_of_freedom():
    result = JackknifeResult(np.array([2.0, 1.0, np.nan]), np.array([10.0, 1.5, np.nan]), 5)
    scaled = result.sigma_t_scaled
    assert scaled[0] == pytest.approx(2.0 * math.sqrt(10.0 / 8.0), rel=1e-15)
    assert scaled[1] == math.inf  # a t with nu <= 2 has no finite variance
    assert math.isnan(scaled[2])  # a term not fitted stays without an error bar

"""The receiver (antsim.world.receiver) through the world: the power of an integration (beam,
receiver and atmosphere together) and the statistics of its noise.

Expected power of a sample (kelvin), channel c, source at elevation E, beam offset u:

    P = Tsys_c + T_atm (1 - exp(-tau0 / sin E))
          + S * gain_k_per_jy * eff(E) * exp(-tau0 / sin E) * peak * exp(-4 ln2 u^2 / W^2)

with ``peak = theta_b^2 / (theta_b^2 + theta_s^2)`` and ``W^2 = theta_b^2 + theta_s^2`` for a
Gaussian source of FWHM theta_s (1 and theta_b for a point source), and eff(E) the report's
efficiency curve (linear between the tabulated elevations).

Noise model of a sample: ``T (1 + g) + T n / sqrt(B dt)``, g an Ornstein-Uhlenbeck process of
rms sigma_g and correlation time tau_g (an AR(1) sequence with rho = exp(-dt / tau_g) at the
sample spacing dt), n white unit Gaussian noise. The mean of N samples then has variance

    T^2 [sigma_g^2 V(rho, N) + 1 / (B N dt)],  V = (N + 2 sum_{m=1}^{N-1} (N - m) rho^m) / N^2

and the sample variance within an integration has expectation N/(N-1) (var - var of mean).
Statistical checks use 400 integrations 600 s apart (10 gain correlation times: successive
integrations are independent to 5e-5) from a fixed seed, and accept at the two-sided 99.9%
level of the sampling distribution stated at each check.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import simpy
from scipy import stats

from antsim.scenario import load_scenario
from antsim.world.world import World

FOUR_LN2 = 4.0 * math.log(2.0)
N_REPEAT = 400
GAP_S = 600.0
TAU_S = 15.0
#: two-sided acceptance level of the statistical checks
ALPHA = 0.001


@pytest.fixture(scope="module")
def scenarios(quiet_path, ghigo_path):
    """(noise-free world with the 1990 atmosphere and efficiency curve, 1990 scenario)."""
    quiet = load_scenario(quiet_path)
    ghigo = load_scenario(ghigo_path)
    beam = dataclasses.replace(quiet.beam, efficiency_el_deg=ghigo.beam.efficiency_el_deg,
                               efficiency=ghigo.beam.efficiency)
    realistic_sky = dataclasses.replace(quiet, atmosphere=ghigo.atmosphere, beam=beam)
    return realistic_sky, ghigo


def _fixed(az_deg, el_deg):
    return lambda t: (np.full(np.shape(t), az_deg), np.full(np.shape(t), el_deg))


def _tracking(world, index, d_az_deg=0.0):
    def trajectory(t):
        az, el = world.sky.observed_altaz_rad(index, np.asarray(t, dtype=float), 0.0)
        return (np.degrees(az) + d_az_deg) % 360.0, np.degrees(el)

    return trajectory


def expected_power_k(world, index, t_samples, d_az_deg, channel):
    """Mean over the samples of the expected power (formula in the module docstring),
    written from the scenario's numbers, with the beam offset in azimuth by ``d_az_deg``."""
    sc = world.scenario
    tsys = {c.name: c.tsys_k for c in sc.receiver.channels}[channel]
    src = sc.sources[index]
    _, el = world.sky.observed_altaz_rad(index, t_samples, 0.0)
    airmass = 1.0 / np.sin(el)
    tau0, t_atm = sc.atmosphere.zenith_opacity, sc.atmosphere.temperature_k
    transmission = np.exp(-tau0 * airmass)
    eff = np.interp(np.degrees(el), sc.beam.efficiency_el_deg, sc.beam.efficiency)
    theta_b, theta_s = sc.beam.hpbw_arcmin, src.size_arcmin
    width2 = theta_b**2 + theta_s**2
    u_arcmin = d_az_deg * 60.0 * np.cos(el)
    beam = theta_b**2 / width2 * np.exp(-FOUR_LN2 * u_arcmin**2 / width2)
    power = (tsys + t_atm * (1.0 - transmission)
             + src.flux_jy * sc.beam.gain_k_per_jy * eff * transmission * beam)
    return float(np.mean(power))


def _sample_times(t_start, seconds, dt):
    n = max(1, round(seconds / dt))
    return t_start + (np.arange(n) + 0.5) * (seconds / n)


def _observe(world, index, d_az_deg, n, gap_s, t_first_s=600.0):
    """``n`` integrations of TAU_S on source ``index`` (offset ``d_az_deg`` in encoder
    azimuth), ``gap_s`` apart; returns [(integration, sample times)]."""
    env, antenna = world.env, world.antenna
    out = []

    def run():
        yield env.timeout(t_first_s)
        yield antenna.track(_tracking(world, index, d_az_deg))
        for _ in range(n):
            t0 = env.now
            integ = yield antenna.integrate(TAU_S)
            out.append((integ, _sample_times(t0, TAU_S, world.scenario.receiver.sample_interval_s)))
            yield antenna.wait(gap_s)

    env.run(until=env.process(run()))
    return out


# ---------------------------------------------------------------------------------------------
# noise-free: the power is exactly the formula
#: float rounding of ~50 K sums (1e-14) and radiometer noise of 5e-12 K per sample (the quiet
#: world's 1e20 MHz bandwidth) are far below this; any missing factor (efficiency 0.96,
#: transmission 0.96, emission 3.7 K, the 0.91 peak) is far above it
EXACT_K = 1e-9

#: (index in quiet.toml, what it tests): 3C84 at el 22-23 deg is on the sloping part of the
#: efficiency curve (0.96) where the airmass is 2.6; Cassiopeia A (3.46') is partly resolved
CASES = [(0, "point source, low elevation"), (2, "extended source, 3.46'")]


@pytest.mark.parametrize("index,what", CASES)
@pytest.mark.parametrize("offset", ["on", "off"])
def test_noise_free_power_on_and_off_source_is_the_formula(scenarios, index, what, offset):
    world = World(scenarios[0], simpy.Environment())
    # off source: 4D = 28' away in cross-elevation (beam response 1.6e-8), same elevation
    _, el0 = world.sky.observed_altaz_rad(index, np.array([600.0]), 0.0)
    d_az_deg = 0.0 if offset == "on" else 28.0 / 60.0 / math.cos(el0[0])
    (integ, t_samples), = _observe(world, index, d_az_deg, 1, 0.0)
    for channel in world.antenna.channels:
        expected = expected_power_k(world, index, t_samples, d_az_deg, channel)
        assert integ.power_k[channel] == pytest.approx(expected, abs=EXACT_K)
    if offset == "on":
        # the source adds S * gain * eff * transmission * peak: check the peak factor itself
        sc = world.scenario
        theta_b, theta_s = sc.beam.hpbw_arcmin, sc.sources[index].size_arcmin
        peak = theta_b**2 / (theta_b**2 + theta_s**2)
        tsys_xr = sc.receiver.channels[0].tsys_k
        sky = expected_power_k(world, index, t_samples, 10.0, "XR") - tsys_xr  # 10 deg away
        source = integ.power_k["XR"] - tsys_xr - sky
        _, el = world.sky.observed_altaz_rad(index, t_samples, 0.0)
        eff = np.interp(np.degrees(el), sc.beam.efficiency_el_deg, sc.beam.efficiency)
        transmission = np.exp(-sc.atmosphere.zenith_opacity / np.sin(el))
        scale = sc.sources[index].flux_jy * sc.beam.gain_k_per_jy * np.mean(eff * transmission)
        # the efficiency and transmission vary by < 1e-3 over the 15 s, so the mean of the
        # product equals the product of the means to ~1e-7: 1e-6 relative
        assert source / scale == pytest.approx(peak, rel=1e-6)
        if index == 0:
            assert np.mean(eff) < 0.97  # on the sloping part of the curve (0.96)
        if index == 2:
            assert peak == pytest.approx(0.91, abs=0.005)  # docs/physics.md: about 0.91 at 11'


def test_noisy_power_on_and_off_source_within_the_modeled_noise(scenarios):
    """The 1990 receiver: 10 integrations on and 10 off 3C84, 600 s apart; each differs from
    the formula by less than 4 predicted sigma (two channels x 20: P(any |z| > 4) = 2.5e-3
    for Gaussian noise), and the rms of the 40 z-scores is inside its chi-square(40) 99.9%
    interval."""
    realistic_sky, ghigo = scenarios
    scenario = dataclasses.replace(realistic_sky, receiver=ghigo.receiver)
    _, el0 = World(scenario, simpy.Environment()).sky.observed_altaz_rad(0, np.array([600.0]),
                                                                         0.0)
    off = 28.0 / 60.0 / math.cos(el0[0])
    z = []
    for d_az in (0.0, off):
        world = World(scenario, simpy.Environment(), seed=3 if d_az == 0 else 4)
        for integ, t_samples in _observe(world, 0, d_az, 10, GAP_S):
            for c, channel in enumerate(world.antenna.channels):
                expected = expected_power_k(world, 0, t_samples, d_az, channel)
                sigma = math.sqrt(_var_mean(world.scenario.receiver, c, expected, 15))
                z.append((integ.power_k[channel] - expected) / sigma)
    z = np.array(z)
    assert np.all(np.abs(z) < 4.0), z
    lo, hi = stats.chi2.ppf([ALPHA / 2, 1 - ALPHA / 2], z.size) / z.size
    assert lo < np.mean(z**2) < hi


# ---------------------------------------------------------------------------------------------
# the noise model: scatter of integration means and the reported sample std
def _ar1_v(rho: float, n: int) -> float:
    """Variance of the mean of n samples of a unit-variance AR(1) sequence (exact sum)."""
    m = np.arange(1, n)
    return (n + 2.0 * np.sum((n - m) * rho**m)) / n**2


def _dgg(receiver, c: int) -> float:
    """dG/G of channel ``c``: its own value if the channel sets one, else the receiver's."""
    own = getattr(receiver.channels[c], "gain_fluctuation", None)
    return receiver.gain_fluctuation if own is None else own


def _var_mean(receiver, c: int, t_k: float, n: int) -> float:
    dt = receiver.sample_interval_s
    rho = math.exp(-dt / receiver.gain_timescale_s)
    bandwidth = receiver.bandwidth_mhz * 1e6
    return t_k**2 * (_dgg(receiver, c) ** 2 * _ar1_v(rho, n) + 1.0 / (bandwidth * n * dt))


def _expected_sample_var(receiver, c: int, t_k: float, n: int) -> float:
    """E[sample variance (ddof=1) of the n samples of one integration]."""
    dt = receiver.sample_interval_s
    bandwidth = receiver.bandwidth_mhz * 1e6
    total = t_k**2 * (_dgg(receiver, c) ** 2 + 1.0 / (bandwidth * dt))
    return n / (n - 1) * (total - _var_mean(receiver, c, t_k, n))


#: receivers: the 1990 one (gain fluctuation 3e-4 over 60 s, 135 MHz), and its two noise
#: sources alone
RECEIVERS = {
    "radiometer only": {"gain_fluctuation": 0.0},
    "gain only": {"bandwidth_mhz": 1e20},
    "1990 receiver": {},
}


@pytest.fixture(scope="module")
def repeated(scenarios):
    """N_REPEAT off-source integrations (az 180, el 45: no source within 2 deg) per receiver,
    with the 1990 atmosphere; returns {name: (world, means, stds)} with arrays (N, channels)."""
    realistic_sky, ghigo = scenarios
    out = {}
    for name, change in RECEIVERS.items():
        receiver = dataclasses.replace(ghigo.receiver, **change)
        if name == "radiometer only":  # also no per-channel gain fluctuation, if any is set
            receiver = dataclasses.replace(receiver, channels=tuple(
                dataclasses.replace(ch, gain_fluctuation=None)
                if hasattr(ch, "gain_fluctuation") else ch for ch in receiver.channels))
        scenario = dataclasses.replace(realistic_sky, receiver=receiver)
        world = World(scenario, simpy.Environment(), seed=2024)
        env, antenna = world.env, world.antenna
        integrations = []

        def run(env=env, antenna=antenna, integrations=integrations):
            yield antenna.track(_fixed(180.0, 45.0))
            for _ in range(N_REPEAT):
                integrations.append((yield antenna.integrate(TAU_S)))
                yield antenna.wait(GAP_S)

        env.run(until=env.process(run()))
        assert antenna._targets == []  # really off source
        channels = antenna.channels
        means = np.array([[i.power_k[c] for c in channels] for i in integrations])
        stds = np.array([[i.std_k[c] for c in channels] for i in integrations])
        out[name] = (world, means, stds)
    return out


def _system_k(world) -> np.ndarray:
    """T = Tsys + sky emission at 45 deg, per channel."""
    atm = world.scenario.atmosphere
    emission = atm.temperature_k * (1.0 - math.exp(-atm.zenith_opacity / math.sin(math.pi / 4)))
    return np.array([c.tsys_k for c in world.scenario.receiver.channels]) + emission


@pytest.mark.parametrize("name", list(RECEIVERS))
def test_mean_power_off_source_is_tsys_plus_sky(repeated, name):
    world, means, _ = repeated[name]
    t_k = _system_k(world)
    for c in range(t_k.size):
        sigma = math.sqrt(_var_mean(world.scenario.receiver, c, t_k[c], 15) / N_REPEAT)
        assert abs(means[:, c].mean() - t_k[c]) < 4.0 * sigma  # 4 sigma of the grand mean


@pytest.mark.parametrize("name", list(RECEIVERS))
def test_scatter_of_integration_means_matches_the_noise_model(repeated, name):
    """Sample variance of 400 independent means: (n-1) s^2 / sigma^2 ~ chi-square(n-1);
    accepted inside its 99.9% interval, [0.79, 1.24] of the prediction."""
    world, means, _ = repeated[name]
    receiver = world.scenario.receiver
    n = means.shape[0]
    lo, hi = stats.chi2.ppf([ALPHA / 2, 1 - ALPHA / 2], n - 1) / (n - 1)
    for c, t_k in enumerate(_system_k(world)):
        predicted = _var_mean(receiver, c, t_k, 15)
        ratio = np.var(means[:, c], ddof=1) / predicted
        assert lo < ratio < hi, (name, c, ratio)
        if _dgg(receiver, c) > 0:
            # the test tells the models apart: gain samples taken as independent
            # (sigma_g^2 / N) would predict 13.8 times less
            naive = t_k**2 * (_dgg(receiver, c) ** 2 / 15
                              + 1.0 / (receiver.bandwidth_mhz * 1e6 * TAU_S))
            assert not lo < np.var(means[:, c], ddof=1) / naive < hi
    if name == "radiometer only":
        # docs/physics.md: radiometer noise is only ~1 mK in 15 s
        assert math.sqrt(_var_mean(receiver, 0, _system_k(world)[0], 15)) == pytest.approx(
            1.0e-3, rel=0.1)


@pytest.mark.parametrize("name", list(RECEIVERS))
def test_reported_sample_std_matches_the_noise_model(repeated, name):
    """Mean of the 400 reported within-integration variances against its expectation. With
    white noise only, sum (N-1) s^2 / sigma^2 is chi-square(400 (N-1)) exactly; with
    correlated gain the sampling error is taken from the spread of the 400 values (their
    mean is Gaussian to a good approximation: 4 standard errors)."""
    world, _, stds = repeated[name]
    receiver = world.scenario.receiver
    n_int, n = stds.shape[0], 15
    for c, t_k in enumerate(_system_k(world)):
        expected = _expected_sample_var(receiver, c, t_k, n)
        s2 = stds[:, c] ** 2
        if _dgg(receiver, c) == 0:
            dof = n_int * (n - 1)
            lo, hi = stats.chi2.ppf([ALPHA / 2, 1 - ALPHA / 2], dof) / dof
            assert lo < s2.mean() / expected < hi
        else:
            standard_error = s2.std(ddof=1) / math.sqrt(n_int)
            assert abs(s2.mean() - expected) < 4.0 * standard_error


def test_xl_noise_is_above_xr(repeated):
    """Every noise term scales with the system temperature: XL's (Tsys 15% higher) variance
    is (T_XL / T_XR)^2 = 1.30 times XR's. Radiometer-only within-integration variances pool
    400 x 14 degrees of freedom per channel; their ratio is F-distributed: 99.9% interval
    about +-9%, which excludes equality."""
    world, means, stds = repeated["radiometer only"]
    t_k = _system_k(world)
    predicted = (t_k[1] / t_k[0]) ** 2
    assert world.antenna.channels == ("XR", "XL")
    dof = stds.shape[0] * 14
    lo, hi = stats.f.ppf([ALPHA / 2, 1 - ALPHA / 2], dof, dof)
    ratio = np.mean(stds[:, 1] ** 2) / np.mean(stds[:, 0] ** 2)
    assert lo * predicted < ratio < hi * predicted
    assert lo * predicted > 1.0
    # the 1990 receiver: both the scatter of the means and the reported std are higher in
    # XL (ratio of 400-mean variances: F(399, 399), 99.9% interval [0.72, 1.38])
    world, means, stds = repeated["1990 receiver"]
    receiver, t_k = world.scenario.receiver, _system_k(world)
    predicted = _var_mean(receiver, 1, t_k[1], 15) / _var_mean(receiver, 0, t_k[0], 15)
    lo, hi = stats.f.ppf([ALPHA / 2, 1 - ALPHA / 2], 399, 399)
    ratio = np.var(means[:, 1], ddof=1) / np.var(means[:, 0], ddof=1)
    assert lo * predicted < ratio < hi * predicted
    assert np.mean(stds[:, 1]) > np.mean(stds[:, 0])
    assert np.std(means[:, 1]) > np.std(means[:, 0])



"""The thermal building blocks (antsim.world.effects.thermal): ``SunsetDrift`` (a (1 - 1/e)
one time constant after sunset; Fomalont's 1' in the 4 hours after sunset is expressible in a
scenario), the first-order filter against scipy's lfilter, and the scalar interpolator
against np.interp."""

from __future__ import annotations

import math

import numpy as np
import pytest
import simpy

from antsim.scenario import load_scenario
from antsim.world.effects import PointingState
from antsim.world.effects.thermal import GRID_STEP_S
from antsim.world.world import World
from controller.astro.sun import sunset_times_s
from tests.antsim.world.effects.conftest import (
    ARCSEC,
    _effect,
)


@pytest.fixture
def ghigo_24h_with(ghigo_text, write_scenario):
    """The 24-hour 1990 scenario with an extra [[truth.effects]] table appended."""

    def make(extra: str):
        return load_scenario(write_scenario(ghigo_text + "\n" + extra))

    return make


def test_sunset_drift_one_time_constant_after_sunset(ghigo_24h_with):
    """a (1 - e^-1) one tau after sunset, counted from the level at sunset (the previous
    night's drift has relaxed by e^-(10.6 h / tau) = 0.1% by then, the 'residual'). The
    model switches its night indicator on the 60-s grid, so its exponential starts up to one
    grid step before the exact sunset: tolerance a e^-1 (60 s / tau) = 0.4% of a."""
    a, tau = 60.0, 5400.0
    scenario = ghigo_24h_with(f'[[truth.effects]]\neffect = "sunset_drift"\n'
                              f"amplitude_arcsec = {a}\ntau_s = {tau}\n")
    world = World(scenario, simpy.Environment())
    drift = _effect(world, "sunset_drift")
    (t_set,) = sunset_times_s(world.ephemeris, horizon_deg=0.0)
    e0 = float(drift.error_arcsec(t_set))
    assert 0.0 <= e0 < 0.002 * a  # the residual of the previous night
    expected = a - (a - e0) * math.exp(-1.0)  # = a (1 - e^-1) for e0 = 0
    tolerance = a * math.exp(-1.0) * GRID_STEP_S / tau
    assert float(drift.error_arcsec(t_set + tau)) == pytest.approx(expected, abs=tolerance)
    assert float(drift.error_arcsec(t_set + tau)) == pytest.approx(a * (1 - math.exp(-1)),
                                                                   abs=tolerance + 0.002 * a)
    # it is an elevation error only, and the world's error sum includes it
    state = PointingState(t_s=t_set + tau, az_rad=1.0, el_rad=0.7)
    d_az, d_el = drift.pointing_error(state)
    assert d_az == 0.0
    # the same number through a unit conversion: float rounding only
    assert d_el / ARCSEC == pytest.approx(float(drift.error_arcsec(t_set + tau)), rel=1e-12)


def test_fomalont_one_arcmin_in_four_hours_after_sunset_is_expressible(ghigo_24h_with):
    """Fomalont (1973): elevation changed systematically by 1.0' in the 4 h after sunset.
    With tau = 1.5 h, a = 60" / (1 - e^(-4 / 1.5)) = 64.48" gives exactly that. Tolerance
    0.5" (1% of 1'): the 0.1% residual at sunset and the one-grid-step start (a e^-(8/3)
    60 s / tau = 0.05") are far inside it."""
    tau = 5400.0
    a = 60.0 / (1.0 - math.exp(-4 * 3600.0 / tau))
    scenario = ghigo_24h_with(f'[[truth.effects]]\neffect = "sunset_drift"\n'
                              f"amplitude_arcsec = {a:.4f}\ntau_s = {tau}\n")
    world = World(scenario, simpy.Environment())
    drift = _effect(world, "sunset_drift")
    (t_set,) = sunset_times_s(world.ephemeris, horizon_deg=0.0)
    t = t_set + np.linspace(0.0, 4 * 3600.0, 241)
    curve = drift.error_arcsec(t)
    assert curve[-1] - curve[0] == pytest.approx(60.0, abs=0.5)
    assert np.all(np.diff(curve) > 0)  # systematic: monotonic over the 4 hours


def test_first_order_filter_is_lfilter_bit_for_bit():
    from scipy.signal import lfilter

    from antsim.world.effects.thermal import first_order_filter

    rng = np.random.default_rng(4)
    x = rng.standard_normal(500)
    expected = lfilter([0.3], [1.0, -0.97], x, zi=[0.25])[0]
    assert np.array_equal(first_order_filter(x, 0.3, 0.97, 0.25), expected)
    cube = rng.standard_normal((200, 3, 2))
    state = rng.standard_normal((3, 2))
    expected = lfilter([0.3], [1.0, -0.97], cube, axis=0, zi=state[None])[0]
    assert np.array_equal(first_order_filter(cube, 0.3, 0.97, state), expected)


def test_a_long_series_is_filtered_by_lfilter_as_by_the_loop(monkeypatch):
    """A series of LFILTER_SAMPLES or more goes to lfilter itself: the same bytes as the
    loop that shorter ones take (the simulation's bytes do not depend on the length)."""
    from antsim.world.effects import thermal

    rng = np.random.default_rng(5)
    x = rng.standard_normal(thermal.LFILTER_SAMPLES + 7).cumsum()
    fast = thermal.first_order_filter(x, 0.02, 0.98, 1.5)
    monkeypatch.setattr(thermal, "LFILTER_SAMPLES", x.size + 1)
    assert np.array_equal(fast, thermal.first_order_filter(x, 0.02, 0.98, 1.5))


def test_scalar_interpolator_is_np_interp_bit_for_bit():
    from antsim.world.effects.thermal import ScalarInterpolator

    rng = np.random.default_rng(8)
    grid = np.arange(-600.0, 6000.0, 60.0)
    rows = [rng.standard_normal(grid.size) * 10.0 for _ in range(3)]
    interp = ScalarInterpolator(grid, rows)
    times = [-1e4, grid[0], grid[5], 123.456, 3599.999, grid[-1], 1e6,
             *rng.uniform(-700.0, 6100.0, 200)]
    for t in times:
        assert interp(float(t)) == [float(np.interp(t, grid, r)) for r in rows], t

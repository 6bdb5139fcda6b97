"""The heat balance of a member (antsim.world.heat) against the analytic solution and an
ODE integration: each check says what it could catch."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from antsim.world import heat

#: structural steel: 7850 kg/m^3 x 460 J/(kg K)
STEEL_J_M3K = 7850.0 * 460.0


def test_a_member_settles_at_absorbed_over_h_with_tau_rho_c_d_over_h():
    """A 10 mm steel plate switched into 200 W/m^2 of absorbed sunlight with h = 15
    W/(m^2 K): the ODE rho c d dT/dt = aE - h T, integrated by scipy, settles at aE/h =
    13.3 K and reaches 1 - 1/e of it after rho c d / h = 2407 s (40 minutes). A wrong
    factor in the time constant or the equilibrium moves these by more than the 0.1%
    tolerance (the integrator's own error is 1e-8)."""
    d, h, absorbed = 0.010, 15.0, 200.0
    tau = heat.time_constant_s(d, STEEL_J_M3K, h)
    assert tau == pytest.approx(STEEL_J_M3K * d / h) and 2300.0 < tau < 2500.0
    excess = heat.equilibrium_excess_k(absorbed, h)
    assert excess == pytest.approx(absorbed / h)
    sol = solve_ivp(lambda t, y: (absorbed - h * y) / (STEEL_J_M3K * d), (0.0, 10 * tau),
                    [0.0], t_eval=[tau, 10 * tau], rtol=1e-10, atol=1e-10)
    assert sol.y[0, 0] == pytest.approx(excess * (1.0 - math.exp(-1.0)), rel=1e-3)
    assert sol.y[0, 1] == pytest.approx(excess, rel=1e-3)
    # the grid relaxation of the simulation reproduces the same curve exactly at its steps
    step = 60.0
    relaxed = heat.relax_varying(np.full(200, excess), np.full(200, tau), step, 0.0)
    t = step * np.arange(1, 201)
    np.testing.assert_allclose(relaxed, excess * (1.0 - np.exp(-t / tau)), rtol=1e-12)


def test_a_time_constant_that_follows_the_wind_is_integrated_as_the_ode_says():
    """Wind rising from 1 to 5 m/s over two hours raises h (Watmuff: 2.8 + 3 v, plus 4.1 of
    radiation) and shortens the time constant; the one-minute relaxation with the time
    constant of each step follows scipy's integration of the varying ODE within 1% of the
    largest excess (measured 0.2%); a relaxation that kept the first step's time constant is
    4.5% off."""
    d, step = 0.006, 60.0
    t = np.arange(1, 121) * step
    wind = 1.0 + 4.0 * t / t[-1]
    h = heat.convective_coefficient_w_m2k(wind) + heat.radiative_coefficient_w_m2k(0.9, 273.15)
    absorbed = 150.0
    forcing = absorbed / h
    tau = heat.time_constant_s(d, STEEL_J_M3K, h)
    relaxed = heat.relax_varying(forcing, tau, step, 0.0)

    def rhs(time, y):
        v = 1.0 + 4.0 * time / t[-1]
        hh = 2.8 + 3.0 * v + float(heat.radiative_coefficient_w_m2k(0.9, 273.15))
        return (absorbed - hh * y) / (STEEL_J_M3K * d)

    sol = solve_ivp(rhs, (0.0, t[-1]), [0.0], t_eval=t, rtol=1e-10, atol=1e-10)
    assert np.max(np.abs(relaxed - sol.y[0])) < 0.01 * float(forcing.max())
    frozen = heat.relax_varying(forcing, np.full(t.size, tau[0]), step, 0.0)
    assert np.max(np.abs(frozen - sol.y[0])) > 0.03 * float(forcing.max())


def test_the_coefficients_are_the_published_formulas():
    """Watmuff et al. (1977) 2.8 + 3.0 v; 4 eps sigma T^3 = 4.16 W/(m^2 K) for eps 0.9 at
    0 C; Swinbank (1963) 0.0552 T^1.5: 249.2 K over air at 0 C (24 K colder)."""
    np.testing.assert_allclose(heat.convective_coefficient_w_m2k([0.0, 1.5, 4.5]),
                               [2.8, 7.3, 16.3])
    assert heat.radiative_coefficient_w_m2k(0.9, 273.15) == pytest.approx(4.16, abs=0.01)
    assert heat.sky_temperature_k(273.15) == pytest.approx(249.2, abs=0.1)


def test_clear_sky_sunlight_follows_laue_and_the_air_mass():
    """Laue (1970): at the zenith at sea level 1353 x 0.7 = 947 W/m^2 (air mass 1, Kasten
    and Young: 0.9997); higher at 800 m; weaker as the Sun sinks; none below the horizon.
    At Green Bank's 8 February noon (Sun at 36 deg) about 870 W/m^2."""
    zenith = float(heat.direct_normal_irradiance_w_m2(math.pi / 2, 0.0))
    assert zenith == pytest.approx(1353.0 * 0.7, rel=2e-3)
    assert float(heat.air_mass(math.pi / 2)) == pytest.approx(1.0, abs=1e-3)
    el = np.radians([5.0, 10.0, 20.0, 36.0, 60.0, 90.0])
    high = heat.direct_normal_irradiance_w_m2(el, 800.0)
    assert np.all(np.diff(high) > 0.0)
    assert np.all(high > heat.direct_normal_irradiance_w_m2(el, 0.0))
    assert 840.0 < high[3] < 900.0
    assert float(heat.direct_normal_irradiance_w_m2(math.radians(-1.0), 800.0)) == 0.0


def test_a_pair_differs_by_the_sunlight_it_absorbs_differently():
    """Two faces seeing the air and the sky alike differ by alpha (E_a - E_b) / h: a face
    towards the Sun (850 W/m^2) against one away, white paint (0.25), h = 20: 10.6 K."""
    assert heat.pair_forcing_k(0.25, 850.0, 0.0, 20.0) == pytest.approx(10.625)
    assert heat.pair_forcing_k(0.25, 400.0, 400.0, 20.0) == 0.0

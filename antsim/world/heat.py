"""The heat balance of a structural member in sunlight: SI units throughout.

A thin member (a steel plate or the wall of a tube) of thickness ``d`` and volumetric heat
capacity ``rho c`` exchanges heat with the air by convection (coefficient ``h_c``, rising with
the wind) and with its surroundings by long-wave radiation (linearised: ``h_r = 4 eps sigma
T^3``), and absorbs the direct sunlight falling on its projected area with absorptivity
``alpha``. Per unit of its surface:

    rho c d dT/dt = alpha E - h (T - T_air),        h = h_c + h_r

so the member relaxes towards ``T_air + alpha E / h`` with the time constant
``tau = rho c d / h``. The radiative exchange with a clear sky colder than the air
(:func:`sky_temperature_k`) lowers every member's temperature alike; two faces of a member
pair that see the sky alike (vertical faces, tubes) differ only by the sunlight they absorb,
so the difference of a pair obeys the same equation with the difference of the absorbed
fluxes and no air or sky term (:func:`pair_forcing_k`).

The sources of the formulas (the constants are theirs, not tuned here):

* direct normal irradiance of a clear sky: Laue (1970), as PV Education gives it,
  ``E_dn = 1353 W/m^2 [(1 - a h) 0.7^(AM^0.678) + a h]`` with ``a = 0.14`` per km of height
  ``h``, and the air mass of Kasten and Young (1989);
* convection from a surface in wind: Watmuff, Charters and Proctor (1977), the correlation
  Duffie and Beckman's *Solar Engineering of Thermal Processes* recommends,
  ``h_c = 2.8 + 3.0 v`` W/(m^2 K) for a wind of ``v`` m/s (McAdams' 5.7 + 3.8 v is the upper
  end of the published range; a wall in 0-4 m/s of wind measures 6-10 W/(m^2 K), Jayamaha
  et al. 1996);
* the clear sky's effective temperature: Swinbank (1963), ``T_sky = 0.0552 T_air^1.5`` (K);
* Stefan-Boltzmann's constant from :mod:`scipy.constants`.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import constants

#: Stefan-Boltzmann's constant (W/(m^2 K^4))
STEFAN_BOLTZMANN_W_M2K4 = constants.sigma

__all__ = ["LAUE_SOLAR_W_M2", "STEFAN_BOLTZMANN_W_M2K4", "air_mass",
           "convective_coefficient_w_m2k", "direct_normal_irradiance_w_m2",
           "equilibrium_excess_k", "pair_forcing_k", "radiative_coefficient_w_m2k",
           "relax_varying", "sky_temperature_k", "time_constant_s"]

#: the solar constant of Laue's clear-sky formula (W/m^2)
LAUE_SOLAR_W_M2 = 1353.0
#: Laue's fraction of the direct beam transmitted per air mass, its exponent of the air
#: mass, and the rise of the beam with height above sea level (per km)
LAUE_TRANSMISSION = 0.7
LAUE_AIRMASS_EXPONENT = 0.678
LAUE_HEIGHT_PER_KM = 0.14
#: Watmuff, Charters and Proctor (1977): h_c = a + b v (W/(m^2 K), v in m/s)
WATMUFF_STILL_W_M2K = 2.8
WATMUFF_PER_M_S = 3.0
#: Swinbank (1963): T_sky = c T_air^1.5 (K)
SWINBANK_COEFFICIENT = 0.0552


def air_mass(sun_el_rad) -> np.ndarray:
    """Relative air mass towards elevation ``sun_el_rad`` (Kasten and Young 1989); infinite
    at and below -0 deg, where no direct sunlight arrives."""
    el = np.asarray(sun_el_rad, dtype=float)
    zenith_deg = 90.0 - np.degrees(el)
    with np.errstate(invalid="ignore", divide="ignore"):
        am = 1.0 / (np.sin(el) + 0.50572 * np.power(np.maximum(96.07995 - zenith_deg, 1e-9),
                                                    -1.6364))
    return np.where(el > 0.0, am, np.inf)


def direct_normal_irradiance_w_m2(sun_el_rad, height_m: float) -> np.ndarray:
    """Clear-sky direct sunlight on a surface facing the Sun (W/m^2) at a site ``height_m``
    above sea level (Laue 1970); 0 with the Sun below the horizon."""
    am = air_mass(sun_el_rad)
    a_h = LAUE_HEIGHT_PER_KM * max(float(height_m), 0.0) / 1000.0
    with np.errstate(invalid="ignore", over="ignore"):
        beam = LAUE_SOLAR_W_M2 * ((1.0 - a_h) * LAUE_TRANSMISSION ** (am ** LAUE_AIRMASS_EXPONENT)
                                  + a_h)
    return np.where(np.isfinite(am), beam, 0.0)


def convective_coefficient_w_m2k(wind_m_s) -> np.ndarray:
    """Convective heat-transfer coefficient of a surface in a wind of ``wind_m_s`` (W/(m^2 K);
    Watmuff et al. 1977)."""
    return WATMUFF_STILL_W_M2K + WATMUFF_PER_M_S * np.maximum(np.asarray(wind_m_s, float), 0.0)


def radiative_coefficient_w_m2k(emissivity: float, temperature_k) -> np.ndarray:
    """Linearised long-wave radiative coefficient ``4 eps sigma T^3`` (W/(m^2 K)) of a
    surface of ``emissivity`` at ``temperature_k``: 4.1 W/(m^2 K) for white paint (0.9) at
    0 C."""
    t = np.asarray(temperature_k, dtype=float)
    return 4.0 * emissivity * STEFAN_BOLTZMANN_W_M2K4 * t ** 3


def sky_temperature_k(air_k) -> np.ndarray:
    """Effective radiating temperature of a clear sky (K) above air at ``air_k`` (Swinbank
    1963): about 24 K below the air at 0 C."""
    return SWINBANK_COEFFICIENT * np.asarray(air_k, dtype=float) ** 1.5


def time_constant_s(thickness_m: float, heat_capacity_j_m3k: float, h_w_m2k) -> np.ndarray:
    """Thermal time constant (s) of a member ``thickness_m`` thick losing heat with the
    coefficient ``h_w_m2k`` (per unit of the surface that absorbs and loses the heat)."""
    return heat_capacity_j_m3k * thickness_m / np.asarray(h_w_m2k, dtype=float)


def equilibrium_excess_k(absorbed_w_m2, h_w_m2k) -> np.ndarray:
    """The temperature above the air (K) at which a member absorbing ``absorbed_w_m2``
    loses as much as it absorbs (steady state of the balance)."""
    return np.asarray(absorbed_w_m2, dtype=float) / np.asarray(h_w_m2k, dtype=float)


def pair_forcing_k(absorptivity: float, flux_a_w_m2, flux_b_w_m2, h_w_m2k) -> np.ndarray:
    """The steady temperature difference (K) of two faces (or members) that see the air and
    the sky alike and absorb ``absorptivity`` times the direct fluxes ``flux_a_w_m2`` and
    ``flux_b_w_m2`` (W/m^2 on their surfaces)."""
    return absorptivity * (np.asarray(flux_a_w_m2, float) - np.asarray(flux_b_w_m2, float)) \
        / np.asarray(h_w_m2k, dtype=float)


def relax_varying(forcing: np.ndarray, tau_s: np.ndarray, step_s: float,
                  initial) -> np.ndarray:
    """A first-order lag with a time constant that changes with time: ``x[n]`` relaxes from
    ``x[n-1]`` towards ``forcing[n]`` with ``tau_s[n]`` over one step ``step_s`` (exact for
    a forcing and a time constant constant over each step), along axis 0; ``initial`` is the
    value before the first step."""
    forcing = np.asarray(forcing, dtype=float)
    decay = np.exp(-step_s / np.broadcast_to(np.asarray(tau_s, dtype=float),
                                             forcing.shape[:1]))
    out = np.empty_like(forcing)
    x = np.asarray(initial, dtype=float) * np.ones(forcing.shape[1:])
    if forcing.ndim == 1:  # plain floats: a day of one-minute steps in a few milliseconds
        x_f = float(x)
        values = forcing.tolist()
        for i, (f, d) in enumerate(zip(values, decay.tolist(), strict=True)):
            x_f = f + (x_f - f) * d
            values[i] = x_f
        out[:] = values
        return out
    for i in range(forcing.shape[0]):
        x = forcing[i] + (x - forcing[i]) * decay[i]
        out[i] = x
    return out


def step_decay(dt_s: float, tau_s: float) -> float:
    """``exp(-dt / tau)``: how much of a difference from its forcing a member keeps after
    ``dt_s`` (1 when no time passes)."""
    return math.exp(-dt_s / tau_s) if dt_s > 0.0 else 1.0

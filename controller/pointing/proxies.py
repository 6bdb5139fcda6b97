"""Proxies for the structure's temperatures, from what every recording allows.

Without structure temperature sensors (the 1990 antenna had none) the thermal terms of
:mod:`controller.pointing.thermal` can be driven by quantities every recording allows: the
time, the site (hence the Sun), where the antenna pointed and the air temperature. Each proxy
stands for one of the structure's temperature differences:

* ``sun_lag``: the insolation I = max(0, sin h_sun), lagged by the structure's time
  constant: a front-to-back difference that the Sun builds through the day and that relaxes
  after sunset (Fomalont 1973: 1' for 4 hours after sunset);
* ``sun_face``: I (s . b), s the unit vector to the Sun and b the beam's: the Sun on the
  dish's face (+) or back (-); the dish's members follow in minutes, so it is not lagged;
* ``sun_side``: I (s . x), x the direction of increasing azimuth: the Sun on the dish's side;
* ``sun_north_lag``, ``sun_east_lag``: I cos A_sun and I sin A_sun lagged: which side of the
  pedestal the Sun has warmed;
* ``air_lag``: the air temperature lagged by the structure's time constant (K).

The time constant is the observatory's estimate of its structure's (:data:`PROXY_TAU_S`, 1.5 h:
a steel structure of this size warms and cools over an hour or two; an assumption,
``docs/assumptions.md``). What the proxies cannot see (clouds, the wind's cooling, where
the antenna pointed minutes before) stays in the residuals.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
from astropy.time import Time, TimeDelta
from scipy.signal import lfilter

from controller.astro.ephemeris import Ephemeris
from controller.astro.site import Site

__all__ = ["PROXY_NAMES", "PROXY_TAU_S", "proxy_aux"]

#: the structure's time constant the lagged proxies assume (s)
PROXY_TAU_S = 5400.0
#: the proxies' grid step (s) and how far before the first observation it starts (s)
STEP_S = 60.0
SPINUP_S = 86400.0
PROXY_NAMES = ("sun_lag", "sun_face", "sun_side", "sun_north_lag", "sun_east_lag", "air_lag")


def _lag(x: np.ndarray, tau_s: float, initial: float) -> np.ndarray:
    """First-order lag of ``x`` sampled every STEP_S (exact decay per step)."""
    alpha = math.exp(-STEP_S / tau_s)
    out, _ = lfilter([1.0 - alpha], [1.0, -alpha], x, zi=[alpha * initial])
    return out


def proxy_aux(t_s: np.ndarray, az_rad: np.ndarray, el_rad: np.ndarray,
              air_temp_c: np.ndarray | None, site: Mapping[str, float], epoch_utc: str,
              tau_s: float = PROXY_TAU_S) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """The proxies at each observation (times ``t_s`` since ``epoch_utc``, positions in
    radians, North-based azimuth), as :class:`~controller.pointing.data.PointingData`'s
    ``aux`` (the same value for both axes' rows). ``site``: ``latitude_deg``,
    ``longitude_deg``, ``height_m`` (the recordings' metadata). ``air_temp_c`` None: no
    ``air_lag``."""
    t_s = np.asarray(t_s, dtype=float)
    az, el = np.asarray(az_rad, dtype=float), np.asarray(el_rad, dtype=float)
    end = float(np.max(t_s)) if t_s.size else 0.0
    grid = np.arange(-SPINUP_S, end + 2 * STEP_S, STEP_S)
    here = Site(float(site["latitude_deg"]), float(site["longitude_deg"]),
                float(site.get("height_m", 0.0)), str(site.get("name", "")))
    start = Time(epoch_utc, scale="utc") - TimeDelta(SPINUP_S, format="sec")
    sun = Ephemeris(here, start, grid[-1] + SPINUP_S + STEP_S, ())
    sun_az, sun_el = sun.sun_altaz_rad(grid + SPINUP_S)
    insolation = np.clip(np.sin(sun_el), 0.0, None)
    lagged = {
        "sun_lag": _lag(insolation, tau_s, 0.0),
        "sun_north_lag": _lag(insolation * np.cos(sun_az), tau_s, 0.0),
        "sun_east_lag": _lag(insolation * np.sin(sun_az), tau_s, 0.0),
    }
    out = {k: np.interp(t_s, grid, v) for k, v in lagged.items()}
    s_az, s_el = np.interp(t_s, grid, np.unwrap(sun_az)), np.interp(t_s, grid, sun_el)
    flux = np.clip(np.sin(s_el), 0.0, None)
    out["sun_face"] = flux * (np.cos(s_el) * np.cos(el) * np.cos(az - s_az)
                              + np.sin(s_el) * np.sin(el))
    out["sun_side"] = flux * np.cos(s_el) * np.sin(s_az - az)
    if air_temp_c is not None:
        air = np.asarray(air_temp_c, dtype=float)
        ok = np.isfinite(air)
        if ok.any():
            order = np.argsort(t_s[ok])
            curve = np.interp(grid, t_s[ok][order], air[ok][order])  # held before the first
            out["air_lag"] = np.interp(t_s, grid, _lag(curve, tau_s, float(curve[0])))
    return {k: (v, v) for k, v in out.items()}

"""The Sun's day: sunrise and sunset, and the Sun elevations that separate day from night
(the 1990 report's fits D and E, the scheduler's day and night windows)."""

from __future__ import annotations

import math

import numpy as np

from .ephemeris import Ephemeris
from .values import require_finite

__all__ = ["DAY_SUN_MIN_DEG", "NIGHT_SUN_MAX_DEG", "sunrise_times_s", "sunset_times_s"]

#: Sun elevations that separate day and night (deg): civil/nautical twilight in between
DAY_SUN_MIN_DEG = 0.0
NIGHT_SUN_MAX_DEG = -12.0


def _sun_crossings_s(ephemeris: Ephemeris, horizon_deg: float, rising: bool) -> np.ndarray:
    require_finite(horizon_deg, "horizon_deg")
    if not isinstance(ephemeris, Ephemeris):
        raise ValueError(f"expected an Ephemeris, got {type(ephemeris).__name__}.")
    horizon = math.radians(horizon_deg)
    # 5-minute scan: the Sun's elevation changes by at most ~1.25 deg in that time, so only
    # grazing passes (polar sites) could hide two crossings in one step
    n = max(math.ceil(ephemeris.duration_s / 300.0), 1)
    t = np.linspace(0.0, ephemeris.duration_s, n + 1)
    above = ephemeris.sun_altaz_rad(t)[1] >= horizon
    steps = np.flatnonzero(above[1:] & ~above[:-1] if rising else above[:-1] & ~above[1:])
    lo, hi = t[steps], t[steps + 1]
    for _ in range(40):  # bisection to well below a millisecond
        mid = 0.5 * (lo + hi)
        mid_above = ephemeris.sun_altaz_rad(mid)[1] >= horizon
        after = mid_above if rising else ~mid_above
        hi = np.where(after, mid, hi)
        lo = np.where(after, lo, mid)
    return 0.5 * (lo + hi)


def sunset_times_s(ephemeris: Ephemeris, *, horizon_deg: float = -0.833) -> np.ndarray:
    """Times (s since the epoch) at which the Sun's centre sets inside [0, duration].

    The event is the vacuum elevation of the Sun's centre crossing ``horizon_deg`` downward;
    the default -0.833 deg is the almanac sunset (upper limb on the horizon: 16' semidiameter
    plus 34' standard refraction); use 0 for the geometric centre. Accurate to well under a
    second.
    """
    return _sun_crossings_s(ephemeris, horizon_deg, rising=False)


def sunrise_times_s(ephemeris: Ephemeris, *, horizon_deg: float = -0.833) -> np.ndarray:
    """Times (s since the epoch) at which the Sun's centre rises inside [0, duration]: the
    upward crossing of ``horizon_deg`` (see :func:`sunset_times_s`)."""
    return _sun_crossings_s(ephemeris, horizon_deg, rising=True)

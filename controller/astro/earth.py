"""Time and the Earth's orientation: the campaign's UTC instant, UT1 and polar motion from
the bundled IERS tables (:mod:`controller.astro.offline`), exactly as astropy's own transforms
obtain them; UTC labels of the campaign's seconds (:class:`UtcLabeller`)."""

from __future__ import annotations

import datetime
import math
import warnings
from typing import Any

import numpy as np
from astropy import units as u
from astropy.time import Time, TimeDelta
from astropy.utils import iers

from . import offline as _offline

__all__ = ["UtcLabeller", "polar_motion_rad", "ut1_two_part", "utc_instant"]

#: astropy's fallback polar motion (50-year mean) for dates outside the IERS tables (arcsec)
_DEFAULT_POLAR_MOTION_ARCSEC = (0.035, 0.29)


def utc_instant(epoch_utc: Any) -> Time:
    """``epoch_utc`` (a Time, or anything astropy reads as a UTC time) as a UTC ``Time``."""
    if isinstance(epoch_utc, Time):
        epoch = epoch_utc
    else:
        try:
            epoch = Time(epoch_utc, scale="utc")
        except (ValueError, TypeError):
            raise ValueError(
                f"epoch_utc = {epoch_utc!r} is not a time astropy can read; write an ISO UTC "
                "time such as '1990-02-08T00:00:00'."
            ) from None
    if not epoch.isscalar:
        raise ValueError("epoch_utc must be a single instant, not an array of times.")
    return epoch.utc


def ut1_two_part(times: Time) -> tuple[np.ndarray, np.ndarray]:
    """UT1 as two-part Julian dates, exactly as astropy's transforms obtain it."""
    _offline.use_cached_eop_table()
    try:
        ut1 = times.ut1
    except iers.IERSRangeError as err:  # astropy's own transforms fall back the same way
        warnings.warn(f"{err} Assuming UT1-UTC = 0.", stacklevel=4)
        ut1 = times
    return ut1.jd1, ut1.jd2


def polar_motion_rad(times: Time) -> tuple[np.ndarray, np.ndarray]:
    """Polar motion (xp, yp) in rad from the IERS tables, with astropy's fallback (the
    50-year mean) outside them, so positions match astropy's transforms."""
    _offline.use_cached_eop_table()
    xp, yp, status = iers.earth_orientation_table.get().pm_xy(times, return_status=True)
    xp = np.array(xp.to_value(u.rad), dtype=float, ndmin=1)
    yp = np.array(yp.to_value(u.rad), dtype=float, ndmin=1)
    outside = np.isin(status, (iers.TIME_BEFORE_IERS_RANGE, iers.TIME_BEYOND_IERS_RANGE))
    if np.any(outside):
        xp[outside] = math.radians(_DEFAULT_POLAR_MOTION_ARCSEC[0] / 3600.0)
        yp[outside] = math.radians(_DEFAULT_POLAR_MOTION_ARCSEC[1] / 3600.0)
        warnings.warn(
            "Some campaign times are outside the bundled IERS tables; using the 50-year mean "
            "polar motion there (arcsecond-level error). Update astropy-iers-data for newer "
            "dates.",
            stacklevel=4,
        )
    return xp, yp


class UtcLabeller:
    """UTC ISO labels (milliseconds) for seconds since ``epoch_utc`` up to ``duration_s``,
    without astropy per call (a leap second in the span is checked for)."""

    def __init__(self, epoch_utc: str, duration_s: float):
        epoch = Time(epoch_utc, scale="utc")
        end = epoch + TimeDelta(duration_s, format="sec")
        # A leap second inside the campaign would shift naive datetime arithmetic by 1 s;
        # fall back to astropy then (rare; 1990-02 has none).
        self.leap = abs(((end.tai.mjd - end.mjd) - (epoch.tai.mjd - epoch.mjd)) * 86400.0) > 0.5
        self.epoch = epoch
        self.epoch_dt = epoch.to_datetime()

    def __call__(self, t_s: float) -> str:
        if self.leap:
            return (self.epoch + TimeDelta(t_s, format="sec")).isot
        return (self.epoch_dt + datetime.timedelta(seconds=t_s)).isoformat(timespec="milliseconds")

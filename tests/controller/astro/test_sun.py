"""The Sun's rising and setting (controller.astro.sun) at Green Bank, against the almanac and
astropy's Sun."""

from __future__ import annotations

import numpy as np
import pytest
from astropy import units as u
from astropy.coordinates import AltAz, get_body

from controller.astro.ephemeris import Ephemeris
from controller.astro.site import GREEN_BANK_45FT
from controller.astro.sources import GHIGO1990_SOURCES
from controller.astro.sun import sunrise_times_s, sunset_times_s

DAY_S = 86400.0
EPOCH_1990 = "1990-02-08T00:00:00"


@pytest.fixture(scope="module")
def day_1990() -> Ephemeris:
    return Ephemeris(GREEN_BANK_45FT, EPOCH_1990, DAY_S, GHIGO1990_SOURCES)


@pytest.fixture(scope="module")
def month_1990() -> Ephemeris:
    return Ephemeris(GREEN_BANK_45FT, EPOCH_1990, 30.0 * DAY_S, GHIGO1990_SOURCES)


def test_sunset_and_sunrise_1990(day_1990):
    sets = sunset_times_s(day_1990)
    rises = sunrise_times_s(day_1990)
    assert sets.shape == (1,) and rises.shape == (1,)
    # Green Bank, 8 Feb 1990: sunrise about 07:18 EST (12:18 UT), sunset about 17:50 EST
    assert 12.0 < rises[0] / 3600.0 < 12.6
    assert 22.6 < sets[0] / 3600.0 < 23.1
    # at each event the exact (astropy) Sun is at -0.833 deg; the Sun climbs ~10" per second
    times = day_1990.time(np.concatenate([sets, rises]))
    location = day_1990.site.earth_location()
    sun = get_body("sun", times, location).transform_to(
        AltAz(obstime=times, location=location, pressure=0 * u.hPa)
    )
    assert np.abs(sun.alt.deg + 0.833).max() * 3600.0 < 1.0
    # the geometric centre rises later and sets earlier than the almanac event
    assert sunrise_times_s(day_1990, horizon_deg=0.0)[0] > rises[0] + 120.0
    assert sunset_times_s(day_1990, horizon_deg=0.0)[0] < sets[0] - 120.0


def test_month_has_one_sunset_per_day(month_1990):
    sets = sunset_times_s(month_1990)
    assert sets.size == 30
    assert np.allclose(np.diff(sets), DAY_S, atol=120.0)  # day length changes ~1 min/day

"""The true sky (antsim.world.sky): the ephemeris' positions refracted by the weather present,
scaled by ``refraction_scale``, moved by a source's own offset; the sources near a direction."""

from __future__ import annotations

import math

import numpy as np
import pytest
import simpy

from antsim.scenario import load_scenario
from antsim.world.sky import Sky
from antsim.world.world import World
from controller.astro.refraction import refraction_rad
from controller.astro.site import Weather

ARCSEC = math.pi / 648000.0
#: times into the one-hour quiet world (s) at which the checks look
TIMES_S = np.array([300.0, 1800.0, 3300.0])


@pytest.fixture(scope="module")
def sky(quiet_path):
    """A sky of its own, built from the quiet world's ephemeris, sources and weather."""
    world = World(load_scenario(quiet_path), simpy.Environment())
    return Sky(world.ephemeris, world.sky.sources, world.weather, world.sky.frequency_ghz)


def _vacuum(sky, index):
    return sky.ephemeris.altaz_rad(index, TIMES_S)


def test_the_refraction_present_is_the_weathers_at_the_time(sky):
    az0, el0 = _vacuum(sky, 0)
    az, el = sky.observed_altaz_rad(0, TIMES_S, t_weather_s=1800.0)
    reading = sky.weather.reading(1800.0)
    weather = Weather(reading.temperature_c, reading.pressure_hpa, reading.relative_humidity)
    expected = refraction_rad(el0, weather, frequency_ghz=sky.frequency_ghz)
    assert np.all(expected > 0)
    assert np.array_equal(az, az0)
    assert np.allclose(el - el0, expected, rtol=1e-12, atol=0)


def test_refraction_scale_scales_the_refraction(sky):
    _, el0 = _vacuum(sky, 1)
    _, el1 = sky.observed_altaz_rad(1, TIMES_S)
    try:
        sky.refraction_scale = 0.0
        assert np.array_equal(sky.observed_altaz_rad(1, TIMES_S)[1], el0)
        sky.refraction_scale = 2.0
        assert np.allclose(sky.observed_altaz_rad(1, TIMES_S)[1] - el0, 2 * (el1 - el0),
                           rtol=1e-12, atol=0)
    finally:
        sky.refraction_scale = 1.0


def test_a_sources_own_offset_moves_its_observed_position(sky):
    """An offset of (cross-elevation, elevation) arcsec moves the elevation by the second and
    the azimuth by the first over cos(elevation)."""
    az1, el1 = sky.observed_altaz_rad(2, TIMES_S)
    try:
        sky.position_offset_arcsec[2] = (30.0, -20.0)
        az, el = sky.observed_altaz_rad(2, TIMES_S)
    finally:
        sky.position_offset_arcsec[2] = (0.0, 0.0)
    assert np.allclose(el - el1, -20.0 * ARCSEC, rtol=1e-9, atol=0)
    assert np.allclose((az - az1) * np.cos(el), 30.0 * ARCSEC, rtol=1e-9, atol=0)


def test_the_sources_near_a_direction(sky):
    t_s = 1800.0
    az, el = sky.ephemeris.altaz_rad(np.arange(len(sky.sources)), np.full(len(sky.sources), t_s))
    for i, name in enumerate(sky.names):
        assert sky.index(name) == i
        assert i in sky.nearby(float(az[i]), float(el[i]), t_s, radius_deg=0.1)
    # the antipode of the first source is far from it
    assert 0 not in sky.nearby(float(az[0]) + math.pi, -float(el[0]), t_s, radius_deg=10.0)

"""Tracking jitter (antsim.world.effects.tracking): its rms, its wind and its day factors."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from tests.antsim.world.effects.conftest import (
    ARCSEC,
    _effect,
    _quiet_world,
    _rms,
)


def test_tracking_jitter_rms(quiet):
    """The jitter's rms is the configured rms x (1 + (wind / wind_ref)^2) = 1.09 at the
    scenario's 3 m/s. 20010 one-second samples of an AR(1) with rho = exp(-1/60): the
    relative sampling error of the variance is sqrt(2 (1 + rho^2) / (1 - rho^2) / N) = 7.7%,
    of the rms 3.9%: tolerance 4 x 3.9% = 16%."""
    world = _quiet_world(quiet, [("tracking_jitter", {"xel_rms_arcsec": 5.0,
                                                      "el_rms_arcsec": 8.0,
                                                      "timescale_s": 60.0})])
    jitter = _effect(world, "tracking_jitter")
    el = math.radians(40.0)
    # as the world asks for it: 15-sample integrations back to back (continuous process)
    chunks = [jitter.sample_error(15.0 * i + np.arange(15) + 0.5, el) for i in range(1334)]
    d_az = np.concatenate([c[0] for c in chunks])
    d_el = np.concatenate([c[1] for c in chunks])
    scale = 1.0 + (3.0 / 10.0) ** 2
    assert _rms(d_az * math.cos(el)) / ARCSEC == pytest.approx(5.0 * scale, rel=0.16)
    assert _rms(d_el) / ARCSEC == pytest.approx(8.0 * scale, rel=0.16)


def test_tracking_jitter_is_larger_by_day_by_its_day_factors(quiet):
    """day_el_factor 2, day_xel_factor 1: by day (the Sun above the horizon) the elevation
    wander's rms doubles, the cross-elevation's stays. A day of one-second samples, rho =
    exp(-1/60): each half has ~360 independent values, so each rms is known to ~4% and
    their ratio to ~5.3%; tolerance 4 x 5.3% = 21%."""
    day = dataclasses.replace(quiet, duration_s=86400.0)
    world = _quiet_world(day, [("tracking_jitter", {"xel_rms_arcsec": 5.0,
                                                    "el_rms_arcsec": 8.0, "timescale_s": 60.0,
                                                    "day_el_factor": 2.0})])
    jitter = _effect(world, "tracking_jitter")
    el = math.radians(40.0)
    t = 15.0 * np.arange(5760)[:, None] + np.arange(15) + 0.5
    chunks = [jitter.sample_error(ti, el) for ti in t]
    d_az = np.array([c[0] for c in chunks]) * math.cos(el) / ARCSEC
    d_el = np.array([c[1] for c in chunks]) / ARCSEC
    up = world.sun_el_rad(t[:, 7]) > 0.0
    assert 0.3 < up.mean() < 0.7  # both day and night in the day simulated
    assert _rms(d_el[up]) / _rms(d_el[~up]) == pytest.approx(2.0, rel=0.21)
    assert _rms(d_az[up]) / _rms(d_az[~up]) == pytest.approx(1.0, rel=0.21)

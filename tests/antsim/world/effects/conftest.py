"""Shared by the tests of the effects catalogue: the noise-free world of
``tests/data/scenarios/quiet.toml`` with chosen effects, and the probe's tolerances."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import simpy

from antsim.scenario import EffectSpec, load_scenario
from antsim.world.world import World
from controller.pointing.model import PointingModel

ARCSEC = math.pi / 648000.0
DAY_S = 86400.0


def _effect(world, name):
    (effect,) = [e for e in world.effects if e.name == name]
    return effect


def _rms(x) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


@pytest.fixture(scope="module")
def quiet(quiet_path):
    return load_scenario(quiet_path)


def _quiet_world(quiet, effects=(), model: PointingModel | None = None) -> World:
    scenario = dataclasses.replace(quiet, effects=tuple(EffectSpec(n, p) for n, p in effects))
    if model is not None:
        scenario = dataclasses.replace(scenario, truth_model=model)
    return World(scenario, simpy.Environment())


#: probe tolerance: beam centres from noise-free Gaussian powers are exact to ~1e-4" (see
#: tests/antsim/world/test_world.py); what changes during a scan (source rates, over the ~6 s
#: between the three points of an axis) shifts a centre by up to ~0.02", hence 0.03" for
#: time-dependent effects and 0.01" for static ones
STATIC_ARCSEC = 0.01


MOVING_ARCSEC = 0.03


def _source_motion_arcsec(world, index, t_s, dt_s):
    """True (xel, el) motion of source ``index`` from t to t + dt (arcsec)."""
    az, el = world.sky.observed_altaz_rad(index, np.array([t_s, t_s + dt_s]), 0.0)
    d_az = (az[1] - az[0] + math.pi) % (2 * math.pi) - math.pi
    return d_az * math.cos(el[0]) / ARCSEC, (el[1] - el[0]) / ARCSEC

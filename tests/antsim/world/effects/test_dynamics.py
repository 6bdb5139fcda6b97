"""Clock error, servo lag and backlash (antsim.world.effects.dynamics), measured in the
noise-free world through the protocol only (``probe`` fixture in tests/conftest.py: beam
centre from three 1-s integrations per axis).

Probe sign: ``center`` is the encoder offset from the commanded trajectory at which the power
peaks. An effect that makes the beam trail the command by ``d`` (indicated minus true = +d)
gives center = +d; a trajectory that leads the source by ``d`` gives center = -d.
"""

from __future__ import annotations

import pytest

from antsim.world.effects import EFFECTS, PointingState
from tests.antsim.world.effects.conftest import (
    ARCSEC,
    MOVING_ARCSEC,
    _quiet_world,
    _source_motion_arcsec,
)


@pytest.mark.parametrize("index", [0, 1])
def test_clock_error_is_source_rate_times_offset(quiet, probe, index):
    """A clock 10 s fast: the controller commands where the source will be in 10 s, so the
    pointing error is the source's rate x 10 s and the beam centre lies that far behind the
    trajectory (centre = -rate x offset)."""
    probe_beam, source_trajectory = probe
    offset_s = 10.0
    world = _quiet_world(quiet, [("clock_error", {"offset_s": offset_s})])
    result = probe_beam(world, index, source_trajectory(world, index))
    for r in result.values():
        for axis in range(2):
            t = r["times"][axis]
            rate = _source_motion_arcsec(world, index, t - 0.5, 1.0)[axis]  # arcsec per s
            # rate x offset is the linear term of the displacement; its curvature adds
            # acc x offset^2 / 2 (0.05" for Cygnus A at 77 deg), allowed for here
            acc = (_source_motion_arcsec(world, index, t, offset_s)[axis]
                   - _source_motion_arcsec(world, index, t - offset_s, offset_s)[axis]
                   ) / offset_s**2
            assert abs(rate * offset_s) > 5.0  # a real effect on this axis
            assert r["center"][axis] == pytest.approx(
                -rate * offset_s, abs=MOVING_ARCSEC + 0.5 * abs(acc) * offset_s**2)
            # exactly: the displacement of the source over the 10 s
            moved = _source_motion_arcsec(world, index, t, offset_s)[axis]
            assert r["center"][axis] == pytest.approx(-moved, abs=MOVING_ARCSEC)


@pytest.mark.parametrize("index", [0, 1])
def test_servo_lag_is_lag_times_rate(quiet, probe, index):
    """A 2-s servo lag: the beam trails the command by lag x rate, so the power peaks that
    far ahead of the trajectory (centre = +lag x rate). Measured with one-sample integrations
    (the probe's), which also checks that such an integration still sees the axis rate."""
    probe_beam, source_trajectory = probe
    lag = 2.0
    world = _quiet_world(quiet, [("servo_lag", {"lag_s": lag})])
    result = probe_beam(world, index, source_trajectory(world, index))
    for r in result.values():
        for axis in range(2):
            rate = _source_motion_arcsec(world, index, r["times"][axis] - 0.5, 1.0)
            assert abs(rate[axis] * lag) > 1.0
            assert r["center"][axis] == pytest.approx(lag * rate[axis], abs=MOVING_ARCSEC)


def test_backlash_follows_the_approach_direction():
    effect = EFFECTS["backlash"](az_arcsec=10.0, el_arcsec=6.0)
    for sign in (1.0, -1.0):
        state = PointingState(t_s=0.0, az_rad=1.0, el_rad=0.5, approach_az=sign,
                              approach_el=-sign)
        d_az, d_el = effect.pointing_error(state)
        # half the dead band, signed by the approach; 1e-12: float rounding of a conversion
        assert d_az / ARCSEC == pytest.approx(5.0 * sign, rel=1e-12)
        assert d_el / ARCSEC == pytest.approx(-3.0 * sign, rel=1e-12)

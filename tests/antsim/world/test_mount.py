"""The mount as simpy processes: slew and offset durations, cable wrap, elevation limits.

Expected durations come from rest-to-rest kinematics written out here from first principles
(not from ``antsim.world.mount.move_time_s``): an axis accelerates at ``a`` up to at most ``v``,
cruises, and brakes at ``a``. If the distance ``d`` is shorter than the distance needed to
reach full speed and stop again, ``v^2 / a``, the profile is triangular and takes
``2 sqrt(d / a)``; otherwise it takes ``2 v / a`` accelerating and braking plus
``(d - v^2 / a) / v`` cruising. Both axes move at once, so the longer one decides, and the
mount then settles for ``settle_s``. The axis figures are those of ``ghigo1990.toml``
(assumptions from the VLBA analogue): azimuth 1.5 deg/s and 0.5 deg/s^2 (ramp distance
4.5 deg), elevation 0.5 deg/s and 0.5 deg/s^2 (ramp distance 0.5 deg), settle 4 s.

Tolerance on durations: 1e-9 s, i.e. float rounding of sums of seconds (simpy adds the
timeout to ``env.now`` exactly); for moving targets the slew time is the fixed point of
``T = t(|target(now + T) - start|)``, and the check allows 1e-6 s for its iteration.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import simpy

from antsim.scenario import load_scenario
from antsim.world.mount import AxisConfig, Mount, MountConfig
from antsim.world.world import World
from controller.protocol import AntennaError

CONFIG = MountConfig(kind="altaz", az=AxisConfig(1.5, 0.5, -90.0, 450.0),
                     el=AxisConfig(0.5, 0.5, 5.0, 90.0), settle_s=4.0, wrap_margin_s=3600.0)
#: simpy adds timeouts exactly; sums of a few float seconds round at ~1e-13 s
TIME_TOL_S = 1e-9
#: moving targets: the mount iterates the arrival time 4 times, contracting by rate/speed
#: (< 0.01 here) each time, so the fixed point is met to far better than a microsecond
MOVING_TOL_S = 1e-6


def kinematic_s(distance_deg: float, speed: float, accel: float) -> float:
    """Rest-to-rest time of one axis (s): triangular or trapezoidal speed profile."""
    d = abs(distance_deg)
    t_ramp = speed / accel  # time to reach full speed
    d_ramp = 0.5 * accel * t_ramp**2  # distance covered meanwhile
    if d <= 2 * d_ramp:
        return 2.0 * math.sqrt(d / accel)  # accelerate over d/2, brake over d/2
    return 2 * t_ramp + (d - 2 * d_ramp) / speed


def slew_s(d_az: float, d_el: float, config: MountConfig = CONFIG) -> float:
    return max(kinematic_s(d_az, config.az.speed_deg_s, config.az.accel_deg_s2),
               kinematic_s(d_el, config.el.speed_deg_s, config.el.accel_deg_s2))


def fixed(az_deg: float, el_deg: float):
    """A trajectory that stays at one (az, el)."""
    return lambda t: (np.full(np.shape(t), az_deg % 360.0), np.full(np.shape(t), el_deg))


def moving(az0_deg: float, el_deg: float, az_rate_deg_s: float):
    return lambda t: ((az0_deg + az_rate_deg_s * np.asarray(t, dtype=float)) % 360.0,
                      np.full(np.shape(t), el_deg))


def run(env, generator):
    """Run a mount process to completion; its return value."""
    process = env.process(generator)
    env.run(until=process)
    return process.value


def test_kinematics_helper_is_continuous_at_the_ramp_distance():
    # the two branches meet at d = v^2 / a (checks the helper, not the mount)
    for v, a in ((1.5, 0.5), (0.5, 0.5)):
        d = v * v / a
        assert kinematic_s(d * (1 - 1e-12), v, a) == pytest.approx(kinematic_s(d, v, a))
        assert kinematic_s(d, v, a) == pytest.approx(2 * v / a)


# (start az, el) -> (target az, el); parked at (180, 45). Distances are chosen on both sides
# of each axis's ramp distance (az 4.5 deg, el 0.5 deg).
MOVES = {
    "az short (triangular)": (182.0, 45.0),     # 2 deg az: 2 sqrt(2/0.5) = 4 s
    "az long (trapezoidal)": (280.0, 45.0),     # 100 deg az: 100/1.5 + 3 = 69.67 s
    "el short (triangular)": (180.0, 45.2),     # 0.2 deg el: 2 sqrt(0.4) = 1.26 s
    "el long (trapezoidal)": (180.0, 75.0),     # 30 deg el: 30/0.5 + 1 = 61 s
    "both, el decides": (190.0, 20.0),          # az 10 deg: 9.67 s; el 25 deg: 51 s
    "both, az decides": (300.0, 40.0),          # az 120 deg: 83 s; el 5 deg: 11 s
}


@pytest.mark.parametrize("name", list(MOVES))
def test_slew_duration_is_kinematic_plus_settle(name):
    az, el = MOVES[name]
    env = simpy.Environment()
    mount = Mount(env, CONFIG, park_az_deg=180.0, park_el_deg=45.0)
    duration = run(env, mount.track(fixed(az, el)))
    expected = slew_s(az - 180.0, el - 45.0) + CONFIG.settle_s
    assert env.now == pytest.approx(expected, abs=TIME_TOL_S)
    assert duration == pytest.approx(expected, abs=TIME_TOL_S)
    assert mount.on_track
    assert mount.current_deg() == pytest.approx((az, el), abs=1e-9)


@pytest.mark.parametrize("d_az,d_el", [(0.05, 0.0), (10.0, 0.0), (0.0, 0.1), (0.0, 2.0),
                                       (0.2, 0.3)])
def test_offset_duration_is_kinematic_plus_settle(d_az, d_el):
    env = simpy.Environment()
    mount = Mount(env, CONFIG)
    run(env, mount.track(fixed(200.0, 50.0)))
    t0 = env.now
    duration = run(env, mount.set_offset(d_az, d_el))
    expected = slew_s(d_az, d_el) + CONFIG.settle_s
    assert env.now - t0 == pytest.approx(expected, abs=TIME_TOL_S)
    assert duration == pytest.approx(expected, abs=TIME_TOL_S)
    assert mount.current_deg() == pytest.approx((200.0 + d_az, 50.0 + d_el), abs=1e-9)
    # and back: the move is measured from the current offset, not from the trajectory
    t1 = env.now
    run(env, mount.set_offset(0.0, 0.0))
    assert env.now - t1 == pytest.approx(expected, abs=TIME_TOL_S)


def test_slew_to_a_moving_target_meets_it_on_arrival():
    """The slew time T satisfies T = t(target(T) - start): the mount meets the target where
    it will be, not where it was."""
    env = simpy.Environment()
    mount = Mount(env, CONFIG, park_az_deg=180.0, park_el_deg=45.0)
    rate = 0.01  # deg/s: a fast-moving target (the sidereal rate is 0.004 deg/s)
    run(env, mount.track(moving(250.0, 45.0, rate)))
    slew = env.now - CONFIG.settle_s
    expected = kinematic_s(250.0 + rate * slew - 180.0, 1.5, 0.5)
    assert slew == pytest.approx(expected, abs=MOVING_TOL_S)
    # a planner aiming at the starting position would be rate * T = 0.5 deg short
    assert slew - kinematic_s(70.0, 1.5, 0.5) > 0.3


def test_through_the_protocol_track_and_offset_take_the_kinematic_time(quiet_path):
    world = World(load_scenario(quiet_path), simpy.Environment())
    env, antenna = world.env, world.antenna
    durations = []

    def observe():
        durations.append((yield antenna.track(fixed(150.0, 30.0))))
        t0 = env.now
        yield antenna.set_offset(0.5, -0.25)
        durations.append(env.now - t0)

    env.run(until=env.process(observe()))
    mount = world.scenario.mount  # parked at (180, 45) like every simulated mount
    assert durations[0] == pytest.approx(slew_s(-30.0, -15.0, mount) + mount.settle_s,
                                         abs=TIME_TOL_S)
    assert durations[1] == pytest.approx(slew_s(0.5, 0.25, mount) + mount.settle_s,
                                         abs=TIME_TOL_S)
    assert antenna.encoder_deg() == pytest.approx((150.5, 29.75), abs=1e-9)


# ---------------------------------------------------------------------------------------------
# cable wrap: encoder azimuth -90..450 deg, so azimuths 0..90 and 270..360 exist on two turns
def test_wrap_takes_the_quicker_turn():
    env = simpy.Environment()
    mount = Mount(env, CONFIG, park_az_deg=420.0, park_el_deg=45.0)
    run(env, mount.track(fixed(80.0, 45.0)))  # az 80 = encoder 80 or 440
    assert mount.current_deg()[0] == pytest.approx(440.0, abs=1e-9)
    assert env.now == pytest.approx(slew_s(20.0, 0.0) + CONFIG.settle_s, abs=TIME_TOL_S)


def test_wrap_keeps_the_tracking_margin():
    """Target at az 80 moving +0.01 deg/s: on the quick turn (440) it would hit the 450 limit
    within the hour of ``wrap_margin_s``, so the mount takes the long way to encoder ~80."""
    env = simpy.Environment()
    mount = Mount(env, CONFIG, park_az_deg=420.0, park_el_deg=45.0)
    rate = 0.01
    run(env, mount.track(moving(80.0, 45.0, rate)))
    slew = env.now - CONFIG.settle_s
    az_arrive = 80.0 + rate * slew
    assert mount.current_deg()[0] == pytest.approx(az_arrive + rate * CONFIG.settle_s,
                                                   abs=1e-6)
    assert slew == pytest.approx(kinematic_s(420.0 - az_arrive, 1.5, 0.5), abs=MOVING_TOL_S)
    assert az_arrive + rate * CONFIG.wrap_margin_s <= CONFIG.az.max_deg
    # ...whereas on the quick turn it would reach the limit within the margin
    assert az_arrive + 360.0 + rate * CONFIG.wrap_margin_s > CONFIG.az.max_deg

    # without the margin requirement the quick turn is taken
    env = simpy.Environment()
    no_margin = MountConfig(CONFIG.kind, CONFIG.az, CONFIG.el, CONFIG.settle_s, 0.0)
    mount = Mount(env, no_margin, park_az_deg=420.0, park_el_deg=45.0)
    run(env, mount.track(moving(80.0, 45.0, rate)))
    assert mount.current_deg()[0] > 360.0


# ---------------------------------------------------------------------------------------------
def test_track_below_the_elevation_limit_fails():
    env = simpy.Environment()
    mount = Mount(env, CONFIG)
    with pytest.raises(AntennaError, match="elevation"):
        run(env, mount.track(fixed(100.0, CONFIG.el.min_deg - 0.5)))
    assert not mount.on_track


def test_protocol_track_below_the_limit_and_bad_commands_fail(quiet_path):
    world = World(load_scenario(quiet_path), simpy.Environment())
    env, antenna = world.env, world.antenna
    with pytest.raises(AntennaError):
        antenna.set_offset(0.1, 0.0)  # no trajectory yet
    with pytest.raises(AntennaError):
        antenna.integrate(0.0)
    with pytest.raises(AntennaError):
        antenna.integrate(-15.0)
    with pytest.raises(AntennaError, match="elevation"):
        env.run(until=antenna.track(fixed(100.0, 2.0)))

"""The Sun heating the structure (antsim.world.effects.heating): the forcing of each member
pair from the Sun's direction, the dish's shadow on the feed legs, and the relaxation of the
differences with the heat balance's time constants, in a world whose Sun, wind and air are
held fixed (so each expected value is analytic)."""

from __future__ import annotations

import dataclasses
import math
from types import SimpleNamespace

import numpy as np
import pytest
import simpy

from antsim.scenario import EffectSpec, load_scenario
from antsim.world import heat
from antsim.world.effects import EFFECTS, PointingState
from antsim.world.effects.heating import PARTS, _leg_lit, member_forcings
from antsim.world.effects.thermal import GRID_STEP_S
from antsim.world.structure import Structure
from antsim.world.world import World
from controller.astro.sun import sunset_times_s
from tests.antsim.world.effects.conftest import (
    _effect,
    _rms,
)

S = Structure()
SUN_EL, SUN_AZ = math.radians(30.0), math.radians(180.0)  # due south, 30 deg up


def _vec(az, el):
    return np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])


def _forcing(sun, az, el, absorbed=200.0, h_out=12.0, h_plate=17.0):
    return member_forcings(absorbed, h_out, h_plate, *sun, az, el, S)


def test_the_yoke_faces_see_the_horizontal_sun():
    """Sun at the horizon straight ahead: front minus back is alpha E / h_plate and the arms
    are equal; Sun on the right: the right arm's outer face takes it, the arm's mean a
    quarter of that; neither direction touches the other difference."""
    az = math.radians(40.0)
    ahead = _forcing(_vec(az, 0.0), az, math.radians(30.0))
    assert ahead[PARTS.index("yoke_fb")] == pytest.approx(200.0 / 17.0)
    assert abs(ahead[PARTS.index("yoke_rl")]) < 1e-12
    right = _forcing(_vec(az + math.pi / 2, 0.0), az, math.radians(30.0))
    assert right[PARTS.index("yoke_rl")] == pytest.approx(0.25 * 200.0 / 17.0)
    assert abs(right[PARTS.index("yoke_fb")]) < 1e-12


def test_the_legs_see_the_sun_over_their_silhouette():
    """Sun along the boresight: every leg shows the same silhouette, no difference; Sun in
    front and above (45 deg between the boresight and the aperture's up): the lower leg,
    which climbs from the lower rim towards the Sun, lies nearly along its rays and shows
    little, the upper one lies across them and is the warmer: tube (sqrt(1 - a^2) -
    sqrt(1 - c^2)) with a, c the cosines to the two legs; Sun straight behind the dish:
    every leg in its shadow."""
    az, el = math.radians(100.0), math.radians(40.0)
    b = _vec(az, el)
    up = np.array([-math.sin(el) * math.cos(az), -math.sin(el) * math.sin(az), math.cos(el)])
    on_axis = _forcing(b, az, el)
    assert abs(on_axis[0]) < 1e-12 and abs(on_axis[1]) < 1e-12
    sun = (b + up) / math.sqrt(2.0)
    phi = S.leg_angle_rad
    u_upper = math.cos(phi) * b - math.sin(phi) * up
    u_lower = math.cos(phi) * b + math.sin(phi) * up
    tube = 200.0 / (math.pi * 12.0)
    expected = tube * (math.sqrt(1 - (sun @ u_upper) ** 2) - math.sqrt(1 - (sun @ u_lower) ** 2))
    got = _forcing(sun, az, el)
    assert got[0] == pytest.approx(expected, rel=1e-12) and expected > 1.0
    assert abs(got[1]) < 1e-12
    behind = _forcing(-b, az, el)
    np.testing.assert_allclose(behind[:2], 0.0, atol=1e-12)


def test_the_dish_shadow_on_the_legs_against_ray_tracing():
    """The lit fraction of each leg against a plain ray-disc test in three dimensions (2000
    points along each leg, each ray towards the Sun meeting the aperture disc at the rim's
    depth or not: the fraction to 1/2000), for 200 random Suns behind the dish."""
    rng = np.random.default_rng(5)
    r, zr, f = 0.5 * S.diameter_m, S.rim_depth_m, S.focal_length_m
    feet = [np.array([0.0, 1.0, 0.0]), np.array([0.0, -1.0, 0.0]), np.array([0.0, 0.0, 1.0]),
            np.array([0.0, 0.0, -1.0])]  # (boresight, up, right) coordinates
    t = (np.arange(2000) + 0.5) / 2000
    for _ in range(200):
        s = rng.normal(size=3)
        s /= np.linalg.norm(s)
        if s[0] >= 0.0:
            s[0] = -s[0]  # behind the dish
        lit = _leg_lit(s[0], s[1], s[2], S)
        for i, foot in enumerate(feet):
            start = r * foot + zr * np.array([1.0, 0.0, 0.0])
            end = f * np.array([1.0, 0.0, 0.0])
            p = start + t[:, None] * (end - start)
            lam = (zr - p[:, 0]) / s[0]  # along each ray to the rim's plane
            q = p + lam[:, None] * s
            shaded = np.mean(np.hypot(q[:, 1], q[:, 2]) < r)
            assert lit[i] == pytest.approx(1.0 - shaded, abs=1e-3), (s, i)


def _world(wind_m_s=3.0, air_c=0.0, duration_s=6 * 3600.0, sun_az=SUN_AZ):
    """The parts of a world the effect's start asks for: a fixed Sun (30 deg up, due south
    unless ``sun_az`` says otherwise), a steady wind and air, a site at 800 m."""
    weather = SimpleNamespace(daily_curve_c=lambda t: np.full(np.shape(t), air_c),
                              wind_m_s=lambda t: np.full(np.shape(t), wind_m_s))
    return SimpleNamespace(
        duration_s=duration_s, weather=weather,
        scenario=SimpleNamespace(site=SimpleNamespace(height_m=800.0)),
        sun_el_rad_periodic=lambda t: np.full(np.shape(t), SUN_EL),
        sun_az_rad=lambda t: np.full(np.shape(t), sun_az),
        air_temperature_c=lambda t: np.full(np.shape(t), air_c))


def _started(world, **params):
    effect = EFFECTS["thermal"](**{"cloud_modulation": 0.0, **params})
    effect.start(world, np.random.default_rng(0))
    return effect


def test_the_yoke_relaxes_with_rho_c_d_over_h_after_a_slew():
    """The antenna faces the Sun, then turns its back on it: the yoke's front-minus-back
    difference relaxes from its forcing towards the new one with tau = rho c d / h, h the
    wind's convection plus radiation plus the inside of the box (15 mm of steel in 3 m/s of
    wind: 38 minutes). One time constant after the slew it has covered 1 - 1/e of the way
    (to rounding: the state advances exactly)."""
    effect = _started(_world())
    p = effect.p
    h_plate = (float(heat.convective_coefficient_w_m2k(3.0))
               + float(heat.radiative_coefficient_w_m2k(p["emissivity"], 273.15))
               + p["inside_w_m2k"])
    tau = p["heat_capacity_j_m3k"] * p["yoke_plate_m"] / h_plate
    assert 2000.0 < tau < 2600.0
    el = math.radians(45.0)
    t0 = 3600.0
    effect.pointing_error(PointingState(t0, SUN_AZ, el))  # facing the Sun: starts there
    start = effect._parts[PARTS.index("yoke_fb")]
    beam = float(heat.direct_normal_irradiance_w_m2(SUN_EL, 800.0))
    assert start == pytest.approx(p["absorptivity"] * beam * math.cos(SUN_EL) / h_plate)
    effect.pointing_error(PointingState(t0 + tau, 0.0, el))  # facing north since t0
    after = effect._parts[PARTS.index("yoke_fb")]
    target = -start
    assert after == pytest.approx(target + (start - target) * math.exp(-1.0), rel=1e-9)


def test_the_pedestal_leans_away_from_the_sun():
    """With the Sun due south for hours the pedestal's south face settles alpha E cos h / h
    warmer than the north (north minus south negative, east minus west nil), and the
    azimuth axis tilts north (away from the Sun) by the geometry's arcsec per kelvin of
    that difference."""
    effect = _started(_world(duration_s=4 * 3600.0))
    p = effect.p
    h_plate = (float(heat.convective_coefficient_w_m2k(3.0))
               + float(heat.radiative_coefficient_w_m2k(p["emissivity"], 273.15))
               + p["inside_w_m2k"])
    beam = float(heat.direct_normal_irradiance_w_m2(SUN_EL, 800.0))
    settled = -p["absorptivity"] * beam * math.cos(SUN_EL) / h_plate
    assert effect.pedestal_n_k[-1] == pytest.approx(settled, rel=1e-6)  # a day of spin-up
    assert abs(effect.pedestal_e_k[-1]) < 1e-9 * abs(settled)
    tilt_n = effect._tilt_n_arcsec[-1]
    assert tilt_n == pytest.approx(-effect.k["pedestal_tilt"] * settled) and tilt_n > 0.0


def test_the_pedestal_leans_away_from_a_morning_sun_too():
    """The same with the Sun due east: the east face is the warmer and the axis tilts west
    (negative towards the east) by the same arcsec per kelvin: the pedestal bends away from
    its warmer side whichever way that lies."""
    effect = _started(_world(duration_s=4 * 3600.0, sun_az=math.radians(90.0)))
    east = effect.pedestal_e_k[-1]
    assert east > 0.0 and abs(effect.pedestal_n_k[-1]) < 1e-9 * east
    tilt_e = effect._tilt_e_arcsec[-1]
    assert tilt_e == pytest.approx(-effect.k["pedestal_tilt"] * east) and tilt_e < 0.0


def _tilted_axis_errors(tilt_n_arcsec, tilt_e_arcsec, az, el):
    """Indicated minus true (dA cos E, dE) arcsec of a mount whose azimuth axis (its pole)
    is tilted towards north and east by the given angles, by rotating the direction it
    indicates out of the tilted frame (no small-angle algebra)."""
    from scipy.spatial.transform import Rotation

    tilt = np.radians(np.array([tilt_n_arcsec, tilt_e_arcsec]) / 3600.0)
    up = np.array([tilt[0], tilt[1], 1.0])  # north, east, up
    up /= np.linalg.norm(up)
    axis = np.cross([0.0, 0.0, 1.0], up)
    angle = math.asin(np.linalg.norm(axis))
    true = Rotation.from_rotvec(axis / np.linalg.norm(axis) * angle).apply(_vec(az, el))
    true_az, true_el = math.atan2(true[1], true[0]), math.asin(true[2])
    d_az = (az - true_az + math.pi) % (2.0 * math.pi) - math.pi
    return math.degrees(d_az) * 3600.0 * math.cos(el), math.degrees(el - true_el) * 3600.0


@pytest.mark.parametrize("tilt_n, tilt_e", [(40.0, 0.0), (0.0, 40.0), (-25.0, 30.0)])
def test_the_tilt_turns_the_beam_as_a_tilted_azimuth_axis(tilt_n, tilt_e):
    """The effect's errors for the axis' tilts towards north and east are those of a frame
    so tilted (to 0.1": the second order, i^2 tan E, is 0.04" for 40" at 80 deg; a flipped
    sign is off by twice the tilt): pole north, the northern horizon
    tips down and a northern source is indicated too high (dE = i cos A, dA cos E = i sin A
    sin E). A flipped sign in either direction fails at the first azimuth."""
    effect = _started(_world())
    parts = np.zeros(4)
    for az_deg in (0.0, 60.0, 135.0, 210.0, 300.0):
        for el_deg in (15.0, 50.0, 80.0):
            az, el = math.radians(az_deg), math.radians(el_deg)
            d_az, d_el = effect._errors(parts, tilt_n, tilt_e, az, el)
            got = (d_az * math.cos(el) * 3600.0 * 180.0 / math.pi,
                   d_el * 3600.0 * 180.0 / math.pi)
            want = _tilted_axis_errors(tilt_n, tilt_e, az, el)
            assert got == pytest.approx(want, abs=0.1), (az_deg, el_deg)


def test_the_sensors_tilt_terms_are_the_heatings_tilt():
    """The controller's pedestal terms with the sensors' truth (TNPNS = -c, TWPEW = c, and
    TTILT = c alone: towards the cooler side) give the heating's tilt errors for the same
    north-minus-south and east-minus-west differences, so a fit of sensors recovers the
    world's own geometry with one sign convention in both directions."""
    from antsim.world.sensors import thermal_truth
    from controller.pointing.model import PointingModel

    effect = _started(_world())
    c = effect.k["pedestal_tilt"]
    truth = thermal_truth({})
    assert (truth["TNPNS"], truth["TWPEW"], truth["TTILT"]) == pytest.approx((-c, c, c))
    rng = np.random.default_rng(3)
    az = rng.uniform(0.0, 2.0 * math.pi, 40)
    el = rng.uniform(math.radians(12.0), math.radians(80.0), 40)
    north, east = rng.normal(0.0, 3.0, 40), rng.normal(0.0, 3.0, 40)  # K
    zero = np.zeros(40)
    aux = {"pedestal_north": (north, north), "pedestal_south": (zero, zero),
           "pedestal_east": (east, east), "pedestal_west": (zero, zero)}
    d_az, d_el = effect._errors(np.zeros((4, 40)), -c * north, -c * east, az, el)
    for model in (PointingModel(["TNPNS", "TWPEW"], [truth["TNPNS"], truth["TWPEW"]]),
                  PointingModel(["TTILT"], [truth["TTILT"]])):
        m_az, m_el = model.offset_rad(az, el, aux=aux)
        np.testing.assert_allclose(m_az, d_az, atol=1e-12)
        np.testing.assert_allclose(m_el, d_el, atol=1e-12)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_thermal_elevation_excursions_larger_by_day_than_by_night(ghigo_path, seed):
    """The heating's elevation error with every member at its equilibrium, for a dish facing
    south-east at 40 deg, over the 1990 scenario's minute grid: by day (Sun above the
    horizon) its rms is more than three times the night's (measured: 20-22" by day, 3-4"
    at night, the pedestal's and yoke's relaxation after sunset), and it moves by day."""
    world = World(load_scenario(ghigo_path), simpy.Environment(), seed=seed)
    thermal = _effect(world, "thermal")
    t = np.arange(0.0, world.duration_s, 60.0)
    _, el = thermal.equilibrium_errors_arcsec(t, math.radians(135.0), math.radians(40.0))
    day = world.sun_el_rad(t) > 0.0
    assert 0.2 < day.mean() < 0.6  # both halves well sampled (Feb: ~10.6 h of day)
    assert _rms(el[day]) > 3.0 * _rms(el[~day])
    assert np.std(el[day]) > 2.0 * np.std(el[~day])  # the excursion, not only the level


def test_the_pointing_per_kelvin_follows_the_yoke_geometry_alone(ghigo_path):
    """Doubling the yoke arms' height doubles their bow and roll per kelvin and nothing
    else: an afternoon instant's error, less the same instant's with the yoke's
    coefficients all but zeroed by arms a million metres deep and apart, scales by two (to
    1e-5: that yoke keeps 3e-6 of the coefficients; the same differences, one product),
    and the legs' and pedestal's per kelvin are unchanged."""
    base = load_scenario(ghigo_path)

    def effect(**params):
        effects = tuple(EffectSpec(e.name, {**e.params, **params}) if e.name == "thermal"
                        else e for e in base.effects)
        world = World(dataclasses.replace(base, effects=effects), simpy.Environment(), seed=3)
        return _effect(world, "thermal")

    one, two = effect(yoke_height_m=3.0), effect(yoke_height_m=6.0)
    for name in ("legs_el", "legs_xel", "pedestal_tilt"):
        assert two.k[name] == one.k[name]
    for name in ("yoke_bow", "yoke_roll"):
        assert two.k[name] == pytest.approx(2.0 * one.k[name], rel=1e-12)
    state = PointingState(3 * 3600.0, math.radians(130.0), math.radians(30.0))
    e_one = np.array(one.pointing_error(dataclasses.replace(state)))
    e_two = np.array(two.pointing_error(dataclasses.replace(state)))
    without = effect(yoke_height_m=3.0, yoke_depth_m=1e6, yoke_separation_m=1e6)
    e_none = np.array(without.pointing_error(dataclasses.replace(state)))
    assert np.all(np.abs(e_one - e_none) > 1e-7)  # the yoke's share is there (> 0.02")
    np.testing.assert_allclose(e_two - e_none, 2.0 * (e_one - e_none), rtol=1e-5)


def test_the_pedestal_relaxes_after_sunset_with_its_time_constant(ghigo_path):
    """After the geometric sunset the pedestal's forcing is zero and its north-south
    difference decays with tau = rho c d / h of the evening's wind (h changes a little as
    the wind drops: the decay over one mean time constant is e^-1 to 2%)."""
    world = World(load_scenario(ghigo_path), simpy.Environment())
    thermal = _effect(world, "thermal")
    (t_set,) = sunset_times_s(world.ephemeris, horizon_deg=0.0)
    grid = thermal.t_grid
    i0 = int(np.searchsorted(grid, t_set)) + 1
    tau = thermal.p["heat_capacity_j_m3k"] * thermal.p["pedestal_wall_m"] / thermal._h_plate
    n = round(float(np.mean(tau[i0:i0 + 120])) / GRID_STEP_S)
    start, later = thermal.pedestal_n_k[i0], thermal.pedestal_n_k[i0 + n]
    assert abs(start) > 1.0  # a real difference to decay from (K)
    assert later / start == pytest.approx(math.exp(-1.0), rel=0.02)

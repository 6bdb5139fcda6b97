"""The physical-effects catalogue: thermal model, sunset drift, and every registered effect.

* Thermal (``ThermalEffect`` in the 1990 scenario): elevation excursions larger by day than by
  night; the pointing per kelvin follows the geometry; after sunset the pedestal's difference
  decays with its heat balance's time constant.
* ``SunsetDrift``: a (1 - 1/e) one time constant after sunset; Fomalont's 1' in the 4 hours
  after sunset is expressible in a scenario.
* Each registered effect: a scenario with it loads and runs, and its truth appears in
  ``World.truth()`` (the truth.json content); plus one physical check where cheap, measured in
  the noise-free world of ``tests/data/scenarios/quiet.toml`` through the protocol only
  (``probe`` fixture in conftest.py: beam centre from three 1-s integrations per axis).

Probe sign: ``center`` is the encoder offset from the commanded trajectory at which the power
peaks. An effect that makes the beam trail the command by ``d`` (indicated minus true = +d)
gives center = +d; a trajectory that leads the source by ``d`` gives center = -d.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import simpy

from antsim.scenario import EffectSpec, load_scenario
from antsim.simulate.runner import simulate
from antsim.world.effects import EFFECTS, PointingState
from antsim.world.effects.optics import ExactTiltCollimation
from antsim.world.effects.thermal import GRID_STEP_S
from antsim.world.world import World
from controller.astro.sun import sunset_times_s
from controller.pointing.model import PointingModel

ARCSEC = math.pi / 648000.0
FOUR_LN2 = 4.0 * math.log(2.0)
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


# =============================================================================================
# thermal
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


@pytest.fixture
def ghigo_24h_with(ghigo_text, write_scenario):
    """The 24-hour 1990 scenario with an extra [[truth.effects]] table appended."""

    def make(extra: str):
        return load_scenario(write_scenario(ghigo_text + "\n" + extra))

    return make


def test_sunset_drift_one_time_constant_after_sunset(ghigo_24h_with):
    """a (1 - e^-1) one tau after sunset, counted from the level at sunset (the previous
    night's drift has relaxed by e^-(10.6 h / tau) = 0.1% by then, the 'residual'). The
    model switches its night indicator on the 60-s grid, so its exponential starts up to one
    grid step before the exact sunset: tolerance a e^-1 (60 s / tau) = 0.4% of a."""
    a, tau = 60.0, 5400.0
    scenario = ghigo_24h_with(f'[[truth.effects]]\neffect = "sunset_drift"\n'
                              f"amplitude_arcsec = {a}\ntau_s = {tau}\n")
    world = World(scenario, simpy.Environment())
    drift = _effect(world, "sunset_drift")
    (t_set,) = sunset_times_s(world.ephemeris, horizon_deg=0.0)
    e0 = float(drift.error_arcsec(t_set))
    assert 0.0 <= e0 < 0.002 * a  # the residual of the previous night
    expected = a - (a - e0) * math.exp(-1.0)  # = a (1 - e^-1) for e0 = 0
    tolerance = a * math.exp(-1.0) * GRID_STEP_S / tau
    assert float(drift.error_arcsec(t_set + tau)) == pytest.approx(expected, abs=tolerance)
    assert float(drift.error_arcsec(t_set + tau)) == pytest.approx(a * (1 - math.exp(-1)),
                                                                   abs=tolerance + 0.002 * a)
    # it is an elevation error only, and the world's error sum includes it
    state = PointingState(t_s=t_set + tau, az_rad=1.0, el_rad=0.7)
    d_az, d_el = drift.pointing_error(state)
    assert d_az == 0.0
    # the same number through a unit conversion: float rounding only
    assert d_el / ARCSEC == pytest.approx(float(drift.error_arcsec(t_set + tau)), rel=1e-12)


def test_fomalont_one_arcmin_in_four_hours_after_sunset_is_expressible(ghigo_24h_with):
    """Fomalont (1973): elevation changed systematically by 1.0' in the 4 h after sunset.
    With tau = 1.5 h, a = 60" / (1 - e^(-4 / 1.5)) = 64.48" gives exactly that. Tolerance
    0.5" (1% of 1'): the 0.1% residual at sunset and the one-grid-step start (a e^-(8/3)
    60 s / tau = 0.05") are far inside it."""
    tau = 5400.0
    a = 60.0 / (1.0 - math.exp(-4 * 3600.0 / tau))
    scenario = ghigo_24h_with(f'[[truth.effects]]\neffect = "sunset_drift"\n'
                              f"amplitude_arcsec = {a:.4f}\ntau_s = {tau}\n")
    world = World(scenario, simpy.Environment())
    drift = _effect(world, "sunset_drift")
    (t_set,) = sunset_times_s(world.ephemeris, horizon_deg=0.0)
    t = t_set + np.linspace(0.0, 4 * 3600.0, 241)
    curve = drift.error_arcsec(t)
    assert curve[-1] - curve[0] == pytest.approx(60.0, abs=0.5)
    assert np.all(np.diff(curve) > 0)  # systematic: monotonic over the 4 hours


# =============================================================================================
# every registered effect plugs in: a scenario with it runs, and its truth is reported
SMOKE = {
    "terms": ({"HESA2": 6.0, "HACA2": -4.0}, {"terms_arcsec": {"HESA2": 6.0, "HACA2": -4.0}}),
    "thermal": ({"absorptivity": 0.3, "yoke_plate_m": 0.01}, None),
    "sunset_drift": ({"amplitude_arcsec": 64.48, "tau_s": 5400.0}, None),
    "tracking_jitter": ({"xel_rms_arcsec": 5.0, "el_rms_arcsec": 7.0, "timescale_s": 60.0},
                        None),
    "irregularities": ({"az_encoder_rms_arcsec": 10.0, "el_encoder_rms_arcsec": 12.0,
                        "track_rms_arcsec": 8.0, "pattern_seed": 3.0}, None),
    "clock_error": ({"offset_s": 2.0, "drift_s_per_day": 0.5}, None),
    "servo_lag": ({"lag_s": 0.5}, None),
    "backlash": ({"az_arcsec": 10.0, "el_arcsec": 6.0}, None),
    "polarization_squint": ({"separation_arcsec": 12.0, "angle_deg": 30.0}, None),
    "beam_width": ({"scale": 1.1}, None),
    "source_structure": ({"source": "Cygnus A", "size_arcmin": 2.0, "xel_arcsec": 5.0}, None),
    "refraction_anomaly": ({"scale": 1.05}, None),
    "exact_tilt_collimation": ({"tilt_arcmin": 1.0, "tilt_az_deg": 30.0,
                                "collimation_arcmin": 0.5}, None),
    # the effects for diagnosis (antsim/world/effects/harmonics.py, drifts.py)
    **{name: ({"amplitude_arcsec": 6.0, "phase_deg": 30.0}, None)
       for name in ("az_track_2a", "az_track_3a", "az_runout_1a", "az_runout_2a", "el_nod_1a",
                    "el_eccentricity", "el_eccentricity_2e")},
    "feed_offset": ({"offset_arcsec": 10.0, "angle_deg": 45.0}, None),
    "temperature_drift": ({"arcsec_per_k": 2.0, "tau_s": 3600.0, "reference_c": 5.0}, None),
    # a change at one instant (antsim/world/effects/steps.py)
    "step": ({"t_s": 3600.0, "az_arcsec": 20.0, "el_arcsec": -30.0}, None),
    # the equatorial effect (antsim/world/effects/equatorial.py), run on the 140-ft
    "polar_torsion": ({"amplitude_arcsec": 30.0, "phase_deg": 315.0}, None),
}
#: the effects of an equatorial mount: smoke-tested in the 140-ft's 4990 MHz scenario cut to
#: 6 hours (about 20 scans)
EQUATORIAL_ONLY = {"polar_torsion"}


def test_every_registered_effect_has_a_smoke_test():
    assert set(SMOKE) == set(EFFECTS)


def _toml_value(value) -> str:
    return f'"{value}"' if isinstance(value, str) else repr(float(value))


@pytest.mark.parametrize("name", sorted(SMOKE))
def test_effect_runs_in_a_scenario_and_reports_its_truth(short_ghigo_text, write_scenario,
                                                         name):
    """The 3-hour 1990 scenario (an equatorial mount's effect: the 140-ft's 4990 MHz run)
    with its own effects replaced by this one alone."""
    given, expected_params = SMOKE[name]
    base = short_ghigo_text
    if name in EQUATORIAL_ONLY:
        from tests.conftest import REPO, edit_text

        base = edit_text((REPO / "scenarios" / "crane1981_140ft_4990.toml").read_text(),
                         (("duration_h = 96.0", "duration_h = 6.0"),))
    start = base.index("[[truth.effects]]")
    end = base.index("[controller]")
    table = f'[[truth.effects]]\neffect = "{name}"\n' + "".join(
        f"{k} = {_toml_value(v)}\n" for k, v in given.items())
    text = base[:start] + table + "\n" + base[end:]
    scenario = load_scenario(write_scenario(text))
    assert [e.name for e in scenario.effects] == [name]
    result = simulate(scenario)
    assert result.n_scans > 10  # ran the campaign (3 h: ~30 scans)
    truth = result.world.truth()
    # the run's truth is the world's and the fit's recoverable truth beside it
    assert truth == {k: v for k, v in result.truth.items() if k != "recoverable"}
    (entry,) = truth["effects"]
    assert entry["effect"] == name
    params = entry["params"]
    for key, value in (expected_params or given).items():
        assert params[key] == value, (key, params)
    if name == "exact_tilt_collimation":
        assert entry["terms"] == ["AN", "AW", "CA"]


# =============================================================================================
# physical checks in the noise-free world
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


def test_polarization_squint_splits_xr_and_xl(quiet, probe):
    """XR's beam looks +sep/2 along ``angle_deg`` from the axis and XL's -sep/2, so XR peaks
    with the antenna -sep/2 away: centre_XR - centre_XL = -sep (cos a, sin a), mean zero."""
    probe_beam, source_trajectory = probe
    sep, angle = 20.0, math.radians(30.0)
    world = _quiet_world(quiet, [("polarization_squint",
                                  {"separation_arcsec": sep, "angle_deg": 30.0})])
    result = probe_beam(world, 0, source_trajectory(world, 0))
    xr, xl = np.array(result["XR"]["center"]), np.array(result["XL"]["center"])
    split = -sep * np.array([math.cos(angle), math.sin(angle)])
    assert xr - xl == pytest.approx(split, abs=STATIC_ARCSEC)
    assert 0.5 * (xr + xl) == pytest.approx([0.0, 0.0], abs=STATIC_ARCSEC)


#: injected geometry for the scaling checks: W10 = 60" (collimation: xel = W10 everywhere) and
#: W1 = 60" (elevation encoder offset)
SCALING_MODEL = PointingModel(["W10", "W1"], [60.0, 60.0])


def test_beam_width_scales_measured_offsets(quiet, probe):
    """A beam 1.2x wider than assumed: the true error (centre, width-free) is unchanged,
    the offset a fixed-width reduction measures (``nominal``) is the true one scaled by
    (H_nominal / H_true)^2 = 1/1.44 (log-ratio of a Gaussian: offset * 4 ln2 / H^2)."""
    probe_beam, source_trajectory = probe
    scale = 1.2
    world = _quiet_world(quiet, [("beam_width", {"scale": scale})], SCALING_MODEL)
    result = probe_beam(world, 0, source_trajectory(world, 0))
    for r in result.values():
        assert r["center"] == pytest.approx((60.0, 60.0), abs=STATIC_ARCSEC)
        assert r["nominal"] == pytest.approx((60.0 / scale**2, 60.0 / scale**2),
                                             abs=STATIC_ARCSEC)


def test_source_structure_scales_offsets_and_moves_the_centroid(quiet, probe):
    """3C84 made a 5' Gaussian with its centroid (+20", -10") from the catalogue: pointing
    at the catalogue position, the true offset is (60 + 20, 60 - 10)" and a reduction that
    assumes a point source measures it scaled by theta_b^2 / (theta_b^2 + theta_s^2) =
    121 / 146 = 0.829 (the response is a Gaussian of width^2 = theta_b^2 + theta_s^2)."""
    probe_beam, _ = probe
    params = {"source": "3C84", "size_arcmin": 5.0, "xel_arcsec": 20.0, "el_arcsec": -10.0}
    world = _quiet_world(quiet, [("source_structure", params)], SCALING_MODEL)

    def catalogue(t):  # true position of the catalogue coordinates (refracted)
        az, el = world.sky.ephemeris.altaz_rad(0, np.asarray(t, dtype=float))
        el = el + world.sky.refraction_rad(el, 0.0)
        return np.degrees(az) % 360.0, np.degrees(el)

    result = probe_beam(world, 0, catalogue)
    factor = 11.0**2 / (11.0**2 + 5.0**2)
    for r in result.values():
        assert r["center"] == pytest.approx((80.0, 50.0), abs=STATIC_ARCSEC)
        assert r["nominal"] == pytest.approx((80.0 * factor, 50.0 * factor),
                                             abs=STATIC_ARCSEC)
        # the source's peak is reduced by the same factor (flux conserved); the el scan's
        # zero point is (80", 50") off the centroid, in a beam widened to sqrt(146)'
        on_axis = 50.0 * 0.025 * factor
        k = FOUR_LN2 / (121.0 + 25.0) / 3600.0  # per arcsec^2
        # (d ln P / d offset = 2 k 94" = 1e-3 per arcsec: 0.01" is 1e-5 of it)
        assert r["peak"][1] == pytest.approx(on_axis * math.exp(-k * (80.0**2 + 50.0**2)),
                                             rel=2e-5)


def test_refraction_anomaly_leaves_scaled_refraction_in_elevation(quiet, probe):
    """Refraction present = 1.1 x the formula; commanding the formula's refraction leaves
    0.1 R(E) in elevation (R ~ 2.3' at 3C84's 22 deg: ~14")."""
    probe_beam, _ = probe
    scale = 1.1
    world = _quiet_world(quiet, [("refraction_anomaly", {"scale": scale})])

    def formula(t):  # what a controller that trusts the formula commands
        az, el = world.sky.ephemeris.altaz_rad(0, np.asarray(t, dtype=float))
        el = el + world.sky.refraction_rad(el, 0.0) / scale
        return np.degrees(az) % 360.0, np.degrees(el)

    result = probe_beam(world, 0, formula)
    _, el_vac = world.sky.ephemeris.altaz_rad(0, result["XR"]["times"][1])
    residual = (scale - 1.0) / scale * float(world.sky.refraction_rad(el_vac, 0.0)) / ARCSEC
    assert residual > 10.0
    for r in result.values():
        assert r["center"] == pytest.approx((0.0, residual), abs=STATIC_ARCSEC)


def test_backlash_follows_the_approach_direction():
    effect = EFFECTS["backlash"](az_arcsec=10.0, el_arcsec=6.0)
    for sign in (1.0, -1.0):
        state = PointingState(t_s=0.0, az_rad=1.0, el_rad=0.5, approach_az=sign,
                              approach_el=-sign)
        d_az, d_el = effect.pointing_error(state)
        # half the dead band, signed by the approach; 1e-12: float rounding of a conversion
        assert d_az / ARCSEC == pytest.approx(5.0 * sign, rel=1e-12)
        assert d_el / ARCSEC == pytest.approx(-3.0 * sign, rel=1e-12)


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


# ---------------------------------------------------------------------------------------------
def _linear_tilt_model(tilt_arcsec: float, tilt_az_deg: float, collimation_arcsec: float):
    """Small-angle equivalent of a tilt towards azimuth phi and a collimation c: to first
    order the encoders read dE = t cos(A - phi), dA = t tan E sin(A - phi) - c sec E
    (indicated - true), which in TPOINT's terms (docs/physics.md's signature table; signs as in
    tests/antsim/world/test_world.py: TPOINT's AN > 0 is the pole north of the zenith, AW > 0 west
    of it)
    is AN = t cos phi, AW = -t sin phi, CA = -c."""
    phi = math.radians(tilt_az_deg)
    return PointingModel(["AN", "AW", "CA"], [tilt_arcsec * math.cos(phi),
                                              -tilt_arcsec * math.sin(phi),
                                              -collimation_arcsec])


@pytest.mark.parametrize("tilt_az_deg", [0.0, 30.0, 120.0, 250.0])
@pytest.mark.parametrize("collimation_arcmin", [0.0, 1.0])
def test_exact_tilt_collimation_agrees_with_linear_terms_below_60_deg(tilt_az_deg,
                                                                      collimation_arcmin):
    """1' tilt (and 1' collimation): second-order terms are ~t^2 tan E ~ 0.02", so the exact
    and linear errors agree to < 0.1" (sky: xel and el) over all azimuths below 60 deg."""
    effect = ExactTiltCollimation(tilt_arcmin=1.0, tilt_az_deg=tilt_az_deg,
                                  collimation_arcmin=collimation_arcmin)
    linear = _linear_tilt_model(60.0, tilt_az_deg, 60.0 * collimation_arcmin)
    worst = 0.0
    for az_deg in np.arange(0.0, 360.0, 15.0):
        for el_deg in (5.0, 20.0, 40.0, 59.9):
            az, el = math.radians(az_deg), math.radians(el_deg)
            exact = effect.pointing_error(PointingState(t_s=0.0, az_rad=az, el_rad=el))
            approx = linear.offset_scalar_rad(az, el)
            d_xel = (exact[0] - approx[0]) * math.cos(el) / ARCSEC
            d_el = (exact[1] - approx[1]) / ARCSEC
            worst = max(worst, math.hypot(d_xel, d_el))
            # and the error itself is of the size of the tilt (a non-vacuous comparison)
            assert math.hypot(exact[0] * math.cos(el), exact[1]) / ARCSEC > 1.0
    assert worst < 0.1


def test_tilted_sky_is_encoder_from_true_within_rounding():
    """diagnose's path to the exact tilt's error (TiltedSky: one rotation matrix, one arctan2)
    against the effect's own (Rodrigues per vector, arcsin then sine): the same formulas
    rearranged, so they differ by rounding, which the elevation's arcsin amplifies near the
    zenith by 1/cos E (573 at 89.9 deg): measured 3e-7" at worst on the sky (tilts of 1' to
    2 deg); 1e-6" bounds it, far below any measured offset."""
    from antsim.world.effects.optics import TiltedSky

    rng = np.random.default_rng(12)
    az = rng.uniform(0.0, 2 * math.pi, 20_000)
    el = np.radians(rng.uniform(5.0, 89.9, 20_000))
    sky = TiltedSky(az, el)
    for tilt_arcmin, tilt_az_deg, coll_arcmin in ((1.0, 30.0, 0.0), (40.0, 60.0, 5.0),
                                                  (80.0, 250.0, -12.0), (120.0, 359.0, 30.0)):
        effect = ExactTiltCollimation(tilt_arcmin=tilt_arcmin, tilt_az_deg=tilt_az_deg,
                                      collimation_arcmin=coll_arcmin)
        az_enc, el_enc = effect.encoder_from_true(az, el)
        d_az = (az_enc - az + math.pi) % (2 * math.pi) - math.pi
        fast_az, fast_el = sky.errors_rad(math.radians(tilt_arcmin / 60.0),
                                          math.radians(tilt_az_deg),
                                          math.radians(coll_arcmin / 60.0))
        assert np.abs(d_az * np.cos(el)).max() / ARCSEC > 30.0 * tilt_arcmin  # not vacuous
        assert np.abs((fast_az - d_az) * np.cos(el)).max() / ARCSEC < 1e-6
        assert np.abs(fast_el - (el_enc - el)).max() / ARCSEC < 1e-6


def test_tilted_skys_derivatives_are_its_errors_central_differences():
    """TiltedSky.derivatives_rad (analytic, the exact tilt's Levenberg-Marquardt Jacobian)
    against central differences of errors_rad, step 1e-7 rad: their truncation error is
    ~h^2 = 1e-14 of the third derivative and their rounding ~1e-16 / 1e-7 of the errors'
    arithmetic, both growing near the zenith as the derivatives do (tan E: 28 at 88 deg):
    1e-7 of the largest derivative bounds them (measured 4e-9 to 2e-8 of it), while a wrong
    term is of the derivatives' order (not vacuous: each reaches 0.5); at zero tilt the
    series branch; a 2 deg tilt takes some directions past the pole, where errors_rad clips
    the elevation and both are zero."""
    from antsim.world.effects.optics import TiltedSky

    rng = np.random.default_rng(13)
    az = rng.uniform(0.0, 2 * math.pi, 5_000)
    el = np.radians(rng.uniform(5.0, 88.0, 5_000))
    sky = TiltedSky(az, el)

    def errors(p):
        north, east, coll = p
        d_az, d_el = sky.errors_rad(math.hypot(north, east), math.atan2(east, north), coll)
        return np.concatenate([d_az, d_el])

    h = 1e-7
    for p in ((1e-2, -2e-2, 5e-3), (3e-3, 1e-3, -2e-3), (0.0, 0.0, 0.0), (1e-6, 0.0, 1e-3),
              (-0.03, 0.02, 0.01)):
        d_az, d_el = sky.derivatives_rad(*p)
        for i in range(3):
            step = np.zeros(3)
            step[i] = h
            fd = (errors(np.add(p, step)) - errors(np.subtract(p, step))) / (2 * h)
            analytic = np.concatenate([d_az[i], d_el[i]])
            assert np.abs(analytic).max() > 0.5
            assert np.abs(analytic - fd).max() < 1e-7 * np.abs(analytic).max()


def test_wrap_pi_is_the_remainder_formula_bit_for_bit():
    """TiltedSky's wrap of the azimuth error (the remainder only outside (0, 2 pi)) gives the
    bytes of ``(x + pi) % (2 pi) - pi``: small errors, whole turns, the edges, NaN and inf."""
    from antsim.world.effects.optics import wrap_pi

    rng = np.random.default_rng(4)
    edges = [math.pi, -math.pi, 0.0, -0.0, 3 * math.pi, -3 * math.pi, np.nan, np.inf,
             -np.inf, np.nextafter(math.pi, 0.0), np.nextafter(-math.pi, 0.0)]
    x = np.concatenate([rng.normal(0.0, 1e-3, 10_000), rng.uniform(-20.0, 20.0, 10_000),
                        edges])
    with np.errstate(invalid="ignore"):
        expected = (x + math.pi) % (2 * math.pi) - math.pi
        got = wrap_pi(x.copy())
    assert got.tobytes() == expected.tobytes()


def test_exact_tilt_departs_from_linear_terms_near_the_zenith():
    """Near the zenith the linear dA = t tan E sin(A - phi) diverges, the exact one does not:
    at 89.5 deg the encoder azimuths differ by more than 1' and the sky positions by more
    than 0.5", growing towards 89.9 deg."""
    effect = ExactTiltCollimation(tilt_arcmin=1.0, tilt_az_deg=30.0, collimation_arcmin=0.0)
    linear = _linear_tilt_model(60.0, 30.0, 0.0)

    def worst(el_deg):
        d_a = d_sky = 0.0
        for az_deg in np.arange(0.0, 360.0, 15.0):
            az, el = math.radians(az_deg), math.radians(el_deg)
            exact = effect.pointing_error(PointingState(t_s=0.0, az_rad=az, el_rad=el))
            approx = linear.offset_scalar_rad(az, el)
            d_a = max(d_a, abs(exact[0] - approx[0]) / ARCSEC)
            d_sky = max(d_sky, math.hypot((exact[0] - approx[0]) * math.cos(el),
                                          exact[1] - approx[1]) / ARCSEC)
        return d_a, d_sky

    d_a, d_sky = worst(89.5)
    assert d_a > 60.0
    assert d_sky > 0.5
    assert worst(89.9)[1] > 2.0 * d_sky

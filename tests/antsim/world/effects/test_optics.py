"""Optical effects (antsim.world.effects.optics): polarization squint, beam width, source
structure, refraction anomaly, and the exact tilt and collimation against the linear terms;
measured in the noise-free world through the protocol only (``probe`` fixture in
tests/conftest.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from antsim.world.effects import PointingState
from antsim.world.effects.optics import ExactTiltCollimation
from controller.pointing.model import PointingModel
from tests.antsim.world.effects.conftest import (
    ARCSEC,
    STATIC_ARCSEC,
    _quiet_world,
)

FOUR_LN2 = 4.0 * math.log(2.0)


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

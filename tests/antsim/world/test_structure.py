"""Pointing per kelvin from the 45-ft's geometry (antsim.world.structure): the formulas
against exact geometry (scipy's solver and rotations) and against published antennas."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import fsolve
from scipy.spatial.transform import Rotation

from antsim.world.structure import JCMT_ARCSEC_PER_K, Structure, beam_deviation_factor
from controller.units import ARCSEC_PER_RAD

S = Structure()


def test_the_beam_deviation_factor_is_ruzes():
    """(1 + 0.36 q) / (1 + q), q = (D/4F)^2: 0.82 at F/D 0.4 (Ruze 1965's curve gives
    0.80-0.85 there), tending to 1 for a flat dish and to 0.36 for a deep one (0.361 at
    F/D = 0.01)."""
    assert beam_deviation_factor(13.7, 5.48) == pytest.approx(0.820, abs=1e-3)
    assert beam_deviation_factor(1.0, 100.0) == pytest.approx(1.0, abs=1e-4)
    assert beam_deviation_factor(100.0, 1.0) == pytest.approx(0.361, abs=1e-3)


def test_a_longer_leg_moves_the_feed_as_the_bipod_formula_says():
    """The upper and lower legs from the rim (R, R^2/4F) to the focus as a bipod: lengthen
    the upper one by 1 mm and solve for the feed's new position (scipy's fsolve on the two
    lengths). The feed moves away from the upper foot by dL / (2 sin phi) across the axis
    (to 1e-3 of it: the formula is the first order in dL / L = 1.3e-4; measured 7e-5), and
    the beam (the other way, times the beam deviation factor over F) rises: the elevation
    error is legs_el_arcsec_per_k (negative) per kelvin scaled to 1 mm."""
    r, zr, f = 0.5 * S.diameter_m, S.rim_depth_m, S.focal_length_m
    upper, lower = np.array([r, zr]), np.array([-r, zr])
    length = S.leg_length_m
    dl = 1e-3

    def lengths(p):
        return [np.hypot(*(p - upper)) - (length + dl), np.hypot(*(p - lower)) - length]

    x, _ = fsolve(lengths, [0.0, f], xtol=1e-14)
    assert x == pytest.approx(-dl / (2.0 * math.sin(S.leg_angle_rad)), rel=1e-3)
    bdf = beam_deviation_factor(S.diameter_m, f)
    beam_up_arcsec = -bdf * x / f * ARCSEC_PER_RAD  # feed down: beam up
    per_k = dl / (S.expansion_per_k * length)  # kelvin that lengthen the leg by dl
    assert S.legs_el_arcsec_per_k * per_k == pytest.approx(-beam_up_arcsec, rel=1e-3)
    assert S.legs_xel_arcsec_per_k == S.legs_el_arcsec_per_k  # a symmetric quadripod


def _beam(az, el):
    """Unit vector (north, east, up) of azimuth ``az``, elevation ``el`` (rad)."""
    return np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])


def _az_el(v):
    return math.atan2(v[1], v[0]), math.asin(v[2])


@pytest.mark.parametrize("az_deg, el_deg", [(0.0, 30.0), (125.0, 60.0), (300.0, 80.0)])
def test_the_yoke_signs_from_rotations(az_deg, el_deg):
    """The yoke's two effects as rotations of the beam (scipy): the arms' tops turning back
    by theta (a rotation about the elevation axis) raise the beam by theta, so the error
    (indicated minus true) is -theta per the bow coefficient's sign; the right arm longer
    rolls the elevation axis (a rotation about the horizontal direction faced), moving the
    beam left by theta sin E: dA cos E = +theta sin E, the roll coefficient's sign."""
    az, el = math.radians(az_deg), math.radians(el_deg)
    theta = 1e-5
    forward = np.array([math.cos(az), math.sin(az), 0.0])
    right = np.array([-math.sin(az), math.cos(az), 0.0])  # increasing azimuth
    b = _beam(az, el)
    # bow: the top leans back, the rotation about the elevation axis that takes up to back
    bowed = Rotation.from_rotvec(-theta * right).apply(b)
    _, e1 = _az_el(bowed)
    assert (e1 - el) == pytest.approx(theta, rel=1e-4)  # true beam higher
    assert np.sign(S.yoke_bow_arcsec_per_k) == -1.0
    # roll: the right end of the elevation axis up, a rotation about the direction faced
    rolled = Rotation.from_rotvec(theta * forward).apply(b)
    a2, e2 = _az_el(rolled)
    xel_true_minus_indicated = ((a2 - az + math.pi) % (2 * math.pi) - math.pi) * math.cos(el)
    assert -xel_true_minus_indicated == pytest.approx(theta * math.sin(el), rel=1e-4)
    assert np.sign(S.yoke_roll_arcsec_per_k) == 1.0
    assert abs(e2 - el) < 1e-3 * theta * 10  # second order in elevation


def test_the_coefficients_are_of_the_order_published_antennas_show():
    """The 45-ft's derived coefficients against the JCMT's (15 m; its error budget): its
    leg front-back difference moves elevation 6.5"/K (the same physics as the yoke's bow
    here: a member pair bending what carries the elevation axis), its elevation axis rolls
    2.4"/K side to side. Ours, from assumed dimensions, come within a factor of two of each
    (7.4" and 1.9"), and the feed legs' 1.6"/K below the JCMT's 3"/K for a gradient across
    its primary: a prime-focus feed's legs bend the beam less than a structure that turns
    the whole optics."""
    k = S.coefficients()
    assert 0.5 < abs(k["yoke_bow"]) / JCMT_ARCSEC_PER_K["legs_front_back"] < 2.0
    assert 0.5 < abs(k["yoke_roll"]) / JCMT_ARCSEC_PER_K["yoke_roll"] < 2.0
    assert 0.3 < abs(k["legs_el"]) / JCMT_ARCSEC_PER_K["dish_gradient"] < 1.0
    # the pedestal: alpha H / D, 4.95" per kelvin for 5 m over 2.5 m
    assert k["pedestal_tilt"] == pytest.approx(12e-6 * 2.0 * ARCSEC_PER_RAD)

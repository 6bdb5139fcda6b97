"""The pointing model (controller.pointing.model): offset, apply and reverse as TPOINT's
corrections say, round trips of the 1990 report's Table 3 model, the Quantity API, and the
named models."""

from __future__ import annotations

import math

import numpy as np
import pytest
from astropy import units as u
from hypothesis import given, settings
from hypothesis import strategies as st

from controller.pointing.model import NAMED_MODELS, PointingModel
from controller.units import ARCSEC_PER_RAD, RAD_PER_ARCSEC
from tests.controller.pointing.test_fitting import GHIGO_TABLE3_ARCSEC, ghigo_truth, synthetic

# A grid over the whole sky the terms are used on: every 15 deg of azimuth, elevation 5-85.
_AZ, _EL = np.meshgrid(np.radians(np.arange(0.0, 360.0, 15.0)),
                       np.radians(np.arange(5.0, 86.0, 10.0)))
GRID_AZ, GRID_EL = _AZ.ravel(), _EL.ravel()


# ---------------------------------------------------------------------------------------------
# PointingModel: offset / apply / reverse
# ---------------------------------------------------------------------------------------------
def test_offset_is_minus_the_tpoint_correction():
    """offset_rad ("indicated minus true") = -(basis @ coefficients)."""
    model = PointingModel(["IA", "AN", "TX"], [30.0, -12.0, 4.0])
    basis_az, basis_el = model.design_matrix(GRID_AZ, GRID_EL)
    d_az, d_el = model.offset_rad(GRID_AZ, GRID_EL)
    c = model.values_arcsec * RAD_PER_ARCSEC
    np.testing.assert_allclose(d_az, -(basis_az @ c), rtol=1e-14, atol=0)
    np.testing.assert_allclose(d_el, -(basis_el @ c), rtol=1e-14, atol=0)
    # IA alone: TPOINT's correction is dA = -IA, so the indicated azimuth is IA ahead
    ia = PointingModel(["IA"], [36.0])
    assert ia.offset_rad(1.0, 0.5)[0] == pytest.approx(36.0 * RAD_PER_ARCSEC, rel=1e-14)


GHIGO_TABLE3_ARCMIN = [-1.88, -0.17, -1.54, -2.16, 0.80, 12.24, 1.62, -0.35, -3.35, -1.79]


@settings(max_examples=60, deadline=None)
@given(
    coeffs=st.lists(st.floats(-300.0, 300.0), min_size=10, max_size=10),
    az=st.floats(0.0, 2 * math.pi, exclude_max=True),
    el=st.floats(math.radians(5.0), math.radians(80.0)),
)
def test_apply_reverse_round_trip(coeffs, az, el):
    """reverse(apply(x)) == x, with W6 = 12.24' (the 1990 report's large azimuth encoder
    offset) on top.

    Tolerance 1e-8 rad (2 mas): reverse iterates to 1e-4 arcsec on the sky.
    """
    values = np.array(coeffs)
    values[5] += 12.24 * 60.0
    model = PointingModel("ghigo10").with_values(values)
    enc_az, enc_el = model.apply_rad(az, el)
    back_az, back_el = model.reverse_rad(enc_az, enc_el)
    assert abs(back_az - az) * math.cos(el) < 1e-8
    assert abs(back_el - el) < 1e-8
    d_az, d_el = model.offset_rad(az, el)
    assert enc_az - az == pytest.approx(d_az, abs=1e-15)
    assert enc_el - el == pytest.approx(d_el, abs=1e-15)


def test_table3_model_round_trip_on_a_grid():
    model = PointingModel("ghigo10").with_values(np.array(GHIGO_TABLE3_ARCMIN) * 60.0)
    enc = model.apply_rad(GRID_AZ, GRID_EL)
    back = model.reverse_rad(*enc)
    np.testing.assert_allclose(back[1], GRID_EL, rtol=0, atol=1e-9)
    np.testing.assert_allclose((back[0] - GRID_AZ) * np.cos(GRID_EL), 0.0, atol=1e-9)
    # the azimuth encoder offset alone moves the indicated azimuth by W6 = 12.24' (734.4"),
    # which is 734.4" cos E across the sky (the report's "W6 cos E" in dA cos E)
    w6 = PointingModel(["W6"], [12.24 * 60.0])
    d_az, d_el = w6.offset_rad(0.3, 0.7)
    assert d_az * ARCSEC_PER_RAD == pytest.approx(734.4, rel=1e-12) and d_el == 0.0
    assert d_az * math.cos(0.7) * ARCSEC_PER_RAD == pytest.approx(734.4 * math.cos(0.7))


def test_quantity_api_refuses_bare_floats():
    model = PointingModel(["IA", "IE"], [10.0, -5.0])
    with pytest.raises(TypeError, match="Quantity"):
        model.offset(1.0, 0.5)
    with pytest.raises(TypeError, match="Quantity"):
        model.apply(30 * u.deg, 0.5)
    with pytest.raises(TypeError, match="Quantity"):
        model.reverse(30.0, 40.0 * u.deg)
    d_az, d_el = model.offset(30 * u.deg, 40 * u.deg)
    assert d_az.unit == u.arcsec
    assert d_az.value == pytest.approx(10.0, rel=1e-12)
    assert d_el.value == pytest.approx(5.0, rel=1e-12)  # IE: dE = +IE, offset = -dE


def test_named_models_resolve():
    for name, terms in NAMED_MODELS.items():
        model = PointingModel(name)
        assert model.names == terms
        assert model.name == name


def test_model_fit_method_uses_quantities():
    from astropy import units as u

    rng = np.random.default_rng(6)
    data = synthetic(ghigo_truth(), rng, 100)
    model = PointingModel("ghigo10")
    result = model.fit(data.az_rad * u.rad, data.el_rad * u.rad, data.xel_arcsec * u.arcsec,
                       data.el_arcsec * u.arcsec, robust=False)
    np.testing.assert_allclose(result.model.values_arcsec, GHIGO_TABLE3_ARCSEC, atol=1e-6)
    assert not model.values_arcsec.any()  # the model itself is unchanged

"""The equatorial terms of the NRAO 140-ft (controller.pointing.equatorial; Crane 1981). The
mount frame is tested in tests/controller/astro/test_frames.py, the three scenarios end to end in
tests/end_to_end/test_crane1981_runs.py.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from controller.astro.frames import altaz_to_hadec, hadec_to_altaz
from controller.pointing.data import PointingData
from controller.pointing.equatorial import (
    EQUATORIAL_MODELS,
    equatorial_model,
    equatorial_term,
    is_equatorial_term,
)
from controller.pointing.fitting import fit_model
from controller.pointing.model import PointingModel
from controller.pointing.terms import TermError
from controller.units import ARCSEC_PER_RAD

LAT = 38.437611  # the 140-ft (scenarios: SLALIB GBVA140)


# --------------------------------------------------------------------------- frames and terms
def _as_hadec(az_err, el_err, az, el, phi):
    """An alt-az error (indicated - true, rad) moved onto hour angle and declination."""
    h1, d1 = altaz_to_hadec(az + az_err, el + el_err, phi)
    h0, d0 = altaz_to_hadec(az, el, phi)
    return (h1 - h0 + math.pi) % (2 * math.pi) - math.pi, d1 - d0


@pytest.mark.parametrize("name", ["TF", "TX"])
def test_equatorial_tf_tx_are_the_altaz_terms_moved_onto_the_axes(name):
    # TPOINT's equatorial TF and TX are its alt-az TF (dE = -TF cos E) and TX (dE = -TX cot E)
    # seen on the hour-angle and declination axes: this pins their signs and latitude factors
    rng = np.random.default_rng(3)
    phi = math.radians(LAT)
    ha = rng.uniform(-1.5, 1.5, 400)
    dec = rng.uniform(-0.5, 1.3, 400)
    az, el = hadec_to_altaz(ha, dec, phi)
    keep = el > math.radians(12.0)
    ha, dec, az, el = ha[keep], dec[keep], az[keep], el[keep]
    eq = equatorial_model([name], LAT, [20.0])
    aa = PointingModel([name], [20.0])
    dh, dd = eq.offset_rad(ha, dec)
    dh2, dd2 = _as_hadec(*aa.offset_rad(az, el), az, el, phi)
    # equal to first order; the second order of errors up to 100" (TX's 1/sin E reaches 4.8
    # at 12 deg) is (100" / 206265")^2 x 100" ~ 0.01" at most
    assert np.max(np.abs(dh - dh2)) * ARCSEC_PER_RAD < 0.02
    assert np.max(np.abs(dd - dd2)) * ARCSEC_PER_RAD < 0.02


@pytest.mark.parametrize("name, axis", [("ME", (0.0, 1.0, 0.0)), ("MA", (1.0, 0.0, 0.0))])
def test_polar_axis_terms_are_rigid_rotations(name, axis):
    # ME: a rotation about the east-west axis; MA: about the axis through H = 0 on the equator
    # (x towards H = 0, dec = 0; y = -cos(dec) sin H; z the pole). A rotation by -c gives
    # TPOINT's ME (or MA) = c, in both axes at once.
    c = 3.0 / ARCSEC_PER_RAD  # small, so that the second order (~1e-4") stays below 1e-3"
    rng = np.random.default_rng(5)
    ha = rng.uniform(-1.5, 1.5, 200)
    dec = rng.uniform(-0.6, 1.2, 200)
    v = np.stack([np.cos(dec) * np.cos(ha), -np.cos(dec) * np.sin(ha), np.sin(dec)])
    k = np.array(axis)[:, None]
    angle = -c
    rot = (v * math.cos(angle) + np.cross(k.T, v.T).T * math.sin(angle)
           + k * (k * v).sum(axis=0) * (1 - math.cos(angle)))
    ha_r = np.arctan2(-rot[1], rot[0])
    dec_r = np.arcsin(rot[2])
    correction_h = (ha_r - ha + math.pi) % (2 * math.pi) - math.pi
    correction_d = dec_r - dec
    basis_h, basis_d = equatorial_term(name, LAT).basis(ha, dec)
    np.testing.assert_allclose(correction_h, c * basis_h, atol=1e-3 / ARCSEC_PER_RAD)
    np.testing.assert_allclose(correction_d, c * basis_d, atol=1e-3 / ARCSEC_PER_RAD)


def test_index_collimation_and_harmonic_terms():
    ha = np.array([0.3, -1.0])
    dec = np.array([0.2, 0.9])
    assert np.allclose(equatorial_term("IH", LAT).basis(ha, dec)[0], -1.0)
    assert np.allclose(equatorial_term("ID", LAT).basis(ha, dec)[1], -1.0)
    assert np.allclose(equatorial_term("CH", LAT).basis(ha, dec)[0], -1.0 / np.cos(dec))
    assert np.allclose(equatorial_term("NP", LAT).basis(ha, dec)[0], -np.tan(dec))
    assert np.allclose(equatorial_term("FO", LAT).basis(ha, dec)[1], np.cos(ha))
    assert np.allclose(equatorial_term("HDSD", LAT).basis(ha, dec)[1], np.sin(dec))
    assert np.allclose(equatorial_term("HXCH2", LAT).basis(ha, dec)[0],
                       np.cos(2 * ha) / np.cos(dec))
    assert is_equatorial_term("hdsd") and not is_equatorial_term("IA")
    with pytest.raises(TermError, match="unknown equatorial pointing term"):
        equatorial_term("IA", LAT)
    assert EQUATORIAL_MODELS["crane11"] == ("IH", "ID", "CH", "NP", "MA", "ME", "TF", "FO",
                                            "DAF", "TX", "HCES")


def test_daf_is_hcec_and_np_combined():
    # why crane11 leaves HCEC out: DAF = -cos(phi) HCEC + sin(phi) NP exactly
    rng = np.random.default_rng(2)
    ha, dec = rng.uniform(-1.5, 1.5, 300), rng.uniform(-0.6, 1.2, 300)
    model = equatorial_model(["HCEC", "NP", "DAF"], LAT, [0.0, 0.0, 10.0])
    dh, dd = model.offset_rad(ha, dec)
    data = PointingData(ha, dec, dh * np.cos(dec) * ARCSEC_PER_RAD, dd * ARCSEC_PER_RAD)
    fit = fit_model(data, model.terms, robust=False)
    assert fit.unconstrained == ("DAF",)
    phi = math.radians(LAT)
    assert fit.model["HCEC"] == pytest.approx(-10.0 * math.cos(phi), abs=1e-6)
    assert fit.model["NP"] == pytest.approx(10.0 * math.sin(phi), abs=1e-6)


def test_crane11_is_well_determined_over_the_140ft_sky():
    # the eleven terms separate on a sky like the scenarios' (no rank deficiency)
    rng = np.random.default_rng(8)
    ha = rng.uniform(-1.5, 1.5, 300)
    dec = rng.uniform(math.radians(-12), math.radians(53), 300)
    model = equatorial_model("crane11", LAT, [35, -28, 22, -15, 18, -25, 40, 12, -14, 8, 6])
    dh, dd = model.offset_rad(ha, dec)
    data = PointingData(ha, dec, dh * np.cos(dec) * ARCSEC_PER_RAD, dd * ARCSEC_PER_RAD)
    fit = fit_model(data, model.terms, robust=False)
    assert not fit.unconstrained
    np.testing.assert_allclose(fit.values_arcsec, model.values_arcsec, atol=1e-8)



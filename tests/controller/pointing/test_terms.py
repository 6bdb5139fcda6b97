"""TPOINT's terms that observatories use beyond the basic eight: the Nasmyth rotator
displacements NRX and NRY, the polynomial terms (PEE1 ...), ACEC and ACES as TPOINT defines
them, and the refusal of TX10 and of polynomials in the azimuth, whose definitions public
documents do not establish."""

from __future__ import annotations

import math

import numpy as np
import pytest

from controller.pointing.terms import TermError, evaluate_basis, get_term

RNG = np.random.default_rng(20)
AZ = RNG.uniform(0.0, 2.0 * math.pi, 200)
EL = RNG.uniform(math.radians(5.0), math.radians(85.0), 200)


def columns(name: str) -> tuple[np.ndarray, np.ndarray]:
    """(dA cos E, dE) of a term's basis: its error on the sky."""
    d_az, d_el = evaluate_basis([get_term(name)], AZ, EL)
    return d_az[:, 0] * np.cos(EL), d_el[:, 0]


def test_a_nasmyth_rotator_displacement_draws_a_circle_on_the_sky():
    """A displacement (x, y) of the rotator's axis in a Nasmyth focal plane reaches the sky
    turned by the elevation: its size is the same at every elevation, and NRX and NRY are
    the same circle a quarter turn apart (TPOINT's tptPterms, terms 38 and 39)."""
    x_s, x_e = columns("NRX")
    y_s, y_e = columns("NRY")
    np.testing.assert_allclose(np.hypot(x_s, x_e), 1.0, atol=1e-12)
    np.testing.assert_allclose(np.hypot(y_s, y_e), 1.0, atol=1e-12)
    np.testing.assert_allclose(x_s * y_s + x_e * y_e, 0.0, atol=1e-12)
    # the angle on the sky (left-right = -dA cos E, as CA's; up = dE) turns with E itself
    angle = np.arctan2(x_e, -x_s)
    np.testing.assert_allclose(np.angle(np.exp(1j * (angle + EL))), 0.0, atol=1e-12)


def test_nrx_and_nry_are_combinations_of_basic_terms():
    """Why a fit with IA, NPAE, ECEC and ECES cannot tell NRX and NRY apart from them:
    NRX = IA - ECES and NRY = NPAE + ECEC, column by column."""
    for name, parts in (("NRX", (("IA", 1.0), ("ECES", -1.0))),
                        ("NRY", (("NPAE", 1.0), ("ECEC", 1.0)))):
        s, e = columns(name)
        want_s = sum(sign * columns(p)[0] for p, sign in parts)
        want_e = sum(sign * columns(p)[1] for p, sign in parts)
        np.testing.assert_allclose(s, want_s, atol=1e-12)
        np.testing.assert_allclose(e, want_e, atol=1e-12)


@pytest.mark.parametrize(("name", "sky", "elevation"), [
    ("PEE1", lambda e: 0.0 * e, lambda e: e),
    ("PEE", lambda e: 0.0 * e, lambda e: e),
    ("PEE2", lambda e: 0.0 * e, lambda e: e**2),
    ("PEZ3", lambda e: 0.0 * e, lambda e: (math.pi / 2 - e) ** 3),
    ("PZE1", lambda e: 0.0 * e, lambda e: -e),
    ("PSE2", lambda e: -(e**2), lambda e: 0.0 * e),
    ("PAE1", lambda e: -e * np.cos(e), lambda e: 0.0 * e),
    ("PEE1Z2", lambda e: 0.0 * e, lambda e: e * (math.pi / 2 - e) ** 2),
])
def test_polynomial_terms_are_powers_of_the_elevation_in_radians(name, sky, elevation):
    """PEE1: dE = PEE1 E (E in radians), an elevation scale error; the result letters sign
    as the harmonics' do (dA and dA cos E minus, dE plus, dZ = -dE)."""
    s, e = columns(name)
    np.testing.assert_allclose(s, sky(EL), atol=1e-12)
    np.testing.assert_allclose(e, elevation(EL), atol=1e-12)


def test_acec_and_aces_are_tpoints_hasa_and_haca():
    """TPOINT defines ACES and ACEC as dAz = ACES sin Az and dAz = ACEC cos Az, the
    harmonics HASA and HACA (tptPterms, terms 34 and 35)."""
    for named, harmonic in (("ACES", "HASA"), ("ACEC", "HACA")):
        np.testing.assert_allclose(columns(named)[0], columns(harmonic)[0], atol=1e-12)
        np.testing.assert_allclose(columns(named)[1], 0.0, atol=0.0)


@pytest.mark.parametrize(("name", "says"), [
    ("TX10", "no public TPOINT document establishes"),
    ("PAA1", "polynomial in the azimuth"),
    ("PEA2", "polynomial in the azimuth"),
    ("PEE0", "unknown pointing term"),
    ("NRZ", "unknown pointing term"),
])
def test_terms_public_documents_do_not_define_are_refused_saying_why(name, says):
    with pytest.raises(TermError, match=says) as err:
        get_term(name)
    assert "\n" not in str(err.value)

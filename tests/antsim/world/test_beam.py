"""The antenna beam (antsim.world.beam): a Gaussian main beam convolved with the source, the
gain's elevation curve, and a source's offsets in the beam's frame."""

from __future__ import annotations

import math

import numpy as np
import pytest
from astropy.coordinates import angular_separation

from antsim.world.beam import Beam, BeamConfig, tangent_offsets


def test_a_point_source_falls_to_half_power_at_half_the_beam_width():
    beam = Beam(BeamConfig(hpbw_arcmin=11.0))
    assert beam.response(0.0, 0.0) == 1.0
    assert beam.response(5.5, 0.0) == pytest.approx(0.5, rel=1e-12)
    assert beam.response(0.0, -5.5) == pytest.approx(0.5, rel=1e-12)
    assert beam.response(5.5 / math.sqrt(2), 5.5 / math.sqrt(2)) == pytest.approx(0.5, rel=1e-12)


def test_an_extended_source_widens_the_response_and_keeps_its_flux():
    """Gaussians convolve: width sqrt(b^2 + s^2), peak b^2 / (b^2 + s^2); the integral of the
    response (the flux seen) is then the point source's."""
    beam = Beam(BeamConfig(hpbw_arcmin=11.0))
    size = 4.0
    width = math.hypot(11.0, size)
    assert beam.response(0.0, 0.0, size) == pytest.approx(121.0 / (121.0 + 16.0))
    assert beam.response(width / 2, 0.0, size) == pytest.approx(0.5 * 121.0 / 137.0)
    grid = np.linspace(-40.0, 40.0, 801)
    x, y = np.meshgrid(grid, grid)
    assert beam.response(x, y, size).sum() == pytest.approx(beam.response(x, y).sum(), rel=1e-9)


def test_the_gain_follows_the_1990_reports_elevation_curve():
    """Flat above 30 deg, 95% at 20 deg, 90% at 10 deg, linear between, held below."""
    beam = Beam(BeamConfig())
    el_deg = np.array([5.0, 10.0, 15.0, 20.0, 30.0, 60.0])
    assert np.allclose(beam.efficiency(np.radians(el_deg)), [0.90, 0.90, 0.925, 0.95, 1.0, 1.0])


@pytest.mark.parametrize("src, beam", [((0.3, 0.5), (0.31, 0.49)), ((2.0, -0.2), (1.9, -0.25)),
                                       ((0.0, 1.2), (0.05, 1.21))])
def test_tangent_offsets_are_exact_on_the_sphere(src, beam):
    """Orthographic projection: the offsets' length is the sine of the true separation, and a
    source at the beam's longitude lies on the latitude axis."""
    x, y = tangent_offsets(*src, *beam)
    separation = angular_separation(src[0], src[1], beam[0], beam[1])
    assert math.hypot(x, y) == pytest.approx(math.sin(separation), rel=1e-12)
    x0, y0 = tangent_offsets(beam[0], src[1], *beam)
    assert x0 == 0.0 and y0 == pytest.approx(math.sin(src[1] - beam[1]), rel=1e-12)

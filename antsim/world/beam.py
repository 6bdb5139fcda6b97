"""The antenna beam: a Gaussian main beam convolved with the source's brightness.

A Gaussian source of FWHM ``theta_s`` seen by a Gaussian beam of FWHM ``theta_b`` gives a
Gaussian response of FWHM ``sqrt(theta_b^2 + theta_s^2)`` whose peak is
``theta_b^2 / (theta_b^2 + theta_s^2)`` of a point source's (flux is conserved). Five-point
offsets measured with the nominal beam width are then scaled by the same factor (docs/physics.md,
Site and sky: about 0.91 for Taurus A and Cassiopeia A at 11').

The gain falls at low elevation as the 1990 report's section V describes: flat above
30 deg, 95% at 20 deg, 90% at 10 deg (linear in between, held below the table).

Where a source lies in the beam's own frame (:func:`tangent_offsets`) is what the beam's
response and the optical camera (:mod:`antsim.world.camera`) both need.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Beam", "BeamConfig", "tangent_offsets"]

FOUR_LN2 = 4.0 * math.log(2.0)


@dataclass(frozen=True)
class BeamConfig:
    hpbw_arcmin: float = 11.0
    efficiency_el_deg: tuple[float, ...] = (10.0, 20.0, 30.0, 90.0)
    efficiency: tuple[float, ...] = (0.90, 0.95, 1.0, 1.0)
    #: aperture gain at the top of the efficiency curve (K per Jy, one polarization)
    gain_k_per_jy: float = 0.025
    extra_efficiency: dict = field(default_factory=dict)
    #: Crane 1981's gain curve: coefficients of Y00, Y10, Y11e, Y11o (controller.scans.gaincurve)
    #: of the relative gain; when given it replaces the elevation curve (World.efficiency)
    gain_harmonics: tuple[float, float, float, float] | None = None


class Beam:
    """Response of the beam to a (possibly extended) source at an offset."""

    def __init__(self, config: BeamConfig):
        self.config = config
        self.hpbw_arcmin = config.hpbw_arcmin
        self._el_rad = np.radians(np.asarray(config.efficiency_el_deg, dtype=float))
        self._eff = np.asarray(config.efficiency, dtype=float)

    def efficiency(self, el_rad) -> np.ndarray:
        """Relative gain at elevation(s) ``el_rad`` (1 on the flat part of the curve)."""
        return np.interp(el_rad, self._el_rad, self._eff)

    def response(self, xel_arcmin, el_arcmin, size_arcmin: float = 0.0) -> np.ndarray:
        """Relative response (1 = point source on axis) at sky offsets in arcmin."""
        width2 = self.hpbw_arcmin ** 2 + size_arcmin ** 2
        peak = self.hpbw_arcmin ** 2 / width2
        return peak * np.exp(-FOUR_LN2 * (np.square(xel_arcmin) + np.square(el_arcmin)) / width2)


def tangent_offsets(src_lon, src_lat, beam_lon, beam_lat) -> tuple[np.ndarray, np.ndarray]:
    """Offsets (rad) of a source from the beam in the beam's own frame (orthographic
    projection: cross-axis and along the latitude-like axis), exact on the sphere. The
    alt-az scans use ``d_az cos(src_el)`` and ``d_el`` instead, which is exact only along one
    axis at a time (the error is ~ x^2 tan(el) for an offset x in both axes): fine for scans
    along azimuth or elevation, not for an equatorial mount's scans, which cross both."""
    d_lon = src_lon - beam_lon
    cos_s = np.cos(src_lat)
    return (cos_s * np.sin(d_lon),
            np.sin(src_lat) * np.cos(beam_lat) - cos_s * np.sin(beam_lat) * np.cos(d_lon))

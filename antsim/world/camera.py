"""A TV camera on the optical axis, and the synthetic bright stars it is pointed at.

BIMA's antennas were pointed optically (Wright 1992, BIMA memo 23): a small telescope with a
TV camera, boresighted on the antenna, shows a bright star; its offset from the optical axis
(the centre of the frame) is read directly, to a few arcseconds, without any radio scan. The
camera here measures, over an exposure, the mean offset of the star nearest the axis from the
axis' true direction (slow pointing errors and per-sample jitter included, exactly as a radio
beam would point), plus Gaussian centroid noise of ``noise_arcsec`` per axis (seeing and
centroiding; assumption). A star outside the field (``field_arcmin`` across) is not found.

Stars: the memo's star list was not available. :func:`synthetic_stars` spreads ``n`` stars
evenly over the sky north of ``dec_min_deg`` on a Fibonacci lattice (ICRS, deterministic):
a documented stand-in for a catalogue of bright stars. Refraction is the optical one (the
camera's wavelength), for the world and for the controller alike.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from controller.astro.frames import MountFrame
from controller.units import ARCSEC_PER_RAD

from .beam import tangent_offsets
from .effects.base import PointingState

__all__ = ["Camera", "CameraConfig", "synthetic_stars"]

_C_UM_GHZ = 299792.458  # speed of light in micrometres * GHz
_GOLDEN = (1.0 + math.sqrt(5.0)) / 2.0


@dataclass(frozen=True)
class CameraConfig:
    """The camera: wavelength (um), centroid noise per axis per exposure (arcsec) and the
    field of view across (arcmin)."""

    wavelength_um: float = 0.55
    noise_arcsec: float = 2.0
    field_arcmin: float = 20.0

    @property
    def frequency_ghz(self) -> float:
        """The camera's frequency (GHz), for the optical refraction formula."""
        return _C_UM_GHZ / self.wavelength_um


def synthetic_stars(n: int, dec_min_deg: float = -30.0) -> list[tuple[str, float, float]]:
    """``n`` stars ``(name, ra_deg, dec_deg)`` (ICRS) evenly spread over the sky above
    declination ``dec_min_deg`` (a Fibonacci lattice in sin(dec) and RA)."""
    if n < 1:
        raise ValueError(f"the star list needs at least one star, not {n}")
    lo = math.sin(math.radians(dec_min_deg))
    stars = []
    for k in range(n):
        z = lo + (1.0 - lo) * (k + 0.5) / n
        dec = math.degrees(math.asin(z))
        ra = (360.0 * k / _GOLDEN) % 360.0
        stars.append((f"S{k + 1:03d}", ra, dec))
    return stars


class Camera:
    """The world's camera: measures a star's offset from the true optical axis."""

    def __init__(self, config: CameraConfig, rng: np.random.Generator):
        self.config = config
        self.rng = rng

    def measure(self, beam_direction: Callable, frame: MountFrame, t: np.ndarray,
                enc_lon: np.ndarray, enc_lat: np.ndarray, state: PointingState, paths,
                error_prev) -> tuple[tuple[float, float, bool], tuple]:
        """Offset (arcsec, mount axes: cross-axis and along the second axis) of the star
        nearest the axis over the exposure with samples ``t``, whether one was in the field,
        and the slow errors solved (the next fixed point's start). ``beam_direction``: the
        world's :meth:`~antsim.world.world.World.beam_direction`; ``frame``: its mount's
        axes."""
        mid = t.size // 2
        beam_lon, beam_lat, (d_lon, d_lat) = beam_direction(t, enc_lon, enc_lat, state,
                                                            error_prev)
        best = None
        for _, src_az, src_el in paths:
            s_lon, s_lat = frame.from_altaz(src_az, src_el)
            d_x, d_y = tangent_offsets(s_lon, s_lat, beam_lon, beam_lat)
            sep = float(np.hypot(d_x[mid], d_y[mid]))
            if best is None or sep < best[0]:
                best = (sep, d_x, d_y)
        half_field = 0.5 * self.config.field_arcmin * 60.0 / ARCSEC_PER_RAD
        if best is None or best[0] > half_field:
            return (math.nan, math.nan, False), (d_lon, d_lat)
        noise = self.config.noise_arcsec * self.rng.standard_normal(2)
        xel = float(np.mean(best[1])) * ARCSEC_PER_RAD + float(noise[0])
        el = float(np.mean(best[2])) * ARCSEC_PER_RAD + float(noise[1])
        return (xel, el, True), (d_lon, d_lat)

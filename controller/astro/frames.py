"""Mount frames: the coordinates a mount's two axes turn in, and their link to azimuth-elevation.

An alt-az mount turns in (azimuth, elevation); an equatorial (polar) mount in (hour angle,
declination). Everything that works on "the mount's two axes" (encoder commands, scan offsets,
pointing-model terms, the fitter) is written for a generic pair ``(lon, lat)``: azimuth and
elevation for an alt-az mount, hour angle and declination for an equatorial one. Cross-axis
offsets are ``d_lon cos(lat)`` in both (cross-elevation, cross-declination). The physics that
needs the local horizon (atmosphere, gain against elevation, refraction) converts with
:meth:`MountFrame.to_altaz`.

Conventions: azimuth North = 0, East = pi/2; hour angle positive West (in ``(-pi, pi]``);
radians; the conversions are ERFA's ``hd2ae``/``ae2hd`` (exact spherical trigonometry, no
refraction; ufuncs, so they broadcast over any array shapes).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import erfa
import numpy as np

__all__ = ["ALTAZ", "MOUNT_KINDS", "MountFrame", "altaz_to_hadec", "hadec_to_altaz"]

#: the mount kinds a scenario may name
MOUNT_KINDS = ("altaz", "equatorial")


def hadec_to_altaz(ha_rad, dec_rad, latitude_rad: float) -> tuple[np.ndarray, np.ndarray]:
    """Azimuth (N = 0, E = pi/2, in [0, 2 pi)) and elevation (rad) of hour angle(s) and
    declination(s) (rad) at geodetic latitude ``latitude_rad``: ``erfa.hd2ae``."""
    return erfa.hd2ae(ha_rad, dec_rad, latitude_rad)


def altaz_to_hadec(az_rad, el_rad, latitude_rad: float) -> tuple[np.ndarray, np.ndarray]:
    """Hour angle (positive West, in (-pi, pi]) and declination (rad) of azimuth(s) and
    elevation(s) (rad) at geodetic latitude ``latitude_rad``: ``erfa.ae2hd``."""
    return erfa.ae2hd(az_rad, el_rad, latitude_rad)


@dataclass(frozen=True)
class MountFrame:
    """The frame of a mount's axes: ``kind`` ``"altaz"`` or ``"equatorial"`` and the site's
    geodetic latitude (deg). For ``"altaz"`` every conversion is the identity."""

    kind: str = "altaz"
    latitude_deg: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in MOUNT_KINDS:
            raise ValueError(f"mount kind {self.kind!r} is not one of {', '.join(MOUNT_KINDS)}")

    @property
    def is_altaz(self) -> bool:
        return self.kind == "altaz"

    @property
    def latitude_rad(self) -> float:
        return math.radians(self.latitude_deg)

    @property
    def axis_names(self) -> tuple[str, str]:
        """Names of the two axes, for messages and recordings."""
        return ("az", "el") if self.is_altaz else ("ha", "dec")

    def to_altaz(self, lon_rad, lat_rad) -> tuple[np.ndarray, np.ndarray]:
        """Azimuth and elevation (rad) of mount-frame coordinates (rad)."""
        if self.is_altaz:
            return lon_rad, lat_rad
        return hadec_to_altaz(lon_rad, lat_rad, self.latitude_rad)

    def from_altaz(self, az_rad, el_rad) -> tuple[np.ndarray, np.ndarray]:
        """Mount-frame coordinates (rad) of azimuth and elevation (rad)."""
        if self.is_altaz:
            return az_rad, el_rad
        return altaz_to_hadec(az_rad, el_rad, self.latitude_rad)

    def to_altaz_deg(self, lon_deg: float, lat_deg: float) -> tuple[float, float]:
        """:meth:`to_altaz` for one position in degrees (azimuth in [0, 360))."""
        if self.is_altaz:
            return lon_deg, lat_deg
        az, el = hadec_to_altaz(math.radians(lon_deg), math.radians(lat_deg), self.latitude_rad)
        return math.degrees(float(az)), math.degrees(float(el))


#: the alt-az frame (identity conversions)
ALTAZ = MountFrame("altaz", 0.0)

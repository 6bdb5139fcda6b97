"""The antenna's site and its surface weather: where the sky is seen from, and the weather
the refraction depends on."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from .values import finite_fields, require_finite

if TYPE_CHECKING:
    from astropy.coordinates import EarthLocation

__all__ = ["GREEN_BANK_45FT", "Site", "Weather", "standard_pressure_hpa"]


@dataclass(frozen=True)
class Site:
    """An antenna's position on the WGS84 ellipsoid.

    ``latitude_deg`` geodetic, North positive (deg); ``longitude_deg`` East positive (deg);
    ``height_m`` above the ellipsoid (m); ``name`` for reports.
    """

    latitude_deg: float
    longitude_deg: float
    height_m: float
    name: str = ""

    def __post_init__(self) -> None:
        finite_fields(self, "Site", "latitude_deg", "longitude_deg", "height_m")
        if not -90.0 <= self.latitude_deg <= 90.0:
            raise ValueError(
                f"Site latitude_deg = {self.latitude_deg} is outside -90..90; give the geodetic "
                "latitude in degrees, North positive."
            )
        if not -360.0 <= self.longitude_deg <= 360.0:
            raise ValueError(
                f"Site longitude_deg = {self.longitude_deg} is outside -360..360; give the "
                "longitude in degrees, East positive (Green Bank is -79.84)."
            )
        if not -500.0 <= self.height_m <= 10000.0:
            raise ValueError(
                f"Site height_m = {self.height_m} is not a plausible antenna height; give the "
                "height above the WGS84 ellipsoid in metres."
            )

    @property
    def latitude_rad(self) -> float:
        """Geodetic latitude (rad)."""
        return math.radians(self.latitude_deg)

    @property
    def longitude_rad(self) -> float:
        """Longitude, East positive (rad)."""
        return math.radians(self.longitude_deg)

    def earth_location(self) -> EarthLocation:
        """The site as an astropy ``EarthLocation`` (WGS84), for exact astropy transforms."""
        from astropy import units as u
        from astropy.coordinates import EarthLocation

        return EarthLocation.from_geodetic(
            lon=self.longitude_deg * u.deg, lat=self.latitude_deg * u.deg,
            height=self.height_m * u.m, ellipsoid="WGS84",
        )


#: The NRAO 45-ft (13.7 m) alt-az antenna at Green Bank (at Green Bank since 1988, after its
#: years as the GBI's remote element at Huntersville). No published survey of the 45-ft's
#: own pad was found, so these are docs/physics.md's nominal Green Bank values (latitude +38.43 deg,
#: longitude -79.84 deg, height 800 m), an assumption. The GBT, a few hundred metres away, is
#: published at 38.4331 N, 79.8398 W, about 810-825 m; the nominal values may be off the
#: 45-ft by some 10-20 arcsec of latitude/longitude. That matters only when comparing with
#: real recordings at the arcsecond level: the simulated world and the controller use the
#: same site.
GREEN_BANK_45FT = Site(38.43, -79.84, 800.0, "NRAO Green Bank 45-ft")


def standard_pressure_hpa(height_m: float) -> float:
    """Air pressure of the ICAO standard atmosphere at ``height_m`` metres (hPa).

    About 921 hPa at Green Bank (800 m): the pressure this module's refraction figures assume
    when no barometer reading is given.
    """
    require_finite(height_m, "height_m")
    return 1013.25 * (1.0 - 2.25577e-5 * float(height_m)) ** 5.25588


@dataclass(frozen=True)
class Weather:
    """Surface weather for refraction: air temperature (deg C), pressure (hPa), relative
    humidity (fraction 0..1, not percent)."""

    temperature_c: float
    pressure_hpa: float
    relative_humidity: float

    def __post_init__(self) -> None:
        finite_fields(self, "Weather", "temperature_c", "pressure_hpa", "relative_humidity")
        if not -90.0 <= self.temperature_c <= 60.0:
            raise ValueError(
                f"Weather temperature_c = {self.temperature_c} is not a plausible air "
                "temperature; give it in degrees Celsius."
            )
        if not 0.0 <= self.pressure_hpa <= 1100.0:
            raise ValueError(
                f"Weather pressure_hpa = {self.pressure_hpa} is outside 0..1100; give the "
                "station pressure in hPa (about 920 at 800 m; 0 means no atmosphere)."
            )
        if not 0.0 <= self.relative_humidity <= 1.0:
            raise ValueError(
                f"Weather relative_humidity = {self.relative_humidity} is outside 0..1; give "
                "a fraction (0.5 for 50 %), not a percentage."
            )

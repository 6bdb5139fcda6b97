"""The true sky of a simulation: where the sources really are, how bright and how big.

Positions come from the vectorized ephemeris of :mod:`controller.astro.ephemeris` (exact
astropy/ERFA on a grid, interpolated), refracted by the refraction actually present: the weather at
the time, scaled by ``refraction_scale`` (1 unless a refraction effect changes it). The control
program corrects refraction with its own model; the difference is a real pointing error.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from controller.astro.ephemeris import Ephemeris
from controller.astro.refraction import refraction_rad
from controller.astro.site import Weather

__all__ = ["Sky", "SourceConfig"]


@dataclass(frozen=True)
class SourceConfig:
    """A source as it really is: position, flux density at the observing frequency and
    the FWHM of a Gaussian of equal second moment (0 for point-like)."""

    name: str
    ra_deg: float
    dec_deg: float
    frame: str = "fk4"
    flux_jy: float = 1.0
    size_arcmin: float = 0.0
    note: str = ""


class Sky:
    """True positions (observed, i.e. refracted) and brightness of the sources."""

    def __init__(self, ephemeris: Ephemeris, sources: tuple[SourceConfig, ...],
                 weather, frequency_ghz: float):
        self.ephemeris = ephemeris
        self.sources = sources
        self.names = tuple(s.name for s in sources)
        self.flux_jy = np.array([s.flux_jy for s in sources])
        self.size_arcmin = np.array([s.size_arcmin for s in sources])
        #: true position of the brightness centroid relative to the catalogue (arcsec)
        self.position_offset_arcsec = np.zeros((len(sources), 2))
        self.weather = weather
        self.frequency_ghz = frequency_ghz
        self.refraction_scale = 1.0

    def index(self, name: str) -> int:
        return self.names.index(name)

    def refraction_rad(self, el_vacuum_rad, t_s: float) -> np.ndarray:
        """Refraction actually present (elevation increase, radians) at time ``t_s``."""
        reading = self.weather.reading(t_s)
        weather = Weather(reading.temperature_c, reading.pressure_hpa, reading.relative_humidity)
        return self.refraction_scale * refraction_rad(el_vacuum_rad, weather,
                                                      frequency_ghz=self.frequency_ghz)

    def observed_altaz_rad(self, index: int, t_s: np.ndarray,
                           t_weather_s: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """True observed azimuth and elevation of source ``index`` at times ``t_s``."""
        az, el = self.ephemeris.altaz_rad(index, t_s)
        t_w = float(np.mean(t_s)) if t_weather_s is None else t_weather_s
        el = el + self.refraction_rad(el, t_w)
        d_xel, d_el = self.position_offset_arcsec[index] * (np.pi / 648000.0)
        if d_xel or d_el:
            el = el + d_el
            az = az + d_xel / np.cos(el)
        return az, el

    def nearby(self, az_rad: float, el_rad: float, t_s: float,
               radius_deg: float = 2.0) -> list[int]:
        """Indices of the sources within ``radius_deg`` of a direction at time ``t_s``."""
        index = np.arange(len(self.sources))
        a, e = self.ephemeris.altaz_rad(index, np.full(index.size, float(t_s)))
        cos_sep = np.sin(e) * np.sin(el_rad) + np.cos(e) * np.cos(el_rad) * np.cos(a - az_rad)
        return [int(i) for i in np.flatnonzero(cos_sep >= np.cos(np.radians(radius_deg)))]

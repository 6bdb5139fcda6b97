"""Atmospheric refraction: how much the air lifts a source above its vacuum elevation (ERFA's
model, the one astropy's ``AltAz`` uses)."""

from __future__ import annotations

import math
from functools import lru_cache

import erfa
import numpy as np

from .site import Weather
from .values import scalar

__all__ = ["refraction_rad"]

#: ERFA's limits in eraAtioq's refraction: minimum cos(el) and sin(el) (the model is not
#: meant for elevations below about 3 degrees; the bending is held near its value there)
_CELMIN = 1e-6
_SELMIN = 0.05
#: any wavelength above 100 micrometres selects ERFA's radio refraction formula
_RADIO_WAVELENGTH_UM = 1.0e4
_SPEED_OF_LIGHT_UM_GHZ = 299792.458  # micrometres * GHz


@lru_cache(maxsize=256)
def _refraction_constants(pressure_hpa: float, temperature_c: float, relative_humidity: float,
                          wavelength_um: float) -> tuple[float, float]:
    refa, refb = erfa.refco(pressure_hpa, temperature_c, relative_humidity, wavelength_um)
    return float(refa), float(refb)


def refraction_rad(el_vacuum_rad, weather: Weather, *,
                   frequency_ghz: float | None = None) -> np.ndarray:
    """Elevation increase due to atmospheric refraction (rad): observed = vacuum + this.

    ``el_vacuum_rad``: vacuum (unrefracted) elevation(s) in rad. ``weather``: surface
    :class:`Weather`. ``frequency_ghz``: observing frequency; ``None`` means radio. Radio
    refraction (any frequency below 3000 GHz, i.e. wavelengths above 100 um) does not depend
    on frequency; above that ERFA's optical formula for that wavelength is used.

    The model is ERFA's (``erfa.refco`` A tan z + B tan^3 z, inverted as in ``eraAtioq``), the
    one astropy's ``AltAz`` uses with pressure, temperature, humidity and ``obswl``: at 10 C,
    50 % humidity, 920 hPa it gives 5.29' at 10 deg, 2.63' at 20 deg, 0.965' at 45 deg
    (docs/physics.md: 5.3', 2.6', 0.97'). Below about 3 deg elevation (ERFA's limit) the bending is
    held near its 3 deg value (about 11.5' at 920 hPa); the model is not meant for the horizon.
    """
    if not isinstance(weather, Weather):
        raise ValueError(
            f"weather must be a controller.astro.site.Weather, got {type(weather).__name__}; build "
            "one with Weather(temperature_c, pressure_hpa, relative_humidity)."
        )
    if frequency_ghz is None:
        wavelength_um = _RADIO_WAVELENGTH_UM
    else:
        frequency = float(frequency_ghz)
        if not (math.isfinite(frequency) and frequency > 0.0):
            raise ValueError(
                f"frequency_ghz = {frequency_ghz} must be a positive number of GHz (8.4 for "
                "X-band), or None for radio."
            )
        wavelength_um = _SPEED_OF_LIGHT_UM_GHZ / frequency
    refa, refb = _refraction_constants(weather.pressure_hpa, weather.temperature_c,
                                       weather.relative_humidity, wavelength_um)
    el = np.asarray(el_vacuum_rad, dtype=float)
    sin_el = np.sin(el)
    cos_el_true = np.cos(el)
    cos_el = np.maximum(cos_el_true, _CELMIN)
    sin_el_clamped = np.maximum(sin_el, _SELMIN)
    tan_z = cos_el / sin_el_clamped
    w = refb * tan_z * tan_z
    # A tan z + B tan^3 z evaluated at the observed zenith distance by one Newton step
    delta = (refa + w) * tan_z / (1.0 + (refa + 3.0 * w) / (sin_el_clamped * sin_el_clamped))
    cos_delta = 1.0 - 0.5 * delta * delta
    horizontal = cos_el_true * np.abs(cos_delta - delta * sin_el_clamped / cos_el)
    up = cos_delta * sin_el + delta * cos_el
    return scalar(np.arctan2(up, horizontal) - el)

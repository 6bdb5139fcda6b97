"""The weather of a campaign: air temperature through the day, pressure, humidity, wind.

The air temperature follows a daily cycle with its minimum near sunrise and its maximum in
the early afternoon (local mean solar time), rising as a half cosine over the morning and
falling as a half cosine over the rest of the day, plus a slow random wander drawn per run.
The wind follows the same daily shape between a calm night and a breezier afternoon (surface
wind typically peaks with the afternoon's convective mixing).
For 8 Feb 1990 (Ghigo 1990, section IV: 0 to 15 C by day, -4 to 3 C at night) the scenario sets
minimum -4 C, maximum 15 C.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from controller.protocol import WeatherReading

from .effects.thermal import ScalarInterpolator, ou_series

__all__ = ["WeatherConfig", "WeatherModel"]


@dataclass(frozen=True)
class WeatherConfig:
    """Scenario weather (units in the names)."""

    air_min_c: float = -4.0
    air_max_c: float = 15.0
    #: local mean solar times of the daily minimum and maximum (hours)
    min_local_h: float = 7.0
    max_local_h: float = 14.5
    #: rms and correlation time of the random wander about the daily curve
    wander_rms_c: float = 0.5
    wander_timescale_s: float = 7200.0
    pressure_hpa: float = 920.0
    relative_humidity: float = 0.5
    #: wind at the coolest hour; ``wind_day_m_s`` at the warmest (None: constant wind)
    wind_speed_m_s: float = 3.0
    wind_day_m_s: float | None = None


class WeatherModel:
    """Weather as a function of campaign time (seconds since the epoch)."""

    GRID_STEP_S = 300.0

    def __init__(self, config: WeatherConfig, epoch_utc_hours: float, longitude_deg: float,
                 duration_s: float, rng: np.random.Generator, spinup_s: float = 86400.0):
        self.config = config
        self.pressure_hpa = config.pressure_hpa
        self.relative_humidity = config.relative_humidity
        self.wind_speed_m_s = config.wind_speed_m_s
        self._epoch_local_h = epoch_utc_hours + longitude_deg / 15.0
        step = self.GRID_STEP_S
        self._t = np.arange(-spinup_s, duration_s + 2 * step, step)
        self._wander = ou_series(rng, self._t.size, step, config.wander_timescale_s,
                                 config.wander_rms_c)
        self._wander_now = None

    def daily_curve_c(self, t_s) -> np.ndarray:
        """The deterministic daily temperature curve (C)."""
        c = self.config
        if isinstance(t_s, float):  # the World asks once per integration: plain floats
            return self._daily_curve_scalar_c(t_s)
        local_h = (self._epoch_local_h + np.asarray(t_s, dtype=float) / 3600.0) % 24.0
        rise_h = (c.max_local_h - c.min_local_h) % 24.0
        since_min = (local_h - c.min_local_h) % 24.0
        rising = since_min < rise_h
        phase = np.where(rising, since_min / rise_h,
                         1.0 + (since_min - rise_h) / (24.0 - rise_h))
        # phase 0 -> minimum, 1 -> maximum, 2 -> minimum again
        return c.air_min_c + (c.air_max_c - c.air_min_c) * 0.5 * (1.0 - np.cos(math.pi * phase))

    def _daily_curve_scalar_c(self, t_s: float) -> float:
        c = self.config
        local_h = (self._epoch_local_h + t_s / 3600.0) % 24.0
        rise_h = (c.max_local_h - c.min_local_h) % 24.0
        since_min = (local_h - c.min_local_h) % 24.0
        phase = (since_min / rise_h if since_min < rise_h
                 else 1.0 + (since_min - rise_h) / (24.0 - rise_h))
        return c.air_min_c + (c.air_max_c - c.air_min_c) * 0.5 * (1.0 - math.cos(math.pi * phase))

    def wind_m_s(self, t_s) -> np.ndarray:
        """Wind speed (m/s) at time(s) ``t_s``."""
        if self.config.wind_day_m_s is None:
            return np.full(np.shape(t_s), self.config.wind_speed_m_s)
        return self._wind_from_daily(self.daily_curve_c(t_s))

    def _wind_from_daily(self, daily_c):
        """Wind speed (m/s) where the daily temperature curve stands at ``daily_c`` (C): the
        night's speed at the daily minimum, the day's at the maximum."""
        c = self.config
        if c.wind_day_m_s is None:
            return c.wind_speed_m_s
        shape = (daily_c - c.air_min_c) / max(c.air_max_c - c.air_min_c, 1e-9)
        return c.wind_speed_m_s + (c.wind_day_m_s - c.wind_speed_m_s) * shape

    def air_temperature_c(self, t_s) -> np.ndarray:
        """Air temperature (C): the daily curve plus this run's random wander."""
        return self.daily_curve_c(t_s) + np.interp(t_s, self._t, self._wander)

    def reading(self, t_s: float) -> WeatherReading:
        """What the weather sensors report at ``t_s``."""
        t_s = float(t_s)
        if self._wander_now is None:
            self._wander_now = ScalarInterpolator(self._t, [self._wander])
        daily_c = self._daily_curve_scalar_c(t_s)
        wind = self._wind_from_daily(daily_c)
        return WeatherReading(
            temperature_c=daily_c + self._wander_now(t_s)[0],
            pressure_hpa=self.pressure_hpa,
            relative_humidity=self.relative_humidity,
            wind_speed_m_s=float(wind),
        )

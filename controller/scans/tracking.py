"""Source trajectories: where the encoders must point to follow a source.

encoder = observed position (apparent place + the controller's refraction correction)
          + pointing-model offset (indicated - true) + the controller's running correction.

The refraction and the model offset change slowly along a track; they are evaluated exactly
on nodes every ``NODE_STEP_S`` and interpolated linearly (the curvature over a minute is
below 0.01"). The commanded path itself is tabulated every ``TABLE_STEP_S`` over the next
``NODE_SPAN_S`` and interpolated linearly: with a 2 s step the error is below 0.01" up to
85 deg elevation, and a call costs a few microseconds. Outside the table (slew planning
looks an hour ahead for the cable wrap) positions are computed exactly. The table is kept in
encoder degrees, so that an antenna driven over the wire with it as a program track
(:meth:`SourceTrajectory.program_track`) interpolates to the same bits.

On an equatorial mount (``frame``) the encoder coordinates are hour angle and declination of
the observed (refracted) place, the model offset is evaluated there, and the running
correction is cross-declination and declination. ``feed_rad``: the feed angle the model's
feed terms (if any) are evaluated at.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from controller.astro.ephemeris import Ephemeris
from controller.astro.frames import MountFrame
from controller.astro.refraction import refraction_rad
from controller.astro.site import Weather
from controller.pointing.model import PointingModel
from controller.units import DEG_PER_RAD, RAD_PER_ARCMIN

__all__ = ["ProgramTrack", "RefractionCorrection", "SourceTrajectory", "standard_weather"]


class ProgramTrack(NamedTuple):
    """A program track's table: clock times (s) and encoder azimuth and elevation (deg)."""

    t_s: np.ndarray
    az_deg: np.ndarray
    el_deg: np.ndarray

NODE_STEP_S = 30.0
NODE_SPAN_S = 900.0
TABLE_STEP_S = 2.0


def standard_weather(height_m: float) -> Weather:
    """10 C, 50% RH and the standard-atmosphere pressure at ``height_m``."""
    pressure = 1013.25 * (1.0 - 2.25577e-5 * height_m) ** 5.25588
    return Weather(temperature_c=10.0, pressure_hpa=pressure, relative_humidity=0.5)


@dataclass(frozen=True)
class RefractionCorrection:
    """The refraction the controller corrects: ``mode`` "weather", "standard" or "none"."""

    mode: str
    weather: Weather | None
    frequency_ghz: float

    def rad(self, el_vacuum_rad) -> np.ndarray:
        if self.mode == "none" or self.weather is None:
            return np.zeros_like(np.asarray(el_vacuum_rad, dtype=float))
        return refraction_rad(el_vacuum_rad, self.weather, frequency_ghz=self.frequency_ghz)


class SourceTrajectory:
    """Callable ``t_clock_s -> (az_deg, el_deg)`` of encoder commands for one source."""

    def __init__(self, ephemeris: Ephemeris, index: int, model: PointingModel,
                 refraction: RefractionCorrection, t_start_s: float,
                 correction_arcmin: tuple[float, float] = (0.0, 0.0),
                 frame: MountFrame | None = None, feed_rad: float | None = None):
        self._frame = frame if frame is not None and not frame.is_altaz else None
        self.feed_rad = feed_rad
        self.ephemeris = ephemeris
        self.index = index
        self.model = model
        self.refraction = refraction
        self.correction_arcmin = correction_arcmin
        self._t0 = t_start_s - NODE_STEP_S
        self._build(self._t0)

    def _build(self, t0: float) -> None:
        limit = self.ephemeris.duration_s + self.ephemeris.margin_s
        t_nodes = t0 + np.arange(0.0, NODE_SPAN_S + NODE_STEP_S, NODE_STEP_S)
        t_nodes = t_nodes[t_nodes <= limit]
        if t_nodes.size < 2:
            t_nodes = np.array([max(limit - NODE_STEP_S, 0.0), limit])
        self._t_nodes = t_nodes
        _, _, self._refraction, self._offset_az, self._offset_el = self._exact(t_nodes)
        t_table = np.arange(t_nodes[0], t_nodes[-1] + 0.5 * TABLE_STEP_S, TABLE_STEP_S)
        t_table = t_table[t_table <= t_nodes[-1]]
        az, el = self.ephemeris.altaz_rad(self.index, t_table)
        self._t_table = t_table
        if self._frame is not None:  # equatorial: (HA, Dec) of the observed place
            lon, lat = self._frame.from_altaz(az, el + np.interp(t_table, t_nodes,
                                                                 self._refraction))
            self._table_az_deg = (np.unwrap(lon) + np.interp(t_table, t_nodes,
                                                             self._offset_az)) * DEG_PER_RAD
            self._table_el_deg = (lat + np.interp(t_table, t_nodes,
                                                  self._offset_el)) * DEG_PER_RAD
            return
        self._table_az_deg = (np.unwrap(az)
                              + np.interp(t_table, t_nodes, self._offset_az)) * DEG_PER_RAD
        self._table_el_deg = (el + np.interp(t_table, t_nodes,
                                             self._refraction + self._offset_el)) * DEG_PER_RAD

    def _exact(self, t: np.ndarray):
        """Vacuum position, refraction and model + correction offsets at times ``t``."""
        az, el = self.ephemeris.altaz_rad(self.index, t)
        refraction = self.refraction.rad(el)
        el_obs = el + refraction
        xel_c, el_c = self.correction_arcmin
        if self._frame is not None:  # model and correction in (HA, Dec): el_obs is Dec
            ha, el_obs = self._frame.from_altaz(az, el_obs)
            d_az, d_el = self.model.offset_rad(ha, el_obs, self.feed_rad)
        elif self.feed_rad is not None:
            d_az, d_el = self.model.offset_rad(az, el_obs, self.feed_rad)
        else:
            d_az, d_el = self.model.offset_rad(az, el_obs)
        return (az, el, refraction, d_az + xel_c * RAD_PER_ARCMIN / np.cos(el_obs),
                d_el + el_c * RAD_PER_ARCMIN)

    def _covered(self, t: np.ndarray) -> bool:
        return bool(t.size == 0 or (t.min() >= self._t_table[0]
                                    and t.max() <= self._t_table[-1]))

    def observed_rad(self, t_s) -> tuple[np.ndarray, np.ndarray]:
        """Observed (refracted) azimuth and elevation the controller believes in (radians)."""
        t = np.asarray(t_s, dtype=float)
        if not self._covered(t):
            az, el, refraction, _, _ = self._exact(t)
            return az, el + refraction
        az, el = self.ephemeris.altaz_rad(self.index, t)
        return az, el + np.interp(t, self._t_nodes, self._refraction)

    def __call__(self, t_s) -> tuple[np.ndarray, np.ndarray]:
        t = np.asarray(t_s, dtype=float)
        if self._covered(t):
            return (np.interp(t, self._t_table, self._table_az_deg) % 360.0,
                    np.interp(t, self._t_table, self._table_el_deg))
        # rare: slew planning looks an hour ahead for the cable wrap
        az, el, refraction, d_az, d_el = self._exact(t)
        if self._frame is not None:
            az, el = self._frame.from_altaz(az, el + refraction)
            refraction = 0.0
        az, el = az + d_az, el + refraction + d_el
        return (az * DEG_PER_RAD) % 360.0, el * DEG_PER_RAD

    def program_track(self) -> ProgramTrack:
        """The table this trajectory interpolates linearly: clock times (s), encoder
        azimuth (deg, continuous: not reduced to 0..360) and elevation (deg). Between its
        first and last time the trajectory is ``np.interp`` on it (azimuth then modulo 360),
        bit for bit, so that an antenna given the table (a program track) points exactly
        where this trajectory would; elsewhere it is computed exactly (:meth:`covers`)."""
        return ProgramTrack(self._t_table.copy(), self._table_az_deg.copy(),
                            self._table_el_deg.copy())

    def covers(self, t_s) -> bool:
        """Whether every time of ``t_s`` lies within :meth:`program_track`'s table."""
        return self._covered(np.asarray(t_s, dtype=float))

    def elevation_deg(self, t_s: float) -> float:
        """Commanded elevation at one instant (degrees); the declination on an equatorial
        mount (the latitude-like axis whose cosine scales cross-axis steps)."""
        return float(self(np.array([t_s]))[1][0])

    def sky_elevation_deg(self, t_s: float) -> float:
        """Where the beam should be on the sky at one instant: the commanded elevation less
        the pointing model's and the correction's share (degrees; the declination on an
        equatorial mount). Azimuth steps of a cross scan are divided by its cosine: a
        source at sky elevation E is n D / cos E away in azimuth from a beam at n D in
        cross-elevation, wherever the model puts the encoder (an encoder d above the sky
        would scale the steps by 1 + d tan E: 3.4% at 85 deg for d = 12')."""
        t = np.array([t_s])
        if self._covered(t):
            offset_el = np.interp(t, self._t_nodes, self._offset_el)
        else:
            offset_el = self._exact(t)[4]
        return float(self(t)[1][0] - offset_el[0] * DEG_PER_RAD)

    @staticmethod
    def cos_el(el_deg: float) -> float:
        return math.cos(math.radians(el_deg))

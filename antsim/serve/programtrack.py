"""The program track: a table of time-tagged encoder positions the antenna interpolates.

Real antenna control units take a program-track table from the control software, which
computes the positions with its own ephemeris and pointing model, and interpolate between
its points. This one interpolates linearly (``numpy.interp``, so that a table taken from
:meth:`controller.scans.tracking.SourceTrajectory.program_track` reproduces that trajectory bit
for bit), azimuth the shorter way round between two points (a table may give azimuths
modulo 360), and holds the first and last points before and after the table. Points may be
added later (:meth:`ProgramTrack.add`), in any order; a point at a time already in the
table replaces it.

Units: clock seconds since the scenario epoch, encoder degrees (azimuth North = 0, East =
90; on an equatorial mount hour angle, positive West, and declination).
"""

from __future__ import annotations

import numpy as np

__all__ = ["ProgramTrack", "TableError"]

#: at most this many points in one table (a day at 1 s)
MAX_POINTS = 86400
#: azimuths (or hour angles) lie within two turns either way: modulo 360, or on a cable wrap
AZ_LIMIT_DEG = 720.0


class TableError(ValueError):
    """A program-track table that cannot be used; the message says which value."""


class ProgramTrack:
    """A :data:`controller.protocol.Trajectory` given by a table of points."""

    def __init__(self, t_s, az_deg, el_deg, times_s: tuple[float, float] | None = None):
        self.t_s = np.empty(0)
        self.az_deg = np.empty(0)
        self.el_deg = np.empty(0)
        self._wrapped = np.empty(0, dtype=bool)
        self.add(t_s, az_deg, el_deg, times_s)

    @classmethod
    def from_numbers(cls, values: list[float], track: ProgramTrack | None = None,
                     times_s: tuple[float, float] | None = None) -> ProgramTrack:
        """A table (or ``track`` with points added) from flat triplets t, az, el; with
        ``times_s`` (first, last) the times must lie within it."""
        t, az, el = _triplets(values)
        if track is None:
            return cls(t, az, el, times_s)
        track.add(t, az, el, times_s)
        return track

    def add(self, t_s, az_deg, el_deg, times_s: tuple[float, float] | None = None) -> None:
        """Add points (arrays of equal length), times within ``times_s`` (first, last; None:
        any); raises :class:`TableError`."""
        t = np.asarray(t_s, dtype=float).ravel()
        az = np.asarray(az_deg, dtype=float).ravel()
        el = np.asarray(el_deg, dtype=float).ravel()
        if not (t.size == az.size == el.size):
            raise TableError("the table needs as many azimuths and elevations as times")
        if t.size == 0 and self.t_s.size == 0:
            raise TableError("the table has no points: give at least one (t, az, el)")
        for name, x in (("time", t), ("azimuth", az), ("elevation", el)):
            bad = ~np.isfinite(x)
            if bad.any():
                i = int(np.argmax(bad))
                raise TableError(f"point {i + 1}: {name} {float(x[i])!r} is not a finite "
                                 "number")
        if np.any(np.abs(el) > 90.0):
            i = int(np.argmax(np.abs(el) > 90.0))
            raise TableError(f"point {i + 1}: elevation {float(el[i])!r} deg is outside "
                             "-90..90")
        if np.any(np.abs(az) > AZ_LIMIT_DEG):
            i = int(np.argmax(np.abs(az) > AZ_LIMIT_DEG))
            raise TableError(f"point {i + 1}: azimuth {float(az[i])!r} deg is outside "
                             f"-{AZ_LIMIT_DEG:g}..{AZ_LIMIT_DEG:g}")
        if times_s is not None and np.any((t < times_s[0]) | (t > times_s[1])):
            i = int(np.argmax((t < times_s[0]) | (t > times_s[1])))
            raise TableError(f"point {i + 1}: time {float(t[i])!r} s is outside "
                             f"{times_s[0]:g}..{times_s[1]:g} s (a day around the simulation)")
        if t.size > 1 and np.any(np.diff(t) <= 0.0):
            i = int(np.argmax(np.diff(t) <= 0.0))
            raise TableError(f"point {i + 2}: time {float(t[i + 1])!r} s does not follow "
                             f"{float(t[i])!r} s (times must increase)")
        if self.t_s.size + t.size > MAX_POINTS:
            raise TableError(f"the table would hold more than {MAX_POINTS} points")
        keep = ~np.isin(self.t_s, t)
        all_t = np.concatenate([self.t_s[keep], t])
        order = np.argsort(all_t, kind="stable")
        self.t_s = all_t[order]
        self.az_deg = np.concatenate([self.az_deg[keep], az])[order]
        self.el_deg = np.concatenate([self.el_deg[keep], el])[order]
        # segments whose azimuths are more than half a turn apart: across 0/360
        self._wrapped = np.abs(np.diff(self.az_deg)) > 180.0

    @property
    def start_s(self) -> float:
        return float(self.t_s[0])

    @property
    def end_s(self) -> float:
        return float(self.t_s[-1])

    def __len__(self) -> int:
        return int(self.t_s.size)

    def __call__(self, t_s) -> tuple[np.ndarray, np.ndarray]:
        """Encoder azimuth in [0, 360) and elevation (deg) at clock time(s) ``t_s``."""
        t = np.asarray(t_s, dtype=float)
        az = np.interp(t, self.t_s, self.az_deg)
        el = np.interp(t, self.t_s, self.el_deg)
        if self._wrapped.any():
            az = self._shorter_way(np.atleast_1d(t), np.atleast_1d(az)).reshape(np.shape(az))
        return az % 360.0, el

    def _shorter_way(self, t: np.ndarray, az: np.ndarray) -> np.ndarray:
        """Azimuths strictly inside segments that cross 0/360, interpolated the short way
        (at the points themselves ``np.interp`` already gives their values exactly)."""
        j = np.searchsorted(self.t_s, t, side="right") - 1
        inside = (j >= 0) & (j < self.t_s.size - 1)
        inside[inside] &= self._wrapped[j[inside]] & (t[inside] > self.t_s[j[inside]])
        if not inside.any():
            return az
        az = np.array(az, dtype=float, copy=True)
        k = j[inside]
        frac = (t[inside] - self.t_s[k]) / (self.t_s[k + 1] - self.t_s[k])
        step = (self.az_deg[k + 1] - self.az_deg[k] + 180.0) % 360.0 - 180.0
        az[inside] = self.az_deg[k] + frac * step
        return az


def _triplets(values: list[float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    if len(values) % 3 != 0 or not values:
        raise TableError(f"a table is triplets of time, azimuth, elevation: got {len(values)} "
                         "numbers" + ("" if values else " (none)"))
    a = np.asarray(values, dtype=float).reshape(-1, 3)
    if not np.all(np.isfinite(a)):
        i, c = (int(x[0]) for x in np.nonzero(~np.isfinite(a)))
        name = ("time", "azimuth", "elevation")[c]
        raise TableError(f"point {i + 1}: {name} {float(a[i, c])!r} is not a finite number")
    return a[:, 0], a[:, 1], a[:, 2]


"""Constraints: whether a target may be observed at a time (elevation window, an equatorial
mount's hour angles, a control program's declination limit, day or night, revisit interval),
and the history of what was observed."""

from __future__ import annotations

import bisect
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from .observer import Observer, Target

__all__ = ["Constraint", "DeclinationConstraint", "ElevationConstraint", "History",
           "HourAngleConstraint", "RevisitConstraint", "WindowConstraint"]


@dataclass
class History:
    """What has been observed: times, targets and positions (deg)."""

    t_s: list[float] = field(default_factory=list)
    names: list[str] = field(default_factory=list)
    az_deg: list[float] = field(default_factory=list)
    el_deg: list[float] = field(default_factory=list)
    #: whether ``t_s`` never decreased, so that :meth:`recent` may bisect it
    in_time_order: bool = field(init=False, repr=False)
    #: the time of each name's latest entry (a search back through the history took as
    #: long as the history for a source not seen for long)
    _latest: dict[str, float] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self.in_time_order = all(a <= b for a, b in zip(self.t_s, self.t_s[1:], strict=False))
        self._latest = dict(zip(self.names, self.t_s, strict=True))

    def add(self, t_s: float, name: str, az_deg: float, el_deg: float) -> None:
        if self.t_s and t_s < self.t_s[-1]:
            self.in_time_order = False
        self.t_s.append(t_s)
        self.names.append(name)
        self.az_deg.append(az_deg)
        self.el_deg.append(el_deg)
        self._latest[name] = t_s

    def last_time(self, name: str) -> float | None:
        """The time of ``name``'s latest entry (the last added), None if it has none."""
        return self._latest.get(name)

    def recent(self, t_s: float, memory_s: float) -> range | list[int]:
        """Indices of the observations with ``t_s - t <= memory_s``. Bisected, because a scan
        over the whole history made a month-long campaign quadratic in its length; the same
        comparison as the scan, so the same indices."""
        if not self.in_time_order:
            return [i for i, t in enumerate(self.t_s) if t_s - t <= memory_s]
        start = bisect.bisect_left(self.t_s, True, key=lambda t: t_s - t <= memory_s)
        return range(start, len(self.t_s))


class Constraint:
    """Which of ``targets`` may be observed at ``t_s`` (campaign seconds): a bool array."""

    def mask(self, observer: Observer, targets: Sequence[Target], t_s: float,
             history: History) -> np.ndarray:
        raise NotImplementedError


@dataclass(frozen=True)
class ElevationConstraint(Constraint):
    min_deg: float
    max_deg: float
    #: the target must stay within limits for this long (a whole scan) (s)
    duration_s: float = 0.0

    def mask(self, observer, targets, t_s, history) -> np.ndarray:
        ok = np.ones(len(targets), dtype=bool)
        for t in (t_s + self.duration_s, t_s):  # now last: the policy asks for now next
            _, el = observer.altaz_all_deg(targets, t)
            ok &= (el >= self.min_deg) & (el <= self.max_deg)
        return ok


@dataclass(frozen=True)
class HourAngleConstraint(Constraint):
    """An equatorial mount's hour-angle range: |HA| <= ``limit_deg`` now and a scan later."""

    limit_deg: float
    duration_s: float = 0.0

    def mask(self, observer, targets, t_s, history) -> np.ndarray:
        index = np.array([tg.index for tg in targets])
        ok = np.ones(len(targets), dtype=bool)
        for t in (t_s, t_s + self.duration_s):
            ha, _ = observer.ephemeris.hadec_rad(index, np.full(index.size, float(t)))
            ok &= np.abs(np.degrees(ha)) <= self.limit_deg
        return ok


@dataclass(frozen=True)
class DeclinationConstraint(Constraint):
    """Sources at or below ``max_deg`` of (apparent) declination only: a control program's
    limit, such as the 140-ft's in 1981 (no pointing above +72 deg, Crane 1981)."""

    max_deg: float

    def mask(self, observer, targets, t_s, history) -> np.ndarray:
        index = np.array([tg.index for tg in targets])
        _, dec = observer.ephemeris.hadec_rad(index, np.full(index.size, float(t_s)))
        return np.degrees(dec) <= self.max_deg


@dataclass(frozen=True)
class WindowConstraint(Constraint):
    """Observe only by day (Sun above 0 deg), only by night (Sun below the observer's night
    threshold, -12 deg unless the campaign says otherwise), or always."""

    window: str = "all"

    def mask(self, observer, targets, t_s, history) -> np.ndarray:
        if self.window == "day":
            ok = observer.is_day(t_s)
        elif self.window == "night":
            ok = observer.is_night(t_s)
        else:
            ok = True
        return np.full(len(targets), ok, dtype=bool)


@dataclass(frozen=True)
class RevisitConstraint(Constraint):
    min_interval_s: float

    def mask(self, observer, targets, t_s, history) -> np.ndarray:
        out = np.ones(len(targets), dtype=bool)
        for i, tg in enumerate(targets):
            last = history.last_time(tg.name)
            out[i] = last is None or t_s - last >= self.min_interval_s
        return out

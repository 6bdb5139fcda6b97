"""Choosing the next pointing source: observer, targets, constraints and a scheduler policy.

Split as astroplan splits planning: an :class:`Observer` (the site and its ephemeris, with the
Sun), :class:`Target` s (catalogue sources), :class:`Constraint` s that say whether a target
may be observed at a time (elevation window, day/night window, revisit interval), and a
:class:`Scheduler` policy that picks one target among those allowed. Policies are swappable:
``spread`` spreads the observations over the sky like Figure 1 of the 1990 report, a
``round_robin`` cycles through the allowed sources.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from controller.astro.ephemeris import Ephemeris
from controller.astro.sun import DAY_SUN_MIN_DEG, NIGHT_SUN_MAX_DEG

from .config import SchedulerConfig

__all__ = [
    "Constraint",
    "ElevationConstraint",
    "HourAngleConstraint",
    "Observer",
    "RevisitConstraint",
    "RoundRobinScheduler",
    "Scheduler",
    "SpreadScheduler",
    "Target",
    "WindowConstraint",
    "make_scheduler",
    "never_rises",
    "never_visible",
]


@dataclass(frozen=True)
class Target:
    """A source the scheduler may choose; ``index`` is its position in the ephemeris."""

    name: str
    index: int


@dataclass
class Observer:
    """The site's view of the sky: positions of targets and of the Sun at campaign times."""

    ephemeris: Ephemeris
    _last: tuple | None = field(default=None, init=False, repr=False, compare=False)

    def altaz_deg(self, target: Target, t_s: float) -> tuple[float, float]:
        az, el = self.ephemeris.altaz_rad(target.index, np.array([t_s]))
        return math.degrees(az[0]), math.degrees(el[0])

    def altaz_all_deg(self, targets: Sequence[Target], t_s: float) -> tuple[np.ndarray, np.ndarray]:
        """Azimuths and elevations (deg) of several targets at one time, in one call (the
        last time's answer is kept: a decision asks its constraints, then its policy)."""
        t = float(t_s)
        index = tuple(tg.index for tg in targets)
        cached = self._last
        if cached is not None and cached[0] == t and set(index) <= cached[1].keys():
            where = cached[1]
            return cached[2][[where[i] for i in index]], cached[3][[where[i] for i in index]]
        az, el = self.ephemeris.altaz_rad(np.array(index), np.full(len(index), t))
        az_deg, el_deg = np.degrees(az), np.degrees(el)
        self._last = (t, {i: k for k, i in enumerate(index)}, az_deg, el_deg)
        return az_deg, el_deg

    def sun_el_deg(self, t_s) -> np.ndarray:
        return np.degrees(self.ephemeris.sun_altaz_rad(np.atleast_1d(t_s))[1])

    def is_day(self, t_s: float) -> bool:
        return bool(self.sun_el_deg(t_s)[0] > DAY_SUN_MIN_DEG)

    def is_night(self, t_s: float) -> bool:
        return bool(self.sun_el_deg(t_s)[0] < NIGHT_SUN_MAX_DEG)


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
class WindowConstraint(Constraint):
    """Observe only by day (Sun above 0 deg), only by night (Sun below -12 deg), or always."""

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


class Scheduler:
    """Base policy: filter targets by the constraints, then :meth:`choose` one."""

    def __init__(self, observer: Observer, targets: Sequence[Target],
                 constraints: Sequence[Constraint]):
        self.observer = observer
        self.targets = list(targets)
        self.constraints = list(constraints)
        self.history = History()

    def allowed(self, t_s: float) -> list[Target]:
        ok = np.ones(len(self.targets), dtype=bool)
        for constraint in self.constraints:
            ok &= constraint.mask(self.observer, self.targets, t_s, self.history)
        return [tg for tg, keep in zip(self.targets, ok, strict=True) if keep]

    def next_target(self, t_s: float, position_deg: tuple[float, float]) -> Target | None:
        """The target to observe next at ``t_s`` from encoder ``position_deg``, or None."""
        allowed = self.allowed(t_s)
        if not allowed:
            return None
        return self.choose(t_s, position_deg, allowed)

    def choose(self, t_s, position_deg, allowed: list[Target]) -> Target:
        raise NotImplementedError

    def record(self, t_s: float, target: Target) -> None:
        az, el = self.observer.altaz_deg(target, t_s)
        self.history.add(t_s, target.name, az, el)


class RoundRobinScheduler(Scheduler):
    """The allowed target observed least recently (ties: catalogue order)."""

    def choose(self, t_s, position_deg, allowed):
        def key(tg):
            last = self.history.last_time(tg.name)
            return (-math.inf if last is None else last, tg.index)

        return min(allowed, key=key)


class SpreadScheduler(Scheduler):
    """Spread observations over the sky: maximise the distance to recent observations.

    Score of a target = angular distance (deg) from its position now to the nearest position
    observed in the last ``memory_s``, minus ``slew_weight`` times the slew in degrees of the
    longer axis per ten degrees. Deterministic: ties go to catalogue order.
    """

    def __init__(self, observer, targets, constraints, slew_weight: float = 0.5,
                 memory_s: float = 6 * 3600.0):
        super().__init__(observer, targets, constraints)
        self.slew_weight = slew_weight
        self.memory_s = memory_s

    def choose(self, t_s, position_deg, allowed):
        hist = self.history
        recent = hist.recent(t_s, self.memory_s)
        if recent:
            az_h = np.radians(np.array([hist.az_deg[i] for i in recent]))
            el_h = np.radians(np.array([hist.el_deg[i] for i in recent]))
        az_all, el_all = self.observer.altaz_all_deg(allowed, t_s)
        best, best_score = None, -math.inf
        for tg, az, el in zip(allowed, az_all, el_all, strict=True):
            if recent:
                a, e = math.radians(az), math.radians(el)
                cos_sep = np.sin(e) * np.sin(el_h) + np.cos(e) * np.cos(el_h) * np.cos(a - az_h)
                gain = math.degrees(math.acos(min(1.0, float(np.max(cos_sep)))))
            else:
                gain = 0.0
            d_az = abs((az - position_deg[0] + 180.0) % 360.0 - 180.0)
            d_el = abs(el - position_deg[1])
            score = gain - self.slew_weight * max(d_az / 3.0, d_el) / 10.0
            if score > best_score + 1e-9:
                best, best_score = tg, score
        return best


def never_visible(observer: Observer, targets: Sequence[Target], config: SchedulerConfig,
                  duration_s: float, step_s: float = 300.0) -> list[Target]:
    """Targets never inside the elevation window during the campaign (checked every
    ``step_s``)."""
    times = np.arange(0.0, duration_s + step_s, step_s)
    times = times[times <= duration_s]
    missing = []
    for tg in targets:
        _, el = observer.ephemeris.altaz_rad(tg.index, times)
        el_deg = np.degrees(el)
        inside = (el_deg >= config.elevation_min_deg) & (el_deg <= config.elevation_max_deg)
        if not inside.any():
            missing.append(tg)
    return missing


def never_rises(observer: Observer, targets: Sequence[Target], latitude_deg: float,
                min_el_deg: float) -> list[Target]:
    """Targets whose transit elevation, 90 - |latitude - declination|, stays below
    ``min_el_deg``: unobservable from this site on any day."""
    out = []
    for tg in targets:
        _, dec = observer.ephemeris.hadec_rad(tg.index, 0.0)
        if 90.0 - abs(latitude_deg - math.degrees(float(dec))) < min_el_deg:
            out.append(tg)
    return out


def make_scheduler(config: SchedulerConfig, observer: Observer, targets: Sequence[Target],
                   scan_duration_s: float) -> Scheduler:
    """The scheduler a :class:`SchedulerConfig` asks for."""
    constraints: list[Constraint] = [
        ElevationConstraint(config.elevation_min_deg, config.elevation_max_deg, scan_duration_s),
        WindowConstraint(config.window),
        RevisitConstraint(config.min_revisit_s),
    ]
    if config.hour_angle_limit_deg is not None:
        constraints.append(HourAngleConstraint(config.hour_angle_limit_deg, scan_duration_s))
    if config.policy == "round_robin":
        return RoundRobinScheduler(observer, targets, constraints)
    return SpreadScheduler(observer, targets, constraints, slew_weight=config.slew_weight)

"""Choosing the next pointing source: observer, targets, constraints and a scheduler policy.

Split as astroplan splits planning: an :class:`~.observer.Observer` (the site and its
ephemeris, with the Sun) and :class:`~.observer.Target` s (catalogue sources) in
:mod:`.observer`, :class:`~.constraints.Constraint` s that say whether a target may be
observed at a time (elevation window, day/night window, revisit interval) in
:mod:`.constraints`, and here a :class:`Scheduler` policy that picks one target among those
allowed. Policies are swappable:
``spread`` spreads the observations over the sky like Figure 1 of the 1990 report, a
``round_robin`` cycles through the allowed sources.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from .config import SchedulerConfig
from .constraints import (
    Constraint,
    DeclinationConstraint,
    ElevationConstraint,
    History,
    HourAngleConstraint,
    RevisitConstraint,
    WindowConstraint,
)
from .observer import Observer, Target

__all__ = ["RoundRobinScheduler", "Scheduler", "SpreadScheduler", "make_scheduler"]


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
    if config.declination_max_deg is not None:
        constraints.append(DeclinationConstraint(config.declination_max_deg))
    if config.policy == "round_robin":
        return RoundRobinScheduler(observer, targets, constraints)
    return SpreadScheduler(observer, targets, constraints, slew_weight=config.slew_weight)

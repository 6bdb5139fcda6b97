"""The observer: the site's view of the sky (targets and the Sun at campaign times), and the
catalogue sources that can never be observed from it.

As astroplan splits planning: this module (observer, targets), :mod:`.constraints` (which
targets may be observed when, and the history of what was), :mod:`.scheduler` (the policy
that picks one).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from controller.astro.ephemeris import Ephemeris
from controller.astro.sun import DAY_SUN_MIN_DEG, NIGHT_SUN_MAX_DEG

from .config import SchedulerConfig

__all__ = ["Observer", "Target", "never_rises", "never_visible"]


@dataclass(frozen=True)
class Target:
    """A source the scheduler may choose; ``index`` is its position in the ephemeris."""

    name: str
    index: int


@dataclass
class Observer:
    """The site's view of the sky: positions of targets and of the Sun at campaign times."""

    ephemeris: Ephemeris
    #: the Sun's elevation below which it is night (deg; ControllerConfig.night_sun_max_deg)
    night_sun_max_deg: float = NIGHT_SUN_MAX_DEG
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
        return bool(self.sun_el_deg(t_s)[0] < self.night_sun_max_deg)


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

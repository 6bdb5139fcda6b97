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

__all__ = ["Observer", "Target", "never_rises", "never_visible", "why_unschedulable"]


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


#: times checked together by :func:`why_unschedulable` (two hours at its 300-s step)
CHECK_BLOCK = 24


def why_unschedulable(observer: Observer, targets: Sequence[Target], config: SchedulerConfig,
                      duration_s: float, step_s: float = 300.0) -> tuple[str, str]:
    """Why the scheduler's constraints (window, elevations, hour angle, declination) let no
    target be observed at any time of the campaign, checked every ``step_s``: (the
    :class:`SchedulerConfig` field to blame, the reason), or ("", "") when some target may
    be observed at some time."""
    times = np.arange(0.0, duration_s + step_s, step_s)
    times = times[times <= duration_s]
    sun = observer.sun_el_deg(times)
    if config.window == "day":
        window = sun > DAY_SUN_MIN_DEG
        if not window.any():
            return "window", (f"the Sun is never above {DAY_SUN_MIN_DEG:g} deg during the "
                              f"campaign (highest {sun.max():.1f} deg)")
    elif config.window == "night":
        window = sun < observer.night_sun_max_deg
        if not window.any():
            return "window", (f"the Sun is never below night_sun_max_deg = "
                              f"{observer.night_sun_max_deg:g} deg during the campaign (lowest "
                              f"{sun.min():.1f} deg)")
    else:
        window = np.ones(times.size, dtype=bool)
    index = np.array([tg.index for tg in targets])[:, None]
    lowest_dec = math.inf
    # (target, time) at once, two hours at a time: most campaigns can observe in the first
    for start in range(0, times.size, CHECK_BLOCK):
        grid, open_ = times[None, start:start + CHECK_BLOCK], window[start:start + CHECK_BLOCK]
        _, el = observer.ephemeris.altaz_rad(index, grid)
        el_deg = np.degrees(el)
        ok = open_ & (el_deg >= config.elevation_min_deg) & (el_deg <= config.elevation_max_deg)
        if config.hour_angle_limit_deg is not None or config.declination_max_deg is not None:
            ha, dec = observer.ephemeris.hadec_rad(index, grid)
            dec_deg = np.degrees(dec)
            lowest_dec = min(lowest_dec, float(dec_deg.min()))
            if config.hour_angle_limit_deg is not None:
                ok &= np.abs(np.degrees(ha)) <= config.hour_angle_limit_deg
            if config.declination_max_deg is not None:
                ok &= dec_deg <= config.declination_max_deg
        if ok.any():
            return "", ""
    if config.declination_max_deg is not None and lowest_dec > config.declination_max_deg:
        return "declination_max_deg", (f"no source lies at or below it (the southernmost at "
                                       f"{lowest_dec:+.1f} deg)")
    limits = [f"between {config.elevation_min_deg:g} and {config.elevation_max_deg:g} deg "
              "elevation"]
    if config.hour_angle_limit_deg is not None:
        limits.append(f"within +-{config.hour_angle_limit_deg:g} deg of hour angle")
    if config.declination_max_deg is not None:
        limits.append(f"at or below {config.declination_max_deg:g} deg of declination")
    when = "" if config.window == "all" else f" by {config.window}"
    return ("window" if config.window != "all" else "elevation_min_deg",
            f"no source is {' and '.join(limits)}{when} at any time of the campaign")


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

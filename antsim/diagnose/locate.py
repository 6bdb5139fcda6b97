"""Locate the mismatch: per axis, how far the residuals exceed the predicted noise, and where.

The residuals of the baseline fit are divided by the noise the baseline predicts (whitened),
so that each is N(0, 1) when the baseline explains the data. Per axis the rms of these
whitened residuals is the ratio to the expected noise. The scans are then grouped by azimuth
sector and elevation band (on an equatorial mount: hour angle and declination), local time
of day, time since sunset, air temperature, source, direction of the last slew; in each
group the chi^2 of the whitened residuals, against the rest of the scans (an F test: is the
excess concentrated there?) and against the prediction, and the group's mean residual (is
it offset there?), give a p-value corrected for the number of groups looked at.
Polarization is located by the XR - XL test of the squint candidate. Everything is also
reported in words.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from astropy.time import Time

from . import pvalues
from .candidates.base import sun_el_grid_deg, time_grid
from .data import Observations
from .problem import Problem

__all__ = ["Group", "Location", "groupings", "locate", "where_signal"]

AXIS_WORDS = {"xel": "cross-elevation", "el": "elevation"}
#: an equatorial mount's axes (its offsets are cross-declination and declination)
EQUATORIAL_AXIS_WORDS = {"xel": "cross-declination", "el": "declination"}
SECTORS = ("north", "north-east", "east", "south-east", "south", "south-west", "west",
           "north-west")


def axis_words(obs: Observations) -> dict[str, str]:
    """The offsets' axes in words for the recordings' mount."""
    return EQUATORIAL_AXIS_WORDS if obs.mount == "equatorial" else AXIS_WORDS


@dataclass
class Group:
    category: str
    label: str  # words, e.g. "in the 4 hours after sunset"
    mask: np.ndarray


@dataclass
class Hotspot:
    axis: str
    group: Group
    n: int
    ratio: float  # rms of whitened residuals in the group
    mean: float  # mean residual (arcsec)
    p: float  # corrected for the number of groups


@dataclass
class Location:
    ratio: dict[str, float]
    p: dict[str, float]
    hotspots: list[Hotspot] = field(default_factory=list)
    words: str = ""


def _hours_since_sunset(obs: Observations) -> np.ndarray | None:
    if not obs.has_time or (obs.sun_el_deg is None and "epoch_utc" not in obs.meta):
        return None
    try:
        t = time_grid(obs)
        sun = sun_el_grid_deg(obs, t)
    except ValueError:
        return None
    sets = t[1:][(sun[:-1] >= 0.0) & (sun[1:] < 0.0)]
    # the last sunset at or before each scan (the grid's sunsets are in time order)
    last = np.searchsorted(sets, obs.t_s, side="right") - 1
    out = np.full(obs.n, np.nan)
    after = last >= 0
    out[after] = (obs.t_s[after] - sets[last[after]]) / 3600.0
    if obs.sun_el_deg is not None:
        out[obs.sun_el_deg >= 0.0] = np.nan  # by day: not "after sunset"
    return out


def groupings(obs: Observations) -> list[Group]:
    """All the groups scans are examined in (each a mask over the observations)."""
    groups = _direction_groups(obs)
    if obs.has_time:
        lon = float(obs.meta.get("longitude_deg", float("nan")))
        epoch = obs.meta.get("epoch_utc")
        if np.isfinite(lon) and epoch:
            hour0 = (Time(str(epoch), scale="utc").mjd % 1.0) * 24.0
            local = (hour0 + lon / 15.0 + obs.t_s / 3600.0) % 24.0
            for lo in range(0, 24, 4):
                groups.append(Group("time of day", f"between {lo:02d}:00 and {lo + 4:02d}:00 "
                                                   "local time",
                                    (local >= lo) & (local < lo + 4)))
        since = _hours_since_sunset(obs)
        if since is not None:
            for lo, hi, words in ((0, 2, "in the 2 hours after sunset"),
                                  (0, 4, "in the 4 hours after sunset"),
                                  (4, 8, "4 to 8 hours after sunset"),
                                  (8, 24, "more than 8 hours after sunset")):
                with np.errstate(invalid="ignore"):
                    groups.append(Group("time since sunset", words,
                                        (since >= lo) & (since < hi)))
            groups.append(Group("time since sunset", "by day", ~np.isfinite(since)))
    if obs.air_temp_c is not None and np.isfinite(obs.air_temp_c).sum() > 10:
        q = np.nanpercentile(obs.air_temp_c, [33.3, 66.7])
        temp = obs.air_temp_c
        groups += [Group("air temperature", f"when the air is coldest (below {q[0]:.1f} C)",
                         temp < q[0]),
                   Group("air temperature", f"at middling air temperatures ({q[0]:.1f} to "
                                            f"{q[1]:.1f} C)", (temp >= q[0]) & (temp < q[1])),
                   Group("air temperature", f"when the air is warmest (above {q[1]:.1f} C)",
                         temp >= q[1])]
    if obs.source is not None:
        for src in np.unique(obs.source):
            groups.append(Group("source", f"on {src}", obs.source == src))
    for col, axis in zip(("slew_az", "slew_el"), obs.axis_names, strict=True):
        v = getattr(obs, col)
        if v is not None and np.unique(v[np.isfinite(v)]).size > 1:
            word_pos = "clockwise" if axis == "azimuth" else "upwards"
            word_neg = "anticlockwise" if axis == "azimuth" else "downwards"
            groups.append(Group("last slew", f"after slewing {word_pos} in {axis}", v > 0))
            groups.append(Group("last slew", f"after slewing {word_neg} in {axis}", v < 0))
    return [g for g in groups if g.mask.any()]


def _direction_groups(obs: Observations) -> list[Group]:
    """Where on the sky: azimuth sectors and elevation bands, or on an equatorial mount
    hour-angle ranges and declination bands."""
    groups: list[Group] = []
    if obs.mount == "equatorial":
        ha = np.degrees(obs.az_rad) / 15.0
        for lo, hi in ((-12, -4), (-4, -2), (-2, 0), (0, 2), (2, 4), (4, 12)):
            side = "East" if hi <= 0 else "West"
            groups.append(Group("hour angle", f"at hour angles {lo:+d} to {hi:+d} h ({side})",
                                (ha >= lo) & (ha < hi)))
        dec = np.degrees(obs.el_rad)
        for lo, hi in ((-90, -20), (-20, 0), (0, 20), (20, 40), (40, 60), (60, 90)):
            groups.append(Group("declination", f"at declinations {lo:+d} to {hi:+d} deg",
                                (dec >= lo) & (dec < hi)))
        return groups
    az = np.degrees(obs.az_rad) % 360.0
    sector = ((az + 22.5) // 45.0).astype(int) % 8
    for k, name in enumerate(SECTORS):
        groups.append(Group("azimuth", f"towards the {name} (azimuth {45 * k - 22.5:.0f} to "
                                       f"{45 * k + 22.5:.0f} deg)", sector == k))
    el = np.degrees(obs.el_rad)
    for lo, hi in ((0, 20), (20, 35), (35, 50), (50, 65), (65, 90)):
        groups.append(Group("elevation", f"at elevations {lo} to {hi} deg",
                            (el >= lo) & (el < hi)))
    return groups


def locate(problem: Problem, min_scans: int = 5) -> Location:
    """Per-axis ratio to the predicted noise and the groups where the excess lives."""
    f = problem.fit_current()
    n = problem.n
    used = problem.used
    gof = problem.gof()
    ratio = {a: float(v["ratio"]) for a, v in gof.items()}
    pvals = {a: float(v["p"]) for a, v in gof.items()}
    groups = groupings(problem.obs)
    raw = (problem.y - problem.current_columns() @ problem.fit(problem.current_columns()).coef)
    hot: list[Hotspot] = []
    n_tests = max(2 * len(groups), 1)
    n_used = int(used.sum())
    for axis, name in ((0, "xel"), (1, "el")):
        z = f.resid[axis * n:(axis + 1) * n]
        r = raw[axis * n:(axis + 1) * n]
        total = float(z[used] @ z[used])
        for g in groups:
            m = g.mask & used
            k = int(m.sum())
            if k < min_scans or n_used - k < min_scans:
                continue
            chi2 = float(z[m] @ z[m])
            # concentrated: larger here than elsewhere (an F test of the two mean squares);
            # with the noise known, also larger than predicted here
            f_ratio = (chi2 / k) / max((total - chi2) / (n_used - k), 1e-12)
            p = float(pvalues.f_sf(f_ratio, k, n_used - k))
            if problem.pred.known_noise:
                p = max(p, float(pvalues.chi2_sf(chi2, k)))
            # or offset: the group's mean residual differs from zero (the model's zero
            # points fit the whole), normal approximation
            zbar = float(np.mean(z[m]))
            p_mean = float(pvalues.chi2_sf(k * zbar * zbar * (1.0 - k / n_used) ** -1, 1))
            p = 2.0 * min(p, p_mean)
            hot.append(Hotspot(name, g, k, math.sqrt(chi2 / k), float(np.mean(r[m])),
                               min(1.0, p * n_tests)))
    hot = [h for h in hot if h.p < 0.01 and h.ratio > 1.0]
    hot.sort(key=lambda h: (h.p, -h.ratio))
    loc = Location(ratio, pvals, hot)
    loc.words = location_words(problem, loc)
    return loc


def location_words(problem: Problem, loc: Location) -> str:
    known = problem.pred.known_noise
    parts = []
    words = axis_words(problem.obs)
    for axis in ("el", "xel"):
        r = loc.ratio[axis]
        head = words[axis]
        spots = [h for h in loc.hotspots if h.axis == axis]
        if known:
            if loc.p[axis] > 0.05 and not spots:
                parts.append(f"{head} residuals match the expected noise "
                             f"({r:.2f} times it)")
                continue
            text = f"{head} residuals are {r:.2f} times the expected noise"
        else:
            if not spots:
                parts.append(f"{head} residuals show no concentration (noise estimated from "
                             "the data)")
                continue
            text = f"{head} residuals (noise estimated from the data)"
        if spots:
            # the most concentrated groups, one per category
            seen = set()
            said = []
            for h in spots:
                if h.group.category in seen:
                    continue
                seen.add(h.group.category)
                said.append(f"{h.group.label} ({h.ratio:.1f} times there, mean "
                            f"{h.mean:+.1f}\")")
                if len(said) == 2:
                    break
            text += ", concentrated " + " and ".join(said)
        parts.append(text)
    return "; ".join(parts)


def where_signal(obs: Observations, signal: np.ndarray, used: np.ndarray) -> str:
    """Words for where a fitted signature (2n, arcsec) lives: its axis, and the grouping
    (azimuth sector, elevation band, time, source, ...) that explains most of its variance,
    with the group where it is largest."""
    n = obs.n
    sx, se = signal[:n], signal[n:]
    cross, along = axis_words(obs)["xel"], axis_words(obs)["el"]
    axis_rms = {cross: float(np.sqrt(np.mean(sx[used] ** 2))),
                along: float(np.sqrt(np.mean(se[used] ** 2)))}
    axis = max(axis_rms, key=axis_rms.get)
    s = sx if axis == cross else se
    total = float(np.mean(s[used] ** 2))
    if total == 0:
        return "nowhere"
    other = cross if axis == along else along
    both = axis_rms[other] > 0.3 * axis_rms[axis]
    head = f"{axis}{' and ' + other if both else ''} ({axis_rms[axis]:.1f}\" rms"
    head += f", {axis_rms[other]:.1f}\" in {other})" if both else ")"
    by_cat: dict[str, list[Group]] = {}
    for g in groupings(obs):
        by_cat.setdefault(g.category, []).append(g)
    best = None
    for cat, groups in by_cat.items():
        if cat == "time since sunset":
            groups = [g for g in groups if g.label != "in the 4 hours after sunset"]
        between = 0.0
        count = 0
        extreme = None
        for g in groups:
            m = g.mask & used
            k = int(m.sum())
            if k < 3:
                continue
            mean = float(np.mean(s[m]))
            between += k * mean * mean
            count += k
            if extreme is None or abs(mean) > abs(extreme[1]):
                extreme = (g, mean, k)
        if count < 0.8 * used.sum() or extreme is None:
            continue
        r2 = between / (count * total)
        if best is None or r2 > best[0]:
            best = (r2, cat, extreme)
    if best is None or best[0] < 0.3:
        return f"{head}, spread over the sky"
    r2, cat, (g, mean, _k) = best
    return (f"{head}, varying most with {cat} ({100 * r2:.0f}% of it), largest {g.label} "
            f"(mean {mean:+.1f}\")")

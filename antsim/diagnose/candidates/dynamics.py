"""Candidates of the drive and the clock: a clock error, servo lag, backlash.
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from antsim.world.effects.dynamics import Backlash, ClockError, ServoLag

from .base import (
    Candidate,
    source_rates_arcsec_s,
    stacked,
)

__all__ = ['BacklashCandidate', 'ClockCandidate', 'ServoLagCandidate']


class ClockCandidate(Candidate):
    name = "clock_error"
    effect = "clock_error"
    title = "clock (timing) error"
    signature = ("an offset along each source's apparent motion, proportional to its rate "
                 "(sidereal-rate regressor); a drifting clock makes it grow in time")
    params_doc: ClassVar[dict[str, str]] = {"offset_s": "clock reading minus true time (s)",
                  "drift_s_per_day": "clock rate error (s per day)"}
    amplitude_param = "drift_s_per_day"
    needs = ("time", "latitude")

    mounts = ("altaz", "equatorial")

    def __init__(self):
        self.explanation = ClockError.explanation

    def columns(self, obs, theta=None):
        # the antenna points where the source is at its clock's time t + dt, so the measured
        # correction (source minus beam) is -dt times the source's apparent motion
        rx, re_ = source_rates_arcsec_s(obs)
        day = obs.t_s / 86400.0
        cols = -np.column_stack([stacked(rx, re_, obs.n), stacked(rx * day, re_ * day, obs.n)])
        return cols, ("offset_s", "drift_s_per_day")

    def params_from(self, obs, theta, coef, cov, names):
        values = dict(zip(names, map(float, coef), strict=True))
        i = names.index("drift_s_per_day") if "drift_s_per_day" in names else None
        amp = values.get("drift_s_per_day", float("nan"))
        sig = math.sqrt(max(cov[i, i], 0.0)) if i is not None else float("nan")
        values.setdefault("offset_s", 0.0)
        return values, amp, sig

    def draw_shape(self, rng, obs):
        return {"sign": float(rng.choice([-1.0, 1.0])),
                "offset_s": float(rng.uniform(-2.0, 2.0))}

    def unit_signal(self, obs, shape):
        return shape["sign"] * self.columns(obs)[0][:, 1]

    def effect_params(self, shape, amplitude):
        return {"offset_s": shape["offset_s"],
                "drift_s_per_day": float(shape["sign"] * amplitude)}

    def effect_from_params(self, params):
        return {"offset_s": params.get("offset_s", 0.0),
                "drift_s_per_day": params.get("drift_s_per_day", 0.0)}


class ServoLagCandidate(Candidate):
    name = "servo_lag"
    effect = "servo_lag"
    title = "servo lag"
    signature = "an error along each axis proportional to that axis' speed (rate regressor)"
    params_doc: ClassVar[dict[str, str]] = {"lag_s": "servo following lag (s)"}
    amplitude_param = "lag_s"
    needs = ("latitude",)
    blind_exclusion = ("while tracking, the axis rates are the source's apparent motion: the "
                       "lag is a rotation about the polar axis that IA and the azimuth-axis "
                       "tilt terms absorb exactly, and it shares its regressor with a clock "
                       "offset")

    def __init__(self):
        self.explanation = ServoLag.explanation

    def columns(self, obs, theta=None):
        # the axes trail their command: the beam lags the source by lag x rate
        rx, re_ = source_rates_arcsec_s(obs)
        return -stacked(rx, re_, obs.n)[:, None], ("lag_s",)

    def params_from(self, obs, theta, coef, cov, names):
        return {"lag_s": float(coef[0])}, float(coef[0]), math.sqrt(max(cov[0, 0], 0.0))

    def effect_from_params(self, params):
        return {"lag_s": params["lag_s"]}


class BacklashCandidate(Candidate):
    name = "backlash"
    effect = "backlash"
    title = "gear backlash"
    signature = "an offset whose sign follows the direction of the last slew on each axis"
    params_doc: ClassVar[dict[str, str]] = {
        "az_arcsec": "azimuth dead band, full width (arcsec of azimuth)",
        "el_arcsec": "elevation dead band, full width (arcsec)"}
    amplitude_param = "el_arcsec"
    needs = ("slew_az", "slew_el")
    blind_exclusion = ("the five-point pattern reaches every on-source point from the same "
                       "side (the offsets step upwards), so backlash is a constant offset "
                       "that IA and IE absorb; the slew direction does not reach the offsets")

    def __init__(self):
        self.explanation = Backlash.explanation

    def applicable(self, obs, known_noise):
        if not super().applicable(obs, known_noise):
            return False
        return bool(np.unique(obs.slew_az[np.isfinite(obs.slew_az)]).size > 1
                    or np.unique(obs.slew_el[np.isfinite(obs.slew_el)]).size > 1)

    def columns(self, obs, theta=None):
        sa = np.nan_to_num(obs.slew_az)
        se = np.nan_to_num(obs.slew_el)
        cols = np.column_stack([stacked(0.5 * sa * np.cos(obs.el_rad), None, obs.n),
                                stacked(None, 0.5 * se, obs.n)])
        return cols, ("az_arcsec", "el_arcsec")

    def effect_from_params(self, params):
        return {"az_arcsec": abs(params.get("az_arcsec", 0.0)),
                "el_arcsec": abs(params.get("el_arcsec", 0.0))}

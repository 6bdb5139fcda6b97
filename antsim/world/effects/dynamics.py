"""Effects of the drive and the clock: timing error, servo lag, backlash."""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from controller.units import RAD_PER_ARCSEC

from .base import Effect, Key, PointingState

__all__ = ["Backlash", "ClockError", "ServoLag"]


class ClockError(Effect):
    """The antenna's clock is off by ``offset_s`` (+ ``drift_s_per_day`` per day).

    The control program computes where the source is for the time its clock shows, so the
    antenna points where the source will be (or was): an error along the source's apparent
    motion, proportional to its rate (sidereal-rate regressor).
    """

    name: ClassVar[str] = "clock_error"
    explanation: ClassVar[str] = (
        "the control computer's clock is wrong, so sources are tracked where they were (or "
        "will be) a few seconds away: the error follows each source's apparent motion"
    )
    PARAMS: ClassVar[dict[str, Key]] = {
        "offset_s": Key(0.0, "clock reading minus true time (s)"),
        "drift_s_per_day": Key(0.0, "clock rate error (s per day)"),
    }

    def start(self, world, rng: np.random.Generator) -> None:
        offset, drift = self.p["offset_s"], self.p["drift_s_per_day"] / 86400.0
        world.set_clock_error(lambda t: offset + drift * t)


class ServoLag(Effect):
    """The axes lag their command by ``lag_s`` while moving: error = lag x axis rate."""

    name: ClassVar[str] = "servo_lag"
    explanation: ClassVar[str] = (
        "the servo loop follows a moving command with a lag, so the pointing trails by an "
        "amount proportional to the axis speed"
    )
    PARAMS: ClassVar[dict[str, Key]] = {
        "lag_s": Key(0.0, "servo following lag (s)"),
    }

    def pointing_error(self, state: PointingState) -> tuple[float, float]:
        lag = self.p["lag_s"]
        # the axis is behind its command, so the encoder command leads the true position
        return lag * state.az_rate_rad_s, lag * state.el_rate_rad_s

    block_error = pointing_error


class Backlash(Effect):
    """Gear backlash: half the dead band, with the sign of the last approach direction."""

    name: ClassVar[str] = "backlash"
    explanation: ClassVar[str] = (
        "play in the gears: the axis settles on one side or the other of the dead band "
        "depending on the direction it last moved"
    )
    PARAMS: ClassVar[dict[str, Key]] = {
        "az_arcsec": Key(0.0, "azimuth dead band, full width (arcsec of azimuth)", min=0.0),
        "el_arcsec": Key(0.0, "elevation dead band, full width (arcsec)", min=0.0),
    }

    def pointing_error(self, state: PointingState) -> tuple[float, float]:
        return (0.5 * self.p["az_arcsec"] * RAD_PER_ARCSEC * state.approach_az,
                0.5 * self.p["el_arcsec"] * RAD_PER_ARCSEC * state.approach_el)

    block_error = pointing_error

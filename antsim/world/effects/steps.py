"""A step: the pointing changes at one instant and stays changed.

An encoder that slips (its zero point jumps), a subreflector or feed that is moved, a
mount that is re-levelled: the error is one offset before and another after (DESIGN
section 5's signature table, "step change at an unknown time"; Crane 1981's 4990 MHz run of
the 140-ft is a real case, where a subreflector offset moved C1 and C6). Here the azimuth
and elevation zero points change by ``az_arcsec`` and ``el_arcsec`` (indicated minus true,
arcsec of azimuth and of elevation) at ``t_s`` seconds after the campaign's start; the
cross-elevation error of an azimuth step is ``az_arcsec cos E``.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from controller.units import RAD_PER_ARCSEC

from .base import REQUIRED, Effect, Key, PointingState

__all__ = ["Step"]


class Step(Effect):
    """Azimuth and elevation zero points that change at ``t_s`` and stay changed."""

    name: ClassVar[str] = "step"
    explanation: ClassVar[str] = (
        "the pointing changed at one instant and stayed changed: an encoder slipped, the "
        "subreflector or the feed was moved, or the mount was re-levelled"
    )
    PARAMS: ClassVar[dict[str, Key]] = {
        "t_s": Key(REQUIRED, "time of the change, seconds after the campaign's start", min=0.0),
        "az_arcsec": Key(0.0, "change of the azimuth zero point (arcsec of azimuth)"),
        "el_arcsec": Key(0.0, "change of the elevation zero point (arcsec)"),
    }

    def pointing_error(self, state: PointingState) -> tuple[float, float]:
        after = float(state.t_s) >= self.p["t_s"]
        return (self.p["az_arcsec"] * RAD_PER_ARCSEC * after,
                self.p["el_arcsec"] * RAD_PER_ARCSEC * after)

    def block_error(self, state: PointingState) -> tuple[np.ndarray, np.ndarray]:
        after = np.asarray(state.t_s, dtype=float) >= self.p["t_s"]
        return (np.where(after, self.p["az_arcsec"] * RAD_PER_ARCSEC, 0.0),
                np.where(after, self.p["el_arcsec"] * RAD_PER_ARCSEC, 0.0))

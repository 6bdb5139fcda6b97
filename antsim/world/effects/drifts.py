"""A temperature-driven elevation drift: the structure follows the air with a lag.

The bulk temperature of the structure relaxes towards the air temperature with time constant
``tau_s`` (first-order lag on the one-minute grid of :mod:`antsim.world.effects.thermal`, spun up a
day before the campaign); the elevation error is ``arcsec_per_k * (T_structure -
reference_c)``: a uniformly warming structure lengthens the feed legs and the dish's focal
length changes, tipping the beam by an amount proportional to the temperature (the JCMT
corrects 6.5" per kelvin of structure temperature difference, DESIGN section 5).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from controller.units import RAD_PER_ARCSEC

from .base import Effect, Key, PointingState
from .thermal import campaign_grid_s, relax

__all__ = ["TemperatureDrift", "structure_temperature_c"]


def structure_temperature_c(t_grid_s: np.ndarray, air_c: np.ndarray, tau_s: float) -> np.ndarray:
    """Structure temperature (C) on an even grid: the air temperature lagged by ``tau_s``
    (no lag when ``tau_s`` is 0), starting in equilibrium with the first air value."""
    if tau_s <= 0.0:
        return np.asarray(air_c, dtype=float).copy()
    step = float(t_grid_s[1] - t_grid_s[0])
    return relax(np.asarray(air_c, dtype=float), step, tau_s, float(air_c[0]))


class TemperatureDrift(Effect):
    """Elevation error proportional to the (lagged) structure temperature."""

    name: ClassVar[str] = "temperature_drift"
    explanation: ClassVar[str] = (
        "the structure expands and contracts with its temperature, which follows the air "
        "temperature with a lag; the beam tips in elevation in proportion"
    )
    PARAMS: ClassVar[dict[str, Key]] = {
        "arcsec_per_k": Key(0.0, "elevation error per kelvin of structure temperature"),
        "tau_s": Key(3600.0, "time constant of the structure temperature (s; 0: none)",
                     min=0.0),
        "reference_c": Key(0.0, "structure temperature of zero error (C)"),
    }

    def start(self, world, rng: np.random.Generator) -> None:
        t = campaign_grid_s(world.duration_s)
        self.t_grid = t
        self.structure_c = structure_temperature_c(t, world.air_temperature_c(t),
                                                   float(self.p["tau_s"]))

    def error_arcsec(self, t_s) -> np.ndarray:
        """Elevation error (arcsec, indicated - true) at time(s) ``t_s``."""
        temp = np.interp(t_s, self.t_grid, self.structure_c)
        return self.p["arcsec_per_k"] * (temp - self.p["reference_c"])

    def pointing_error(self, state: PointingState) -> tuple[float, float]:
        return 0.0, float(self.error_arcsec(state.t_s)) * RAD_PER_ARCSEC

    def block_error(self, state: PointingState) -> tuple[float, np.ndarray]:
        return 0.0, self.error_arcsec(state.t_s) * RAD_PER_ARCSEC

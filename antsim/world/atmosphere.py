"""The atmosphere at X-band: attenuation and emission rising with airmass.

A plane-parallel atmosphere of zenith opacity ``tau0`` and mean radiating temperature
``T_atm``: transmission ``exp(-tau0 A)`` and sky brightness ``T_atm (1 - exp(-tau0 A))``,
with airmass ``A = 1 / sin E`` (adequate above 5 deg). The elevation dependence gives the
elevation scans' baselines a slope.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Atmosphere", "AtmosphereConfig"]


@dataclass(frozen=True)
class AtmosphereConfig:
    zenith_opacity: float = 0.012
    temperature_k: float = 270.0


class Atmosphere:
    def __init__(self, config: AtmosphereConfig):
        self.tau0 = config.zenith_opacity
        self.t_atm = config.temperature_k

    def airmass(self, el_rad) -> np.ndarray:
        return 1.0 / np.sin(np.maximum(el_rad, np.radians(1.0)))

    def transmission(self, el_rad) -> np.ndarray:
        return np.exp(-self.tau0 * self.airmass(el_rad))

    def emission_k(self, el_rad) -> np.ndarray:
        """Sky brightness temperature added to the system temperature (K)."""
        return self.t_atm * (1.0 - self.transmission(el_rad))

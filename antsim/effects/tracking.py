"""Random tracking error: wind buffeting and servo noise, an Ornstein-Uhlenbeck process."""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from controller.units import RAD_PER_ARCSEC

from .base import Effect, Param
from .thermal import OUProcess

__all__ = ["TrackingJitter"]


class TrackingJitter(Effect):
    """Random pointing wander per axis, correlated over ``timescale_s``.

    An exact-discretisation Ornstein-Uhlenbeck process per axis, continuous across
    integrations. Its rms grows with wind as ``1 + (wind / wind_ref)^2`` (wind pressure goes as
    the square of speed); with the 1990 weather (wind below 10 mph) the factor is near 1.
    """

    name: ClassVar[str] = "tracking_jitter"
    per_sample: ClassVar[bool] = True
    explanation: ClassVar[str] = (
        "wind buffeting and servo noise move the beam randomly on time scales of seconds "
        "to minutes"
    )
    PARAMS: ClassVar[dict[str, Param]] = {
        "xel_rms_arcsec": Param(5.0, "rms of the cross-elevation wander (arcsec)", min=0.0),
        "el_rms_arcsec": Param(5.0, "rms of the elevation wander (arcsec)", min=0.0),
        "timescale_s": Param(60.0, "correlation time of the wander (s)", min=1e-3),
        "wind_ref_m_s": Param(10.0, "wind speed that doubles the rms (m/s)", min=0.1),
    }

    def start(self, world, rng: np.random.Generator) -> None:
        wind = world.weather.wind_speed_m_s
        scale = 1.0 + (wind / self.p["wind_ref_m_s"]) ** 2
        rms = np.array([self.p["xel_rms_arcsec"], self.p["el_rms_arcsec"]]) * RAD_PER_ARCSEC
        self.process = OUProcess(rng, rms * scale, self.p["timescale_s"])

    def sample_error(self, t_s: np.ndarray, el_rad: float) -> tuple[np.ndarray, np.ndarray]:
        out = self.process.sample(t_s)
        return out[:, 0] / math.cos(el_rad), out[:, 1]

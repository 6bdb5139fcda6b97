"""Dual-polarization total-power receiver with radiometer noise and gain fluctuations.

Each channel (XR, XL: right and left circular) has its own system temperature (XL about
15% above XR, Ghigo 1990, section IV). Samples every ``sample_interval_s``:

    P = G(t) * T_in + n,     n ~ N(0, T_in / sqrt(B * dt))        (radiometer equation)

with ``G(t) = 1 + g(t)`` and ``g`` an Ornstein-Uhlenbeck process of rms ``gain_fluctuation``
(dG/G, 1e-4..1e-3) and correlation time ``gain_timescale_s``, continuous across
integrations. Gain fluctuations dominate: radiometer noise on a 15 s mean is ~1 mK, gain
fluctuations give 5-50 mK, which is what makes the S/N >= 4 cut of the reduction fire.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .effects.thermal import OUProcess

__all__ = ["ChannelConfig", "Receiver", "ReceiverConfig"]


@dataclass(frozen=True)
class ChannelConfig:
    """One polarization channel; ``gain_fluctuation`` (dG/G) overrides the receiver's and
    ``gain_k_per_jy`` the beam's peak gain (a feed of its own, e.g. the 140-ft's two linear
    feeds at 3245 MHz, Crane 1981 Table 5)."""

    name: str
    tsys_k: float
    gain_fluctuation: float | None = None
    gain_k_per_jy: float | None = None


@dataclass(frozen=True)
class ReceiverConfig:
    channels: tuple[ChannelConfig, ...] = (ChannelConfig("XR", 45.0), ChannelConfig("XL", 51.75))
    frequency_ghz: float = 8.4
    bandwidth_mhz: float = 135.0
    sample_interval_s: float = 1.0
    gain_fluctuation: float = 3e-4
    gain_timescale_s: float = 60.0


class Receiver:
    """Turns input temperatures into sampled total powers with noise (kelvin)."""

    def __init__(self, config: ReceiverConfig, rng: np.random.Generator):
        self.config = config
        self.rng = rng
        self.names = tuple(c.name for c in config.channels)
        self.tsys_k = np.array([c.tsys_k for c in config.channels])
        rms = [config.gain_fluctuation if c.gain_fluctuation is None else c.gain_fluctuation
               for c in config.channels]
        self._gain = OUProcess(rng, np.array(rms), config.gain_timescale_s)

    def sample_times(self, t_start_s: float, seconds: float) -> np.ndarray:
        """Mid-times of the samples of an integration starting at ``t_start_s``."""
        dt = self.config.sample_interval_s
        n = max(1, round(seconds / dt))
        return t_start_s + (np.arange(n) + 0.5) * (seconds / n)

    def sample(self, t_s: np.ndarray, t_in_k: np.ndarray) -> np.ndarray:
        """Total-power samples (K), shape (n, channels), for input temperatures
        ``t_in_k`` of shape (n, channels) excluding the receiver's own Tsys. With ``t_s``
        of shape (K, n) (K integrations, see :class:`~antsim.world.effects.thermal.OUProcess`)
        and ``t_in_k`` (K, n, channels): samples (K, n, channels), the same values as K
        calls."""
        cfg = self.config
        total = self.tsys_k + t_in_k
        if t_s.ndim == 2:  # per integration its gain draws, then its radiometer draws
            normals = self.rng.standard_normal((t_s.shape[0], 2, *total.shape[1:]))
            gains = self._gain.sample(t_s, normals[:, 0])
            noise = normals[:, 1]
        else:
            gains = self._gain.sample(t_s)
            noise = self.rng.standard_normal(total.shape)
        radiometer = total / math.sqrt(cfg.bandwidth_mhz * 1e6 * cfg.sample_interval_s)
        return total * (1.0 + gains) + radiometer * noise

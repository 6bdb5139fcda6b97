"""Random tracking error: wind buffeting and servo noise, an Ornstein-Uhlenbeck process."""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from controller.units import RAD_PER_ARCSEC

from .base import Effect, Key
from .thermal import OUProcess

__all__ = ["TrackingJitter"]


class TrackingJitter(Effect):
    """Random pointing wander per axis, correlated over ``timescale_s``.

    An exact-discretisation Ornstein-Uhlenbeck process per axis, continuous across
    integrations. Its rms grows with the wind at the time as ``1 + (wind / wind_ref)^2``
    (wind pressure goes as the square of speed), so a breezy afternoon shakes the beam more
    than a calm night.

    By day (the Sun above the horizon) each axis' rms is multiplied by ``day_xel_factor`` and
    ``day_el_factor`` (default 1): the structure heated by the Sun scatters more than at night,
    as the 140-ft's nights were quieter (Crane 1981, Table 4: Dec 9.3" at night against 11.9"
    in all) and the 45-ft's (Ghigo 1990, fit E).

    Gusts (off by default): Poisson events at ``gust_rate_per_h``, each displacing the beam by
    a random amount (rms ``gust_arcsec`` per axis) along a raised-cosine profile lasting
    ``gust_duration_s``. A gust inside a scan distorts its five points: the reduction flags it
    or it becomes an outlier for the fitter to reject, as in the 1990 report's filtering.
    """

    name: ClassVar[str] = "tracking_jitter"
    per_sample: ClassVar[bool] = True
    explanation: ClassVar[str] = (
        "wind buffeting and servo noise move the beam randomly on time scales of seconds "
        "to minutes"
    )
    PARAMS: ClassVar[dict[str, Key]] = {
        "xel_rms_arcsec": Key(5.0, "rms of the cross-elevation wander (arcsec)", min=0.0),
        "el_rms_arcsec": Key(5.0, "rms of the elevation wander (arcsec)", min=0.0),
        "timescale_s": Key(60.0, "correlation time of the wander (s)", min=1e-3),
        "wind_ref_m_s": Key(10.0, "wind speed that doubles the rms (m/s)", min=0.1),
        "gust_rate_per_h": Key(0.0, "mean number of gusts per hour", min=0.0, max=3600.0),
        "gust_arcsec": Key(60.0, "rms beam displacement of a gust per axis (arcsec)",
                           min=0.0),
        "gust_duration_s": Key(30.0, "duration of a gust (s)", min=1.0),
        "day_xel_factor": Key(1.0, "cross-elevation rms by day (Sun above the horizon) over "
                              "xel_rms_arcsec", min=0.0, max=100.0, unit="1"),
        "day_el_factor": Key(1.0, "elevation rms by day (Sun above the horizon) over "
                             "el_rms_arcsec", min=0.0, max=100.0, unit="1"),
    }
    #: step of the table of day (Sun up) and night over the campaign (s)
    DAY_TABLE_STEP_S: ClassVar[float] = 60.0

    def start(self, world, rng: np.random.Generator) -> None:
        self.weather = world.weather
        self.rms_rad = np.array([self.p["xel_rms_arcsec"], self.p["el_rms_arcsec"]]) \
            * RAD_PER_ARCSEC
        self.process = OUProcess(rng, np.ones(2), self.p["timescale_s"])
        span_h = (world.duration_s + 3600.0) / 3600.0
        n_gusts = rng.poisson(self.p["gust_rate_per_h"] * span_h)
        self.gust_start_s = np.sort(rng.uniform(0.0, span_h * 3600.0, n_gusts))
        self.gust_rad = rng.standard_normal((n_gusts, 2)) * self.p["gust_arcsec"] \
            * RAD_PER_ARCSEC
        self.day_factor = np.array([self.p["day_xel_factor"], self.p["day_el_factor"]])
        self.sun_up: tuple[np.ndarray, np.ndarray] | None = None
        if np.any(self.day_factor != 1.0):  # (times, Sun up) on a grid over the campaign
            grid = np.arange(0.0, span_h * 3600.0 + self.DAY_TABLE_STEP_S, self.DAY_TABLE_STEP_S)
            self.sun_up = (grid, (world.sun_el_rad(grid) > 0.0).astype(float))

    def axis_factor(self, t_s) -> np.ndarray:
        """The rms factor of each axis at time(s) ``t_s``: (*shape, 2), 1 at night."""
        t = np.asarray(t_s, dtype=float)
        if self.sun_up is None:
            return np.ones((*t.shape, 2))
        up = np.interp(t, *self.sun_up) >= 0.5  # the nearest grid time's day or night
        return 1.0 + up[..., None] * (self.day_factor - 1.0)

    def gusts_rad(self, t_s: np.ndarray) -> np.ndarray:
        """Displacement by gusts at times ``t_s``, shape (n, 2) (xel, el), radians."""
        out = np.zeros((t_s.size, 2))
        duration = self.p["gust_duration_s"]
        first = np.searchsorted(self.gust_start_s, t_s[0] - duration)
        last = np.searchsorted(self.gust_start_s, t_s[-1], side="right")
        for g in range(first, last):
            phase = (t_s - self.gust_start_s[g]) / duration
            inside = (phase >= 0.0) & (phase <= 1.0)
            out[inside] += np.sin(np.pi * phase[inside])[:, None] ** 2 * self.gust_rad[g]
        return out

    def sample_error(self, t_s: np.ndarray, el_rad: float) -> tuple[np.ndarray, np.ndarray]:
        """Per-sample error (rad) at times ``t_s`` (n,), or (K, n) for K integrations
        (``el_rad`` then (K, 1), or (K, 1, members)); ``el_rad`` is the elevation at each
        integration's middle."""
        mid = t_s[..., t_s.shape[-1] // 2]
        wind = self.weather.wind_m_s(mid)
        scale = 1.0 + (wind / self.p["wind_ref_m_s"]) ** 2
        rms = self.rms_rad * self.axis_factor(mid)  # (2,), or (K, 2) per integration
        if t_s.ndim == 2:  # scale per integration against (K, n, [members,] 2)
            out = self.process.sample(t_s)
            lead = (-1, *[1] * (out.ndim - 2))
            out = out * (rms * scale[:, None]).reshape(*lead, 2)
            if self.gust_start_s.size:
                out = out + self.gusts_rad(t_s.ravel()).reshape(out.shape)
        else:
            out = self.process.sample(t_s) * (rms * float(scale))
            if self.gust_start_s.size:
                out = out + self.gusts_rad(t_s)
        # out is (n, 2), or (n, members, 2) in antsim.plan's ensembles (el_rad then (members,))
        return out[..., 0] / (np.cos(el_rad) if np.ndim(el_rad) else math.cos(el_rad)), out[..., 1]

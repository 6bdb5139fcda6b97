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
    integrations. Two laws for the wind:

    * with ``wind_arcsec_per_m2s2`` (the structure's and drives' compliance: pointing per
      unit of the wind's dynamic pressure, as arcsec per (m/s)^2; the pointing errors wind
      causes grow as the square of its speed, Gawronski, Bienkiewicz and Hill 1992) the
      rms per axis is the servo's (``xel_rms_arcsec``, ``el_rms_arcsec``: encoder steps and
      servo noise, no wind) and the turbulent wind's in quadrature, ``2 I c v^2`` with ``I``
      the ``turbulence_intensity`` (the fluctuating pressure of a wind ``v (1 + I x)``);
    * without it (the older scenarios), the rms grows with the wind as
      ``1 + (wind / wind_ref)^2``.

    By day (the Sun above the horizon) each axis' rms is multiplied by ``day_xel_factor`` and
    ``day_el_factor`` (default 1): the structure heated by the Sun scatters more than at night,
    as the 140-ft's nights were quieter (Crane 1981, Table 4: Dec 9.3" at night against 11.9"
    in all) and the 45-ft's (Ghigo 1990, fit E).

    Gusts (off by default): Poisson events at ``gust_rate_per_h``, each displacing the beam by
    a random amount along a raised-cosine profile lasting ``gust_duration_s``: rms
    ``gust_arcsec`` per axis, or, with the compliance law, the wind's own: a gust
    ``gust_factor`` times the wind of its time adds ``c v^2 (G^2 - 1)`` of pressure
    (``G`` the gust factor), the rms per axis of its displacement. A gust inside a scan
    distorts its five points: the reduction flags it or it becomes an outlier for the
    fitter to reject, as in the 1990 report's filtering.
    """

    name: ClassVar[str] = "tracking_jitter"
    per_sample: ClassVar[bool] = True
    explanation: ClassVar[str] = (
        "wind buffeting and servo noise move the beam randomly on time scales of seconds "
        "to minutes"
    )
    PARAMS: ClassVar[dict[str, Key]] = {
        "xel_rms_arcsec": Key(5.0, "rms of the cross-elevation wander (arcsec): servo noise "
                              "and encoder steps, with the compliance law", min=0.0),
        "el_rms_arcsec": Key(5.0, "rms of the elevation wander (arcsec)", min=0.0),
        "timescale_s": Key(60.0, "correlation time of the wander (s)", min=1e-3),
        "wind_ref_m_s": Key(10.0, "wind speed that doubles the rms (m/s), without the "
                            "compliance law", min=0.1),
        "wind_arcsec_per_m2s2": Key(0.0, "pointing per (m/s)^2 of wind: the structure's and "
                                    "drives' compliance (0: the wind_ref law); 0.03-0.04 for "
                                    "precision 10-12 m antennas", min=0.0, max=100.0,
                                    unit="arcsec/(m/s)^2",
                                    source="ASTE 10 m (2.4\" in 9.3 m/s); MMA memo 159"),
        "turbulence_intensity": Key(0.2, "rms of the wind's fluctuations over its mean "
                                    "(0.1-0.3 near the ground)", min=0.0, max=2.0, unit="1"),
        "gust_factor": Key(1.7, "a gust's peak wind over the mean, with the compliance law "
                           "(1.4-2.0)", min=1.0, max=5.0, unit="1"),
        "gust_rate_per_h": Key(0.0, "mean number of gusts per hour", min=0.0, max=3600.0),
        "gust_arcsec": Key(60.0, "rms beam displacement of a gust per axis (arcsec), "
                           "without the compliance law", min=0.0),
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
        self.gust_rad = rng.standard_normal((n_gusts, 2)) \
            * self.gust_rms_arcsec(self.gust_start_s)[:, None] * RAD_PER_ARCSEC
        self.day_factor = np.array([self.p["day_xel_factor"], self.p["day_el_factor"]])
        self.sun_up: tuple[np.ndarray, np.ndarray] | None = None
        if np.any(self.day_factor != 1.0):  # (times, Sun up) on a grid over the campaign
            grid = np.arange(0.0, span_h * 3600.0 + self.DAY_TABLE_STEP_S, self.DAY_TABLE_STEP_S)
            self.sun_up = (grid, (world.sun_el_rad(grid) > 0.0).astype(float))

    @property
    def compliance(self) -> float:
        """The wind's pointing per (m/s)^2 (arcsec), 0 for the older law."""
        return float(self.p["wind_arcsec_per_m2s2"])

    def wind_rms_arcsec(self, wind_m_s) -> np.ndarray:
        """The turbulent wind's rms per axis (arcsec) at mean wind ``wind_m_s``: 2 I c v^2."""
        v = np.asarray(wind_m_s, dtype=float)
        return 2.0 * self.p["turbulence_intensity"] * self.compliance * v * v

    def gust_rms_arcsec(self, t_s) -> np.ndarray:
        """The rms per axis (arcsec) of a gust's displacement at time(s) ``t_s``."""
        t = np.asarray(t_s, dtype=float)
        if self.compliance == 0.0:
            return np.full(t.shape, float(self.p["gust_arcsec"]))
        v = np.asarray(self.weather.wind_m_s(t), dtype=float)
        return self.compliance * v * v * (self.p["gust_factor"] ** 2 - 1.0)

    def gust_energy_arcsec2_per_s(self, t_s) -> float:
        """Gusts' expected rate times their displacement's mean square per axis over the
        times ``t_s`` (arcsec^2 per second): the second moment a plan's noise model uses."""
        rms = self.gust_rms_arcsec(t_s)
        return float(self.p["gust_rate_per_h"]) / 3600.0 * float(np.mean(rms ** 2))

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
        rms = self.rms_rad * self.axis_factor(mid)  # (2,), or (K, 2) per integration
        if self.compliance > 0.0:  # servo and turbulent wind in quadrature
            gusty = self.wind_rms_arcsec(wind)[..., None] * RAD_PER_ARCSEC
            rms = np.sqrt(rms * rms + gusty * gusty)
            scale = np.ones_like(wind)
        else:
            scale = 1.0 + (wind / self.p["wind_ref_m_s"]) ** 2
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

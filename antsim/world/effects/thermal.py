"""Thermal pointing errors: solar heating, lagging structure temperatures, sunset drift.

Physics (DESIGN section 5): differential heating of the structure by the Sun dominates the
elevation errors by day (Ghigo 1990: day el rms 40", night 26"); the structure's
temperatures follow their drivers with time constants of an hour or more, so the error
persists and relaxes after sunset (Fomalont 1973: elevation changed systematically by 1.0'
for 4 hours after sunset); the JCMT corrects 6.5" per kelvin of front-to-back difference.

Model, on a one-minute grid over the campaign plus a day of spin-up:

* insolation ``I(t) = max(0, sin h_sun)`` times a cloud factor, an Ornstein-Uhlenbeck
  modulation drawn per run (clear sky on 8 Feb 1990: small modulation);
* front-to-back gradient ``dT_fb`` relaxes towards ``solar_gradient_k * I`` with time
  constant ``gradient_tau_s``; left-right gradient ``dT_lr`` towards a random, sun-driven
  forcing (which side the Sun heats changes as the antenna moves);
* bulk structure temperature ``T_s`` relaxes towards the air temperature with
  ``bulk_tau_s``;
* error (indicated - true): ``el = el_arcsec_per_k * dT_fb + bulk_arcsec_per_k *
  (T_s - reference_c)``, ``xel = xel_arcsec_per_k * dT_lr``.

Two parts depend on where the antenna points, so they change from scan to scan by day (off
by default; the 1990 scenario uses them):

* the dish: sunlight on its front or back face, or on one side, sets front-back and
  left-right gradients that relax towards ``dish_gradient_k * I * (s . b)`` and
  ``dish_gradient_k * I * (s . x)`` (s: unit vector to the Sun, b: boresight, x: the
  direction of increasing azimuth) with the thin members' ``dish_tau_s`` (feed-support legs
  respond in minutes); they add ``dish_arcsec_per_k`` per kelvin in elevation and
  ``dish_xel_factor`` times that in cross-elevation;
* the pedestal: the Sun heats the side of the azimuth bearing's support that faces it; the
  gradient relaxes with ``pedestal_tau_s`` towards ``pedestal_gradient_k * I`` along the
  Sun's azimuth and tilts the azimuth axis away from the Sun by ``tilt_arcsec_per_k`` per
  kelvin: an AN/AW tilt whose direction follows the Sun through the day.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Sequence
from functools import lru_cache
from typing import ClassVar

import numpy as np

from controller.units import RAD_PER_ARCSEC

from .base import Effect, Key, PointingState

__all__ = ["SUNSET_SHAPES", "OUProcess", "SunsetDrift", "ThermalEffect", "interp_rows",
           "ou_series", "relax", "since_sunset", "sunset_level", "transient_level"]

GRID_STEP_S = 60.0
SPINUP_S = 86400.0


def relax(forcing: np.ndarray, step_s: float, tau_s: float, initial: float) -> np.ndarray:
    """First-order lag of ``forcing`` sampled every ``step_s`` (exact for piecewise-linear
    forcing is not needed here: exponential smoothing with the exact decay per step)."""
    alpha = math.exp(-step_s / tau_s)
    return first_order_filter(np.asarray(forcing, dtype=float), 1.0 - alpha, alpha,
                              alpha * initial)


#: a series at least this long is filtered by scipy.signal.lfilter itself: the loop costs
#: 0.12 us a sample (12 ms here, 0.12 s for the minute grid of a 694-day campaign, which
#: diagnose filters some 70 times), scipy.signal's import 0.5 s once
LFILTER_SAMPLES = 100_000


def first_order_filter(x: np.ndarray, gain: float, rho: float, state=0.0) -> np.ndarray:
    """``y[n] = gain x[n] + rho y[n-1]`` along axis 0, with ``rho y[-1] = state``: the
    arithmetic of ``scipy.signal.lfilter([gain], [1, -rho], x, zi=[state])``, bit for bit;
    a shorter series than :data:`LFILTER_SAMPLES` without importing scipy.signal (0.6 s of
    start-up for one recursion)."""
    if x.ndim == 1 and x.size >= LFILTER_SAMPLES:
        from scipy.signal import lfilter

        return lfilter([gain], [1.0, -rho], x, zi=[float(state)])[0]
    out = np.empty_like(x)
    if x.ndim == 1:
        z = float(state)
        values = x.tolist()
        for i, v in enumerate(values):
            values[i] = z = gain * v + z
            z = rho * z
        out[:] = values
        return out
    z = np.asarray(state, dtype=float) * np.ones(x.shape[1:])
    for i in range(x.shape[0]):
        out[i] = gain * x[i] + z
        z = rho * out[i]
    return out


def _elementwise(math_func, numpy_func):
    """``math_func`` on a scalar (the World's per-integration path, bit for bit as before),
    ``numpy_func`` on an array (a member axis)."""
    return lambda x: math_func(x) if np.ndim(x) == 0 else numpy_func(x)


_sin = _elementwise(math.sin, np.sin)
_cos = _elementwise(math.cos, np.cos)
_tan = _elementwise(math.tan, np.tan)


def interp_rows(t_s, t_grid: np.ndarray, values: np.ndarray):
    """``np.interp(t_s, t_grid, values)``; ``values`` may carry leading axes (one row per
    ensemble member of :mod:`antsim.plan`), all interpolated at the same time(s)."""
    if np.ndim(values) == 1:
        return np.interp(t_s, t_grid, values)
    if np.ndim(t_s) == 0:  # the common case, one time: plain floats are faster
        t = float(t_s)
        i = min(max(int(np.searchsorted(t_grid, t, side="right")) - 1, 0), t_grid.size - 2)
        w = min(max((t - t_grid[i]) / (t_grid[i + 1] - t_grid[i]), 0.0), 1.0)
        return values[..., i] * (1.0 - w) + values[..., i + 1] * w
    t = np.asarray(t_s, dtype=float)
    i = np.clip(np.searchsorted(t_grid, t, side="right") - 1, 0, t_grid.size - 2)
    w = np.clip((t - t_grid[i]) / (t_grid[i + 1] - t_grid[i]), 0.0, 1.0)
    return values[..., i] * (1.0 - w) + values[..., i + 1] * w


class ScalarInterpolator:
    """``np.interp(t, t_grid, row)`` of several rows at one time ``t`` (s), with plain
    floats: np.interp's own arithmetic (bit for bit), one search for all rows, and none of
    numpy's per-call overhead (the World asks once per integration)."""

    def __init__(self, t_grid: np.ndarray, rows: Sequence[np.ndarray]):
        self.grid = np.asarray(t_grid, dtype=float).tolist()
        self.rows = [np.asarray(r, dtype=float).tolist() for r in rows]

    def __call__(self, t: float) -> list[float]:
        grid = self.grid
        if t < grid[0]:
            return [r[0] for r in self.rows]
        if t >= grid[-1]:
            return [r[-1] for r in self.rows]
        j = bisect.bisect_right(grid, t) - 1
        x0 = grid[j]
        if x0 == t:
            return [r[j] for r in self.rows]
        dx, u = grid[j + 1] - x0, t - x0
        return [(r[j + 1] - r[j]) / dx * u + r[j] for r in self.rows]


def campaign_grid_s(duration_s: float) -> np.ndarray:
    """Times (s) every ``GRID_STEP_S`` from a day of spin-up before the campaign to a little
    after its end: the grid the structure-temperature models are computed on."""
    return np.arange(-SPINUP_S, duration_s + 2 * GRID_STEP_S, GRID_STEP_S)


def ou_series(rng: np.random.Generator, n: int, step_s: float, tau_s: float,
              rms: float) -> np.ndarray:
    """Stationary Ornstein-Uhlenbeck series of ``n`` points (exact discretisation)."""
    if rms == 0.0 or n == 0:
        return np.zeros(n)
    rho = math.exp(-step_s / tau_s)
    draws = rng.standard_normal(n)
    draws[0] /= math.sqrt(1.0 - rho * rho)  # stationary start
    return first_order_filter(draws, math.sqrt(1.0 - rho * rho) * rms, rho)


class OUProcess:
    """Ornstein-Uhlenbeck process(es) sampled at increasing times, continuous across calls.

    ``rms`` may be an array of any shape (one independent process per element; samples then
    have shape (n, *rms.shape), e.g. (n, members, channels) for :mod:`antsim.plan`). Within a
    call the samples must be evenly spaced (an integration's samples are); the step from the
    previous call's last sample may be anything (exact discretisation, stationary start).
    Times of shape (K, n) are K such integrations at once, in time order and equally long
    (the antenna's deferred integrations): the same values as K calls, one block each.
    """

    def __init__(self, rng: np.random.Generator, rms, timescale_s: float):
        self.rng = rng
        self.rms = np.atleast_1d(np.asarray(rms, dtype=float))
        self.tau = float(timescale_s)
        self.state = np.zeros_like(self.rms)
        self.t_last: float | None = None

    def sample(self, t_s: np.ndarray, normals: np.ndarray | None = None) -> np.ndarray:
        """Values at times ``t_s`` (evenly spaced), shape (n, *rms.shape); for ``t_s`` of
        shape (K, n), (K, n, *rms.shape). ``normals``: the standard normals of that shape
        to use instead of drawing them from the generator."""
        if t_s.ndim == 2:
            return self._sample_blocks(t_s, normals)
        n = t_s.size
        if normals is None:
            normals = self.rng.standard_normal((n, *self.rms.shape))
        draws = normals * self.rms
        first = self._first(float(t_s[0]), draws[0])
        if n == 1:
            out = first[None, ...]
        elif n > 64:  # long integrations: a recursive filter, not an n x n kernel
            rho = math.exp(-float(t_s[1] - t_s[0]) / self.tau)
            rest = first_order_filter(draws[1:], math.sqrt(1.0 - rho * rho), rho,
                                      rho * first)
            out = np.concatenate([first[None, ...], rest])
        else:
            rho = math.exp(-float(t_s[1] - t_s[0]) / self.tau)
            powers, kernel = _ar1_kernel(n, rho)
            draws[0] = 0.0
            out = ((kernel @ draws.reshape(n, -1)).reshape(draws.shape)
                   + powers.reshape(n, *[1] * first.ndim) * first[None, ...])
        self.state = out[-1].copy()
        self.t_last = float(t_s[-1])
        return out

    def _first(self, t0_s: float, draw: np.ndarray) -> np.ndarray:
        """The value at ``t0_s`` from the last one (or a stationary start), given the
        scaled draw for it (copied: the caller reuses the draw's slot)."""
        if self.t_last is None:
            return draw.copy()
        rho0 = math.exp(-max(t0_s - self.t_last, 0.0) / self.tau)
        return rho0 * self.state + math.sqrt(1.0 - rho0 * rho0) * draw

    def _sample_blocks(self, t_s: np.ndarray, normals: np.ndarray | None) -> np.ndarray:
        blocks, n = t_s.shape
        if normals is None:  # numpy's normal stream does not depend on how it is cut
            normals = self.rng.standard_normal((blocks, n, *self.rms.shape))
        if n == 1 or n > 64:
            return np.stack([self.sample(t_s[k], normals[k]) for k in range(blocks)])
        draws = normals * self.rms
        heads = draws[:, 0].copy()
        draws[:, 0] = 0.0
        rho = math.exp(-float(t_s[0, 1] - t_s[0, 0]) / self.tau)
        powers, kernel = _ar1_kernel(n, rho)
        within = np.matmul(kernel, draws.reshape(blocks, n, -1)).reshape(draws.shape)
        firsts = np.empty_like(heads)
        for k in range(blocks):  # each block starts from the previous one's last value
            firsts[k] = first = self._first(float(t_s[k, 0]), heads[k])
            self.state = within[k, -1] + powers[-1] * first
            self.t_last = float(t_s[k, -1])
        return within + powers.reshape(1, n, *[1] * (heads.ndim - 1)) * firsts[:, None]


@lru_cache(maxsize=64)
def _ar1_kernel(n: int, rho: float) -> tuple[np.ndarray, np.ndarray]:
    """``rho**k`` and the lower-triangular AR(1) kernel ``sqrt(1-rho^2) rho**(k-j)``, j>=1:
    x_k = rho^k x_0 + sum_{j=1..k} sqrt(1-rho^2) rho^(k-j) e_j, as one small matrix product."""
    k = np.arange(n)
    lag = k[:, None] - k[None, :]
    kernel = np.where(lag >= 0, rho ** np.clip(lag, 0, None), 0.0) * math.sqrt(1.0 - rho * rho)
    kernel[:, 0] = 0.0
    return rho ** k, kernel


def _dish_forcing(flux, sun_n, sun_e, sun_u, az_rad, el_rad, maths) -> tuple:
    """Front-back and left-right dish gradients (K) the Sun (unit vector north, east, up)
    drives with ``flux`` (K) on a dish pointing at (az, el) (rad): ``maths`` is ``math``
    for plain floats, ``np`` for arrays."""
    cos_e, sin_e = maths.cos(el_rad), maths.sin(el_rad)
    cos_a, sin_a = maths.cos(az_rad), maths.sin(az_rad)
    return (flux * (sun_n * cos_e * cos_a + sun_e * cos_e * sin_a + sun_u * sin_e),
            flux * (sun_e * cos_a - sun_n * sin_a))


class ThermalEffect(Effect):
    """Solar heating and structure-temperature lag (see module docstring)."""

    name: ClassVar[str] = "thermal"
    explanation: ClassVar[str] = (
        "the Sun heats one side of the structure more than the other; the temperature "
        "differences bend the dish and its support, lag the Sun by an hour or more, and "
        "relax after sunset"
    )
    PARAMS: ClassVar[dict[str, Key]] = {
        "el_arcsec_per_k": Key(6.5, "elevation error per kelvin of front-back gradient"),
        "xel_arcsec_per_k": Key(3.0, "cross-elevation error per kelvin of left-right gradient"),
        "solar_gradient_k": Key(6.0, "front-back gradient under full overhead Sun (K)",
                                min=0.0),
        "lateral_gradient_k": Key(3.0, "rms left-right gradient under full Sun (K)", min=0.0),
        "gradient_tau_s": Key(5400.0, "time constant of the gradients (s)", min=60.0),
        "cloud_modulation": Key(0.3, "rms relative modulation of the insolation (clouds)",
                                min=0.0, max=1.0, unit="1"),
        "cloud_timescale_s": Key(1800.0, "correlation time of the modulation (s)", min=60.0),
        "lateral_timescale_s": Key(3600.0, "correlation time of the lateral forcing (s)",
                                   min=60.0),
        "bulk_arcsec_per_k": Key(0.0, "elevation error per kelvin of bulk temperature"),
        "bulk_tau_s": Key(7200.0, "time constant of the bulk structure temperature (s)",
                          min=60.0),
        "reference_c": Key(0.0, "bulk temperature of zero bulk error (C)"),
        "dish_gradient_k": Key(0.0, "dish gradient with the Sun face-on, full sun (K)",
                               min=0.0),
        "dish_tau_s": Key(600.0, "time constant of the dish gradients (s)", min=1.0),
        "dish_arcsec_per_k": Key(6.5, "pointing error per kelvin of dish gradient"),
        "dish_xel_factor": Key(1.0, "cross-elevation error per kelvin of the dish's "
                               "left-right gradient over dish_arcsec_per_k", min=0.0,
                               max=10.0, unit="1"),
        "pedestal_gradient_k": Key(0.0, "pedestal gradient under full sun (K)", min=0.0),
        "pedestal_tau_s": Key(5400.0, "time constant of the pedestal gradient (s)",
                              min=60.0),
        "tilt_arcsec_per_k": Key(3.0, "azimuth-axis tilt per kelvin of pedestal gradient"),
    }

    def start(self, world, rng: np.random.Generator) -> None:
        step = GRID_STEP_S
        t = campaign_grid_s(world.duration_s)
        sun_el = world.sun_el_rad_periodic(t)
        insolation = np.clip(np.sin(sun_el), 0.0, None)
        n = t.size
        p = self.p
        modulation = 1.0 + ou_series(rng, n, step, p["cloud_timescale_s"], p["cloud_modulation"])
        insolation_eff = insolation * np.clip(modulation, 0.0, None)
        lateral = ou_series(rng, n, step, p["lateral_timescale_s"], 1.0)
        dt_fb = relax(p["solar_gradient_k"] * insolation_eff, step, p["gradient_tau_s"], 0.0)
        dt_lr = relax(p["lateral_gradient_k"] * insolation_eff * lateral, step,
                      p["gradient_tau_s"], 0.0)
        air = world.air_temperature_c(t)
        t_struct = relax(air, step, p["bulk_tau_s"], float(air[0]))
        self.t_grid = t
        self.el_arcsec = p["el_arcsec_per_k"] * dt_fb \
            + p["bulk_arcsec_per_k"] * (t_struct - p["reference_c"])
        self.xel_arcsec = p["xel_arcsec_per_k"] * dt_lr
        self.gradient_fb_k = dt_fb
        self.structure_c = t_struct
        # pointing-dependent parts
        sun_az = world.sun_az_rad(t)
        cos_h = np.cos(sun_el)
        self._sun_vec = np.stack([cos_h * np.cos(sun_az), cos_h * np.sin(sun_az),
                                  np.sin(sun_el)])  # north, east, up
        self._insolation = insolation_eff
        forcing = p["pedestal_gradient_k"] * insolation_eff
        # the pedestal's north-minus-south and east-minus-west differences (K): the side
        # facing the Sun is the warmer
        self.pedestal_n_k = relax(forcing * np.cos(sun_az), step, p["pedestal_tau_s"], 0.0)
        self.pedestal_e_k = relax(forcing * np.sin(sun_az), step, p["pedestal_tau_s"], 0.0)
        self.gradient_lr_k = dt_lr
        # the heated side expands: the axis tilts away from the Sun
        self._tilt_n_arcsec = -p["tilt_arcsec_per_k"] * self.pedestal_n_k
        self._tilt_e_arcsec = -p["tilt_arcsec_per_k"] * self.pedestal_e_k
        #: (time -> forcing and gradients of the dish, K) of every instant the dish state
        #: advanced to, kept only when structure sensors read it (antsim.world.sensors)
        self.dish_log: dict[float, tuple[float, float, float, float]] | None = None
        self._dish_k = None
        self._dish_t = None
        self._now = None
        self._now_cache = None
        self._block = None

    def errors_arcsec(self, t_s) -> tuple[np.ndarray, np.ndarray]:
        """(xel, el) thermal error in arcsec at time(s) ``t_s`` (for tests and reports)."""
        return (interp_rows(t_s, self.t_grid, self.xel_arcsec),
                interp_rows(t_s, self.t_grid, self.el_arcsec))

    def dish_gradients_k(self, state: PointingState, now=None) -> tuple[float, float]:
        """Front-back and left-right dish gradients (K) now, advancing their state from
        the previous call as if the antenna had pointed here since then (the evaluations
        come every integration; slews between them are short). ``now``: this time's
        values of the series (see :meth:`pointing_error`) when the caller has them."""
        p = self.p
        if p["dish_gradient_k"] == 0.0:
            return 0.0, 0.0
        t = state.t_s
        if now is not None and np.ndim(state.az_rad) == 0 and np.ndim(state.el_rad) == 0:
            # one time and one direction (a World): plain floats
            sun_n, sun_e, sun_u, insolation = now[2:6]
            flux = p["dish_gradient_k"] * insolation
            forcing = _dish_forcing(flux, sun_n, sun_e, sun_u, state.az_rad, state.el_rad,
                                    math)
        else:
            if now is None:
                sun = np.array([np.interp(t, self.t_grid, row) for row in self._sun_vec])
                insolation = interp_rows(t, self.t_grid, self._insolation)
            else:
                sun, insolation = np.array(now[2:5]), now[5]
            flux = p["dish_gradient_k"] * insolation
            cos_e, sin_e = _cos(state.el_rad), _sin(state.el_rad)
            cos_a, sin_a = _cos(state.az_rad), _sin(state.az_rad)
            boresight = np.array((cos_e * cos_a, cos_e * sin_a, sin_e))
            side = np.array((-sin_a, cos_a, np.zeros_like(sin_a)))
            forcing = (flux * np.dot(sun, boresight), flux * np.dot(sun, side))
        if self._dish_k is None:
            self._dish_k = forcing
        elif t > self._dish_t:
            decay = math.exp(-(t - self._dish_t) / p["dish_tau_s"])
            self._dish_k = tuple(f + (k - f) * decay
                                 for f, k in zip(forcing, self._dish_k, strict=True))
        self._dish_t = t
        if self.dish_log is not None and np.ndim(t) == 0:
            self.dish_log[float(t)] = (*(float(f) for f in forcing),
                                       *(float(k) for k in self._dish_k))
        return self._dish_k

    def _series_at(self, t: float) -> list:
        """Every series at time ``t`` (s), looked up once per integration (the fixed point
        asks twice): xel, el (arcsec), the Sun (3), insolation, tilts (arcsec). Plain floats
        when no series has a member axis (np.interp's arithmetic), else interp_rows."""
        if self._now_cache is None or self._now_cache[0] != t:
            series = (self.xel_arcsec, self.el_arcsec, *self._sun_vec, self._insolation,
                      self._tilt_n_arcsec, self._tilt_e_arcsec)
            if all(np.ndim(v) == 1 for v in series):
                if self._now is None:
                    self._now = ScalarInterpolator(self.t_grid, series)
                values = self._now(t)
            else:
                values = [interp_rows(t, self.t_grid, v) for v in series]
            self._now_cache = (t, values)
        return self._now_cache[1]

    def pointing_error(self, state: PointingState) -> tuple[float, float]:
        p = self.p
        # the pedestal's tilt, indicated - true: TPOINT's AN = -tilt_n, AW = -tilt_e (AN > 0
        # the pole north of the zenith, AW > 0 west of it)
        if np.ndim(state.t_s) == 0:  # one time (a World, or antsim.plan's shared schedule)
            now = self._series_at(float(state.t_s))
            xel, el, tilt_n, tilt_e = now[0], now[1], now[6], now[7]
            fb, lr = self.dish_gradients_k(state, now)
        else:  # times with a member axis
            xel, el = self.errors_arcsec(state.t_s)
            fb, lr = self.dish_gradients_k(state)
            tilt_n = interp_rows(state.t_s, self.t_grid, self._tilt_n_arcsec)
            tilt_e = interp_rows(state.t_s, self.t_grid, self._tilt_e_arcsec)
        el = el + p["dish_arcsec_per_k"] * fb
        xel = xel + p["dish_arcsec_per_k"] * p["dish_xel_factor"] * lr
        sin_a, cos_a = _sin(state.az_rad), _cos(state.az_rad)
        tan_e = _tan(state.el_rad)
        d_az = -(tilt_n * sin_a + tilt_e * cos_a) * tan_e
        el = el + (-tilt_n * cos_a + tilt_e * sin_a)
        return ((xel / _cos(state.el_rad) + d_az) * RAD_PER_ARCSEC,
                el * RAD_PER_ARCSEC)

    def block_error(self, state: PointingState) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`pointing_error` at K instants (arrays (K,)), see
        :meth:`Effect.block_error`. The dish gradients advance over the K times from where
        they stood before them, forced from the directions of the latest call, so the fixed
        point converges to gradients forced from where the beam truly pointed."""
        p = self.p
        t = state.t_s  # (K,), or (K, 1) with a member axis
        key = (t.size, float(t.flat[0]), float(t.flat[-1]))
        if self._block is None or self._block[0] != key:
            series = [np.interp(t, self.t_grid, v) if np.ndim(v) == 1
                      else interp_rows(t.ravel(), self.t_grid, v).T  # (K, members)
                      for v in (self.xel_arcsec, self.el_arcsec, *self._sun_vec,
                                self._insolation, self._tilt_n_arcsec, self._tilt_e_arcsec)]
            self._block = (key, series, (self._dish_k, self._dish_t))
        _, (xel, el, sun_n, sun_e, sun_u, insolation, tilt_n, tilt_e), start = self._block
        self._dish_k, self._dish_t = start
        fb, lr = self._dish_block(t, state.az_rad, state.el_rad, sun_n, sun_e, sun_u,
                                  insolation)
        el = el + p["dish_arcsec_per_k"] * fb
        xel = xel + p["dish_arcsec_per_k"] * p["dish_xel_factor"] * lr
        sin_a, cos_a = np.sin(state.az_rad), np.cos(state.az_rad)
        d_az = -(tilt_n * sin_a + tilt_e * cos_a) * np.tan(state.el_rad)
        el = el + (-tilt_n * cos_a + tilt_e * sin_a)
        return (xel / np.cos(state.el_rad) + d_az) * RAD_PER_ARCSEC, el * RAD_PER_ARCSEC

    def _dish_block(self, t, az_rad, el_rad, sun_n, sun_e, sun_u,
                    insolation) -> tuple[np.ndarray, np.ndarray]:
        """The dish gradients (K) at times ``t`` (K,), pointing at (az, el) (rad) at each:
        :meth:`dish_gradients_k` once per time, its forcing computed for all at once. With
        a member axis: ``t`` (K, 1), directions (K, members), gradients (K, members)."""
        p = self.p
        if p["dish_gradient_k"] == 0.0:
            return np.zeros(t.shape), np.zeros(t.shape)
        forcing_fb, forcing_lr = _dish_forcing(p["dish_gradient_k"] * insolation, sun_n, sun_e,
                                               sun_u, az_rad, el_rad, np)
        # plain floats per instant for a World; rows (members,) with a member axis
        rows_fb, rows_lr = ((f.tolist() if f.ndim == 1 else list(f))
                            for f in np.broadcast_arrays(forcing_fb, forcing_lr))
        times = t.ravel().tolist()
        if self._dish_k is None:  # no past: the first instant starts at its forcing
            self._dish_k, self._dish_t = (rows_fb[0], rows_lr[0]), times[0]
        last_t = self._dish_t
        gaps = np.diff(np.array([last_t, *times]))
        decays = np.where(gaps > 0.0, np.exp(-np.maximum(gaps, 0.0) / p["dish_tau_s"]),
                          1.0).tolist()
        now_fb, now_lr = self._dish_k
        fb, lr = [], []
        for f_fb, f_lr, decay in zip(rows_fb, rows_lr, decays, strict=True):
            if decay != 1.0:  # time went on (as dish_gradients_k: only when it does)
                now_fb = f_fb + (now_fb - f_fb) * decay
                now_lr = f_lr + (now_lr - f_lr) * decay
            fb.append(now_fb)
            lr.append(now_lr)
        if self.dish_log is not None and np.ndim(now_fb) == 0:  # a World, not members
            for t_k, f_fb, f_lr, g_fb, g_lr in zip(times, rows_fb, rows_lr, fb, lr,
                                                   strict=True):
                self.dish_log[float(t_k)] = (float(f_fb), float(f_lr), float(g_fb),
                                             float(g_lr))
        self._dish_k, self._dish_t = (now_fb, now_lr), max(last_t, times[-1])
        return np.array(fb), np.array(lr)


#: the shapes of a drift after sunset (SunsetDrift's ``shape``)
SUNSET_SHAPES = ("relaxation", "transient")


def sunset_level(night: np.ndarray, step_s: float, tau_s: float,
                 shape: str = "relaxation") -> np.ndarray:
    """The unit drift after sunset on an even grid (``night``: 1 where the Sun is below the
    horizon, else 0). ``"relaxation"``: relaxing towards 1 at night and 0 by day, the
    exponential approach after each sunset and the return after each sunrise.
    ``"transient"``: 1 at each sunset, decaying as exp(-(t - t_set) / tau) (a disturbance
    the evening sets off and the structure forgets), 0 before the grid's first sunset."""
    if shape == "relaxation":
        return relax(night, step_s, tau_s, float(night[0]))
    if shape != "transient":
        raise ValueError(f"unknown sunset drift shape {shape!r}; known: {SUNSET_SHAPES}")
    return transient_level(since_sunset(night), step_s, tau_s)


def since_sunset(night: np.ndarray) -> np.ndarray:
    """Grid steps since the last sunset (the last step from 0 to 1 of ``night``), int32;
    -1 before the grid's first sunset: the part of a transient level that is the same for
    every time constant (a caller that tries many keeps it)."""
    idx = np.arange(night.size)
    sets = np.zeros(night.size, dtype=bool)
    sets[1:] = (night[1:] > 0.5) & (night[:-1] < 0.5)
    last = np.maximum.accumulate(np.where(sets, idx, -1))
    return np.where(last >= 0, idx - last, -1).astype(np.int32)


def transient_level(steps: np.ndarray, step_s: float, tau_s: float) -> np.ndarray:
    """:func:`sunset_level`'s ``"transient"`` shape from :func:`since_sunset`'s ``steps``:
    ``np.where(steps >= 0, np.exp(-steps * step_s / tau_s), 0.0)`` in one array (the same
    bits: s (-step) is -(s step) rounded alike; 3 of 5 ms a level of the 694-day minute
    grid, which diagnose makes some 30 times)."""
    level = np.multiply(steps, -step_s)
    np.divide(level, tau_s, out=level)
    np.exp(level, out=level)
    level[steps < 0] = 0.0
    return level


class SunsetDrift(Effect):
    """Elevation drift after sunset: ``a (1 - exp(-(t - t_set) / tau))``, relaxing back
    with the same time constant after sunrise (Fomalont 1973's 1' in 4 hours); or, with
    ``shape = "transient"``, ``a exp(-(t - t_set) / tau)``: a change the evening sets off
    and that dies away (see :func:`sunset_level`). With ``nights`` > 0 only after the first
    ``nights`` sunsets of the campaign (Fomalont saw it "for a period of 4 hours after sunset
    on February 28", the first of his run)."""

    name: ClassVar[str] = "sunset_drift"
    explanation: ClassVar[str] = (
        "after sunset the structure cools and relaxes from its daytime shape with a time "
        "constant of hours, so the elevation error drifts systematically"
    )
    PARAMS: ClassVar[dict[str, Key]] = {
        "amplitude_arcsec": Key(60.0, "total elevation change after sunset (arcsec)"),
        "tau_s": Key(5400.0, "time constant of the drift (s)", min=60.0),
        "nights": Key(0.0, "after the first this many sunsets of the campaign only "
                           "(0: every night)", min=0.0, max=1000.0, unit="1"),
        "shape": Key("relaxation", "relaxation (a lasting change, back after sunrise) or "
                     "transient (a change at sunset that dies away)", kind="string",
                     choices=SUNSET_SHAPES),
    }

    def start(self, world, rng: np.random.Generator) -> None:
        step = GRID_STEP_S
        t = np.arange(-SPINUP_S, world.duration_s + 2 * step, step)
        night = (world.sun_el_rad_periodic(t) < 0.0).astype(float)
        nights = round(self.p["nights"])
        if nights > 0:  # the nights that begin with one of the campaign's first sunsets
            sunset = np.flatnonzero((np.diff(night) > 0) & (t[1:] >= 0.0)) + 1
            keep = np.zeros_like(night)
            for i in sunset[:nights]:
                end = np.flatnonzero(night[i:] == 0.0)
                keep[i:i + (end[0] if end.size else night.size)] = 1.0
            night = keep
        self.t_grid = t
        self.level = sunset_level(night, step, self.p["tau_s"], self.p["shape"])

    def error_arcsec(self, t_s) -> np.ndarray:
        return self.p["amplitude_arcsec"] * np.interp(t_s, self.t_grid, self.level)

    def pointing_error(self, state: PointingState) -> tuple[float, float]:
        return 0.0, float(self.error_arcsec(state.t_s)) * RAD_PER_ARCSEC

    def block_error(self, state: PointingState) -> tuple[float, np.ndarray]:
        return 0.0, self.error_arcsec(state.t_s) * RAD_PER_ARCSEC

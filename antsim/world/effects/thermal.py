"""Thermal helpers and the sunset drift: first-order lags, Ornstein-Uhlenbeck processes.

The Sun's heating of the structure is :mod:`.heating` (a heat balance per member); this
module keeps what it and other parts share: :func:`relax` (a first-order lag on an even
grid), :func:`ou_series` and :class:`OUProcess` (random wander), :func:`interp_rows` and
:class:`ScalarInterpolator` (series with and without a member axis), the campaign's grid,
and :class:`SunsetDrift` (Fomalont 1973: elevation changed systematically by 1.0' for 4
hours after sunset).
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Sequence
from functools import lru_cache
from typing import ClassVar

import numpy as np
from scipy.signal import lfilter

from controller.units import RAD_PER_ARCSEC

from .base import Effect, Key, PointingState

__all__ = ["SUNSET_SHAPES", "OUProcess", "SunsetDrift", "interp_rows", "ou_series", "relax",
           "since_sunset", "sunset_level", "transient_level"]

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

"""The five-point cross scan, as a simpy process driving an antenna through the protocol.

For each axis in turn (azimuth, then elevation) the antenna integrates at offsets ``n * D``
for n = -4, -1, 0, +1, +4, on the sky: azimuth steps are ``n * D / cos E`` of encoder
azimuth, with E the commanded elevation when the step is made. The mount keeps tracking
throughout. Both polarizations are recorded; their average is formed for the ``AVG`` row.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace
from typing import NamedTuple

import numpy as np

from controller.protocol import Antenna, Integration

from .config import ScanConfig
from .reduction import AxisReduction, reduce_clark, reduce_lsq

__all__ = ["AXES", "RawScan", "ReducedScan", "ScanPowers", "channel_average", "cross_scan",
           "reduce_powers", "reduce_scan", "reduce_sources"]


class ScanPowers(NamedTuple):
    """A cross scan's integrations, shape (axes, channels + AVG, positions): powers and
    sample standard deviations (K) and mid-times (s)."""

    power_k: np.ndarray
    std_k: np.ndarray
    t_mid_s: np.ndarray

AXES = ("az", "el")


@dataclass
class RawScan:
    """The integrations of one cross scan, per axis, in the order of ``offsets_n``."""

    label: str
    step_arcmin: float
    offsets_n: tuple[int, ...]
    channels: tuple[str, ...]
    integrations: dict[str, list[Integration]] = field(default_factory=dict)
    cos_el: float = 1.0
    t_track_s: float = 0.0
    #: structure temperatures (C) read after the central integration of each axis, when the
    #: controller reads them: axis -> sensor -> reading
    structure_c: dict[str, dict[str, float]] = field(default_factory=dict)
    #: when they were read (antenna clock, s): axis -> time
    structure_t_s: dict[str, float] = field(default_factory=dict)

    def powers(self) -> ScanPowers:
        """Power, sample std (K) and mid-times (s), shape (axes, channels + AVG, positions).

        The AVG channel is the mean of the channels' powers, its std the rms of theirs
        divided by sqrt(number of channels) (independent receivers)."""
        n_ch = len(self.channels)
        n_pos = len(self.offsets_n)
        power = np.empty((2, n_ch + 1, n_pos))
        std = np.empty((2, n_ch + 1, n_pos))
        times = np.empty((2, n_ch + 1, n_pos))
        for a, axis in enumerate(AXES):
            for k, integ in enumerate(self.integrations[axis]):
                for c, ch in enumerate(self.channels):
                    power[a, c, k] = integ.power_k[ch]
                    std[a, c, k] = integ.std_k[ch]
                times[a, :, k] = integ.t_mid_s
        power[:, n_ch], std[:, n_ch] = channel_average(power[:, :n_ch], std[:, :n_ch], axis=1)
        return ScanPowers(power, std, times)

    @property
    def t_start_s(self) -> float:
        return self.integrations["az"][0].t_start_s

    @property
    def t_end_s(self) -> float:
        return self.integrations["el"][-1].t_end_s

    @property
    def t_mid_s(self) -> float:
        return 0.5 * (self.t_start_s + self.t_end_s)


@dataclass
class ReducedScan:
    """Per axis (``az`` = cross-elevation, ``el``), reductions with leading axis over
    channels + AVG."""

    raw: RawScan
    axes: dict[str, AxisReduction]
    polarizations: tuple[str, ...]


def cross_scan(env, antenna: Antenna, trajectory, scan: ScanConfig, label: str = "",
               step_arcmin: float | None = None, integration_s: float | None = None,
               structure: bool = False):
    """simpy process: track ``trajectory`` and run a five-point cross scan; returns RawScan.
    With ``structure`` the antenna's structure temperatures are read after the central
    (zero-offset) integration of each axis (:class:`~controller.protocol.StructureAntenna`):
    the temperatures of the structure while that axis' offset was measured."""
    step = scan.step_arcmin if step_arcmin is None else step_arcmin
    tau = scan.integration_s if integration_s is None else integration_s
    raw = RawScan(label=label, step_arcmin=step, offsets_n=scan.offsets_n,
                  channels=tuple(antenna.channels))
    raw.t_track_s = yield antenna.track(trajectory, label)
    move_s = 0.0  # the last move's duration: the estimate of the next one's
    for axis in AXES:
        readings = []
        for n in scan.offsets_n:
            if axis == "az":
                # the step holds at the middle of the integration: near the zenith cos E
                # changes by ~3%/min, ~0.7% between the move's start and that middle
                el_deg = trajectory.sky_elevation_deg(antenna.clock_s() + float(move_s)
                                                      + 0.5 * tau)
                cos_el = max(math.cos(math.radians(el_deg)), 1e-3)
                raw.cos_el = cos_el
                move_s = yield antenna.set_offset(n * step / 60.0 / cos_el, 0.0)
            else:
                move_s = yield antenna.set_offset(0.0, n * step / 60.0)
            readings.append((yield antenna.integrate(tau)))
            if structure and n == 0:
                raw.structure_c[axis] = dict(antenna.structure_temperatures())
                raw.structure_t_s[axis] = float(antenna.clock_s())
        raw.integrations[axis] = readings
    yield antenna.set_offset(0.0, 0.0)
    if scan.overhead_s > 0:
        yield antenna.wait(scan.overhead_s)
    return raw


def channel_average(power: np.ndarray, std: np.ndarray,
                    axis: int) -> tuple[np.ndarray, np.ndarray]:
    """The AVG channel of independent receivers along ``axis``: mean power (K) and the rms
    of the channels' std divided by sqrt(number of channels) (K)."""
    n_ch = power.shape[axis]
    return power.mean(axis=axis), np.sqrt((std ** 2).mean(axis=axis) / n_ch)


def reduce_scan(raw: RawScan, scan: ScanConfig, estimator: str | None = None,
                step_arcmin: float | None = None) -> ReducedScan:
    """Reduce both axes of all channels and their average with the chosen estimator."""
    power, std, times = raw.powers()
    step = raw.step_arcmin if step_arcmin is None else step_arcmin
    result = reduce_powers(power, std, times, scan, estimator, step)
    axes = {axis: _take(result, a) for a, axis in enumerate(AXES)}
    return ReducedScan(raw=raw, axes=axes, polarizations=(*raw.channels, "AVG"))


def reduce_powers(power: np.ndarray, std: np.ndarray, times: np.ndarray, scan: ScanConfig,
                  estimator: str | None = None,
                  step_arcmin: float | None = None) -> AxisReduction:
    """The reduction :func:`reduce_scan` makes, on arrays (..., 5) of powers and std (K)
    and mid-times (s) with any leading (batch) axes."""
    est = estimator or scan.estimator
    step = scan.step_arcmin if step_arcmin is None else step_arcmin
    if est == "clark":
        # baseline: the straight line through the two +-4D powers. It removes the sky's
        # emission slope across an elevation scan exactly to first order; a constant
        # baseline (their mean) turns that slope into an elevation offset of ~8" at 20 deg
        # for a 1 K source (docs/assumptions.md)
        result = reduce_clark(power, std, step_arcmin=step, hpbw_arcmin=scan.hpbw_arcmin,
                              snr_min=scan.snr_min, baseline="line")
    elif est == "lsq":
        result = reduce_lsq(power, std, times, step_arcmin=step, hpbw_arcmin=scan.hpbw_arcmin,
                            snr_min=scan.snr_min)
    else:
        raise ValueError(f"unknown estimator {est!r}: use 'clark' or 'lsq'")
    return result


def reduce_sources(power: np.ndarray, std: np.ndarray, times: np.ndarray, scan: ScanConfig,
                   widths_arcmin: np.ndarray, axis: int) -> AxisReduction:
    """:func:`reduce_powers` of a batch whose index along ``axis`` runs over scans reduced
    with the assumed widths ``widths_arcmin`` (FWHM, arcmin, one per scan; see
    :meth:`ScanConfig.width_for`): one reduction per distinct width."""
    widths = np.asarray(widths_arcmin, dtype=float)
    distinct = np.unique(widths)
    if distinct.size == 1:
        return reduce_powers(power, std, times, replace(scan, hpbw_arcmin=float(distinct[0])))
    shape = np.broadcast_shapes(power.shape, std.shape, times.shape)
    power, std, times = (np.broadcast_to(x, shape) for x in (power, std, times))
    out: dict[str, np.ndarray] = {}
    where = [slice(None)] * (len(shape) - 1)
    for width in distinct:
        index = np.flatnonzero(widths == width)
        where[axis] = index
        part = reduce_powers(power[tuple(where)], std[tuple(where)], times[tuple(where)],
                             replace(scan, hpbw_arcmin=float(width)))
        for f in fields(part):
            value = np.asarray(getattr(part, f.name))
            if f.name not in out:
                out[f.name] = np.empty(shape[:-1], dtype=value.dtype)
            out[f.name][tuple(where)] = value
    return AxisReduction(**out)


def _take(result: AxisReduction, index: int) -> AxisReduction:
    """The reduction of one axis (first batch index) as an AxisReduction."""
    return type(result)(**{f.name: np.asarray(getattr(result, f.name))[index]
                           for f in fields(result)})

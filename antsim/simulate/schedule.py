"""The deterministic ("quiet") campaign and the schedule every Monte Carlo member shares.

When the pointing is good the controller's schedule does not depend on the noise (see
:mod:`antsim.simulate.vectorized`). :func:`record_schedule` runs the campaign of
:func:`quiet_scenario` once with the antenna's recorder attached and keeps, per integration,
the sample times, the encoder command per sample, the antenna's state at the middle and the
true paths of the sources near the beam: a :class:`SharedSchedule`. This module needs only
the simulation (no fitting), so a process that only records schedules starts quickly
(:mod:`antsim.simulate.streaming`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from antsim.simulate.runner import RunResult, simulate
from antsim.world.effects import PointingState
from antsim.world.receiver import ChannelConfig
from antsim.world.world import World

from ..scenario import EffectSpec, Scenario

__all__ = ["QUIET_BANDWIDTH_MHZ", "QUIET_PARAMS", "REFERENCE_SEED", "SharedSchedule",
           "quiet_scenario", "record_schedule"]

#: seed of the deterministic runs (their residual randomness, ~1e-9 K, is irrelevant)
REFERENCE_SEED = 0
#: huge receiver bandwidth of the quiet run: radiometer noise ~1e-9 K (must stay > 0)
QUIET_BANDWIDTH_MHZ = 1e15
#: parameters that switch an effect's random part off (its expected value stays)
QUIET_PARAMS: dict[str, dict[str, float]] = {
    "thermal": {"cloud_modulation": 0.0},
    "tracking_jitter": {"xel_rms_arcsec": 0.0, "el_rms_arcsec": 0.0, "gust_rate_per_h": 0.0,
                        "wind_arcsec_per_m2s2": 0.0},
}


def quiet_scenario(scenario: Scenario) -> Scenario:
    """``scenario`` with its noise switched off: no gain fluctuations, negligible radiometer
    noise, no weather wander, no jitter or gusts, thermal forcing at its mean (no clouds,
    no lateral forcing), structure sensors without noise or local wander (their resolution
    and lag stay). Its campaign is the deterministic simulation of the plan."""
    rec = scenario.receiver
    receiver = replace(rec, gain_fluctuation=0.0, bandwidth_mhz=QUIET_BANDWIDTH_MHZ,
                       channels=tuple(ChannelConfig(c.name, c.tsys_k, 0.0)
                                      for c in rec.channels))
    effects = tuple(EffectSpec(e.name, {**e.params, **QUIET_PARAMS.get(e.name, {})})
                    for e in scenario.effects)
    sensors = scenario.structure_sensors
    if sensors is not None:  # the thermometers' noise and their members' wander off too
        sensors = replace(sensors, noise_k=0.0, local_k=0.0)
    return replace(scenario, receiver=receiver, effects=effects,
                   weather=replace(scenario.weather, wander_rms_c=0.0),
                   structure_sensors=sensors)


@dataclass
class SharedSchedule:
    """What every member of a variant shares: the quiet run's integrations and scans.

    Per integration k (lists, one entry per integration in time order): ``t[k]`` sample
    times (s), ``enc_az[k]``/``enc_el[k]`` the encoder command per sample (rad), ``state[k]``
    the antenna's state at the middle, ``paths[k]`` ``(source index, az, el)`` true paths
    (rad). Per recorded scan s: ``scan_int[s, axis, point]`` the integration index of each of
    the ten points and ``scan_times`` their mid-times (s); ``columns`` the recording columns
    fit A uses (the AVG rows), ``quiet_xel``/``quiet_el`` the quiet run's measured offsets
    (arcmin) and ``quiet_good`` its flags.
    """

    t: list[np.ndarray]
    enc_az: list[np.ndarray]
    enc_el: list[np.ndarray]
    state: list[PointingState]
    paths: list[list[tuple[int, np.ndarray, np.ndarray]]]
    scan_int: np.ndarray
    scan_times: np.ndarray
    columns: dict[str, np.ndarray]
    sources: list[str]
    searches: int
    duration_s: float
    scan_spans_s: np.ndarray
    wall_s: float
    channels: tuple[str, ...] = ()
    #: the sky emission the controller subtracted before each scan's reduction (K),
    #: (scans, axes, channels, positions); None when it subtracted none
    scan_sky_k: np.ndarray | None = None
    #: the structure sensors' response time the fits correct for (s; 0: none)
    sensor_lag_s: float = 0.0

    @property
    def n_integrations(self) -> int:
        return len(self.t)

    @property
    def scan_span_s(self) -> float:
        """Time spent in the recorded scans, first integration to last (s)."""
        return float(self.scan_spans_s.sum())

    @property
    def n_scans(self) -> int:
        return int(self.scan_int.shape[0])

    @classmethod
    def arriving(cls, duration_s: float, channels: tuple[str, ...]) -> SharedSchedule:
        """A schedule whose integrations are still to come (:mod:`antsim.simulate.streaming`):
        what the members' effects need to start, nothing recorded yet."""
        return cls(t=[], enc_az=[], enc_el=[], state=[], paths=[],
                   scan_int=np.zeros((0, 2, 5), dtype=np.int64), scan_times=np.zeros((0, 2, 5)),
                   columns={}, sources=[], searches=0, duration_s=duration_s,
                   scan_spans_s=np.zeros(0), wall_s=0.0, channels=channels)


class _Recorder:
    def __init__(self, also: Callable[..., None] | None = None):
        self.items: list[dict] = []
        self.also = also

    def __call__(self, **item: Any) -> None:
        self.items.append(item)
        if self.also is not None:
            self.also(**item)


def record_schedule(quiet: Scenario, seed: int = 0,
                    on_integration: Callable[..., None] | None = None
                    ) -> tuple[SharedSchedule, RunResult]:
    """Run the deterministic simulation of ``quiet`` (see :func:`quiet_scenario`) with the
    antenna's recorder attached; returns the shared schedule and the run. ``on_integration``
    is also called with each integration's recorder keywords as it is recorded (e.g. by
    :mod:`antsim.simulate.streaming`'s quiet-run process, to send them on)."""
    recorder = _Recorder(on_integration)

    def attach(world: World) -> None:
        world.antenna.recorder = recorder

    t0 = time.perf_counter()
    run = simulate(quiet, seed=seed, on_world=attach)
    wall = time.perf_counter() - t0
    program = run.program
    starts = np.array([it["t"][0] for it in recorder.items])
    n_scans = len(program.outcomes)
    scan_int = np.zeros((n_scans, 2, 5), dtype=np.int64)
    scan_times = np.zeros((n_scans, 2, 5))
    spans = np.zeros(n_scans)
    for s, outcome in enumerate(program.outcomes):
        raw = outcome.reduced.raw
        spans[s] = raw.t_end_s - raw.t_start_s
        for a, axis in enumerate(("az", "el")):
            for k, integ in enumerate(raw.integrations[axis]):
                seconds = integ.t_end_s - integ.t_start_s
                # the recorder's sample times start half a sample after the integration
                j = int(np.argmin(np.abs(starts - integ.t_start_s)))
                if abs(starts[j] - integ.t_start_s) > seconds:
                    raise RuntimeError("recorded integrations do not match the scans")
                scan_int[s, a, k] = j
                scan_times[s, a, k] = integ.t_mid_s
    avg = [r for r in run.rows if r["polarization"] == "AVG"]
    names = ("az_deg", "el_deg", "model_xel_arcmin", "model_el_arcmin", "applied_xel_arcmin",
             "applied_el_arcmin", "sun_el_deg", "t_s", "xel_arcmin", "el_arcmin", "good")
    # an equatorial mount's rows also carry hour angle and declination, which its fit uses
    names += tuple(n for n in ("ha_deg", "dec_deg") if avg and n in avg[0])
    # structure temperatures, which thermal terms of the fit read
    names += tuple(n for n in (avg[0] if avg else ()) if n.startswith("temp_"))
    columns = {n: np.array([r[n] for r in avg]) for n in names}
    columns["polarization"] = np.array(["AVG"] * len(avg))
    shared = SharedSchedule(
        t=[it["t"] for it in recorder.items], enc_az=[it["enc_az"] for it in recorder.items],
        enc_el=[it["enc_el"] for it in recorder.items],
        state=[it["state"] for it in recorder.items],
        paths=[it["paths"] for it in recorder.items], scan_int=scan_int,
        scan_times=scan_times, columns=columns, sources=[r["source"] for r in avg],
        searches=int(program.searches), duration_s=quiet.duration_s, scan_spans_s=spans,
        wall_s=wall, channels=tuple(run.world.antenna.channels), scan_sky_k=_scan_sky(program),
        sensor_lag_s=quiet.controller.structure_lag_s)
    return shared, run


def _scan_sky(program) -> np.ndarray | None:
    """The sky emission each recorded scan had subtracted (K), (scans, axes, channels, 5)."""
    skies = [o.sky_k for o in program.outcomes]
    if all(sky is None for sky in skies):
        return None
    shape = next(sky.shape for sky in skies if sky is not None)
    return np.stack([np.zeros(shape) if sky is None else sky for sky in skies]).swapaxes(2, 3)

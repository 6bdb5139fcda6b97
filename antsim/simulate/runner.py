"""Running a campaign: world and control program in one simpy environment.

:func:`simulate` runs a scenario and returns the rows the controller recorded (in memory);
:func:`run_campaign` does the same while writing ``recordings.ecsv`` scan by scan (resumable)
and ``truth.json`` into an output directory. Same scenario and seed give the same bytes.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import simpy

from antsim._version import __version__
from antsim.outdir import write_file
from antsim.progress import Progress, progress_for
from antsim.scenario import Scenario
from antsim.simulate.equivalents import recoverable_truth
from antsim.world.world import World
from controller.astro.earth import UtcLabeller
from controller.errors import InputError
from controller.pointing.legacy import w_terms_marker
from controller.pointing.model import PointingModel
from controller.program.campaign import ControlProgram, plan_targets
from controller.program.observer import never_rises, never_visible, why_unschedulable
from controller.program.optical import OpticalPointingProgram
from controller.program.recordings import RecordingWriter, recording_columns
from controller.protocol import Antenna

__all__ = ["NoScanError", "RunResult", "check_scenario", "recording_meta", "run_campaign",
           "simulate"]


class NoScanError(InputError):
    """A scenario whose controller can schedule no scan at all (its window, elevation,
    hour-angle and declination limits never let a source be observed)."""


@dataclass
class RunResult:
    """What a campaign produced."""

    scenario: Scenario
    seed: int
    model: PointingModel
    rows: list[dict] = field(default_factory=list)
    truth: dict = field(default_factory=dict)
    program: ControlProgram | None = None
    world: World | None = None
    wall_s: float = 0.0
    out_dir: Path | None = None
    #: the gain curve and opacity (controller.scans.gaincurve.Calibration), set by write_outputs
    calibration: object = None
    #: the tipping scans the controller made (controller.tipping), for the calibration
    tippings: list = field(default_factory=list)

    @property
    def n_scans(self) -> int:
        return len({r["scan"] for r in self.rows})


def recording_meta(scenario: Scenario, seed: int, model: PointingModel) -> dict:
    """Metadata of ``recordings.ecsv`` (docs/contract.md)."""
    c = scenario.controller
    site = scenario.site
    return {
        "scenario": scenario.name,
        "seed": int(seed),
        "software": f"antsim {__version__}",
        "site": {"name": site.name, "latitude_deg": site.latitude_deg,
                 "longitude_deg": site.longitude_deg, "height_m": site.height_m},
        "epoch_utc": scenario.epoch_utc,
        "duration_s": scenario.duration_s,
        "beam_hpbw_arcmin": c.scan.hpbw_arcmin,
        "step_arcmin": c.scan.step_arcmin,
        "integration_s": c.scan.integration_s,
        "estimator": c.scan.estimator,
        "refraction": c.refraction,
        "frequency_ghz": c.frequency_ghz,
        "model": {"name": model.name, "terms_arcsec": model.as_dict(),
                  **w_terms_marker(model.names)},
        "sign_convention": "xel/el: correction to apply (indicated minus true); total "
                           "pointing error = measured + model + applied",
        **({"mount": c.mount} if c.mount != "altaz" else {}),
        **({"method": c.method} if c.method != "five_point" else {}),
        **({"feed_angles_deg": list(c.feed_angles_deg)} if c.feed_angles_deg else {}),
        **({"structure_sensors": {"names": list(c.structure_sensors),
                                  "lag_s": c.structure_lag_s}}
           if c.structure_sensors else {}),
        **({"reduction_width_arcmin": {s.name: c.reduction_width_arcmin(s.name)
                                       for s in c.sources}}
           if c.scan.use_source_size else {}),
        **({"sky_subtracted": {"zenith_opacity": c.sky.zenith_opacity,
                               "t_atm_k": c.sky.t_atm_k}} if c.sky is not None else {}),
    }


def simulate(scenario: Scenario, seed: int | None = None, model: PointingModel | None = None,
             sink: Callable[[list[dict]], None] | None = None,
             progress: Callable[[float], None] | None = None,
             on_world: Callable[[World], None] | None = None,
             antenna: Antenna | None = None) -> RunResult:
    """Run the campaign in memory; ``sink`` also receives each scan's rows as they complete;
    ``on_world`` is called with the world before the campaign starts (e.g. to attach the
    antenna's recorder, as ``antsim.plan`` does). With ``antenna`` (e.g. a
    :class:`controller.wire.KatcpAntenna`, whose ``env`` the controller then runs in) the
    controller drives it instead of a simulated world, and the result has no truth."""
    seed = scenario.seed if seed is None else int(seed)
    if model is not None:
        scenario = scenario.with_controller_model(model)
    model = scenario.controller.model
    t0 = time.perf_counter()
    world = None
    if antenna is None:
        env = simpy.Environment()
        world = World(scenario, env, seed)
        antenna = world.antenna
    else:
        env = antenna.env
    if on_world is not None and world is not None:
        on_world(world)
    labeller = UtcLabeller(scenario.epoch_utc, scenario.duration_s)
    rows: list[dict] = []

    def collect(scan_rows: list[dict]) -> None:
        for row in scan_rows:
            row["time"] = labeller(row["t_s"])
        rows.extend(scan_rows)
        if sink:
            sink(scan_rows)

    program_class: type[ControlProgram] = ControlProgram
    if scenario.controller.method == "optical":
        program_class = OpticalPointingProgram
    program = program_class(scenario.controller, antenna, sink=collect, progress=progress)
    if program.scan_duration_s > scenario.duration_s:
        raise InputError(scenario.path, "campaign.duration_h", scenario.duration_s / 3600.0,
                         f"is shorter than one observation ({program.scan_duration_s:g} s)",
                         "lengthen the campaign or shorten controller.scan.integration_s")
    check_scenario(scenario, program.observer, program.targets)
    env.run(until=env.process(program.run(env)))
    truth = {}
    if world is not None:
        truth = world.truth()
        recoverable = recoverable_truth(rows, scenario, world)
        if recoverable is not None:
            truth["recoverable"] = recoverable.as_json()
    return RunResult(scenario=scenario, seed=seed, model=model, rows=rows, truth=truth,
                     program=program, world=world, wall_s=time.perf_counter() - t0,
                     tippings=list(getattr(program, "tippings", ())))


def check_scenario(scenario: Scenario, observer=None, targets=None) -> None:
    """Checks that need the sky, made before anything runs or is written: a catalogue source
    that never rises above the elevation limit at this site, a source the scheduler is told
    to observe that is never inside the elevation window during the campaign, or limits
    (window, elevations, hour angle, declination) that let no source be observed at any time
    (:class:`NoScanError`)."""
    if observer is None:
        observer, targets = plan_targets(scenario.controller)
    sched = scenario.controller.scheduler
    names = [s.name for s in scenario.sources]
    low = never_rises(observer, targets, scenario.site.latitude_deg, sched.elevation_min_deg)
    if low:
        name = low[0].name
        i = names.index(name)
        raise InputError(scenario.path, f"sources[{i}].dec", scenario.sources[i].dec_deg,
                         f"{name} never rises above controller.scheduler.elevation_min_deg = "
                         f"{sched.elevation_min_deg:g} deg at latitude "
                         f"{scenario.site.latitude_deg:g}",
                         "remove it, or list the observable ones in "
                         "controller.scheduler.sources")
    if sched.sources:
        missing = never_visible(observer, targets, sched, scenario.duration_s)
        if missing:
            raise InputError(scenario.path, "controller.scheduler.sources", missing[0].name,
                             f"never between {sched.elevation_min_deg:g} and "
                             f"{sched.elevation_max_deg:g} deg elevation during the campaign",
                             "remove it or lengthen the campaign")
    key, why = why_unschedulable(observer, targets, sched, scenario.duration_s)
    if why:
        raise NoScanError(scenario.path, f"controller.scheduler.{key}", getattr(sched, key),
                          f"the controller can schedule no scan: {why}",
                          "widen the scheduler's limits, or move or lengthen the campaign")


def run_campaign(scenario: Scenario, out_dir: str | Path, seed: int | None = None,
                 model: PointingModel | None = None, resume: bool = False,
                 show_progress: Progress | bool | None = None,
                 antenna: Antenna | None = None) -> RunResult:
    """Simulate into ``out_dir``: recordings.ecsv (scan by scan) and truth.json (not with
    ``antenna``, see :func:`simulate`: the truth is the antenna's). ``show_progress``: the
    command's :class:`~antsim.progress.Progress`, or whether to show one (None: a bar on a
    terminal, lines off one)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    seed = scenario.seed if seed is None else int(seed)
    use_model = model if model is not None else scenario.controller.model
    meta = recording_meta(scenario, seed, use_model)
    check_scenario(scenario)  # refuse before anything is written
    shown, owned = progress_for(show_progress, "run")
    hours = round(scenario.duration_s / 3600.0, 2)
    shown.stage("campaign", total=hours, unit="h")

    def progress(t_s: float) -> None:
        shown.set(round(min(t_s, scenario.duration_s) / 3600.0, 2))

    columns = recording_columns(scenario.controller.mount,
                                bool(scenario.controller.feed_angles_deg),
                                scenario.controller.structure_sensors)
    with RecordingWriter(out / "recordings.ecsv", meta, resume=resume,
                         columns=columns) as writer:
        try:
            result = simulate(scenario, seed, model, sink=writer.write_scan, progress=progress,
                              antenna=antenna)
            writer.check_replayed()  # rows this run would not write: refused, kept
            if not result.rows and writer.existing_rows == 0:
                raise NoScanError(scenario.path, "campaign.duration_h",
                                  scenario.duration_s / 3600.0, "the controller made no scan "
                                  "in the campaign: no source was within its limits when it "
                                  "looked", "widen the scheduler's limits, or move or "
                                  "lengthen the campaign")
        except BaseException:
            # a file with a header and no scan would only block the next plain run
            if writer.rows_written == 0 and writer.existing_rows == 0:
                writer.discard()
            raise
        finally:
            if owned:
                shown.close()
    result.out_dir = out
    if antenna is None:
        write_file(out / "truth.json", json.dumps(result.truth, indent=2) + "\n")
    return result



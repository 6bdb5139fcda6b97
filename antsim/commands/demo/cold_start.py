"""Chapter 1 of the walk-through, a cold start: where an antenna without a pointing model
misses. An azimuth encoder offset W6 is W6 cos E on the sky: inside the 11' beam for a
source high in the sky, beyond it for one rising, whose first scan misses; the controller's
wide search finds it and the next scan is centred. The 1990 report's W6, 12.24', leaves
3C84 rising at 21 deg some 8.7' away across, which the five points still measure (short, but
not a miss), so the chapter's mount has its encoder zero lost further,
:data:`COLD_START_W6_ARCMIN`, and says so. The scans are those of the campaign's first
minutes, replayed with an antenna that remembers every integration."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path
from typing import Any

from controller.units import ARCMIN_PER_RAD

from .story import Story

__all__ = ["COLD_START_HIGH", "COLD_START_LOW", "tell"]

#: the cold start is shown on a source high in the sky, then on one low in the sky (where the
#: azimuth encoder offset is nearly all on the sky), each the first of its list that is up
COLD_START_HIGH = ("Cassiopeia A", "Cygnus A")
COLD_START_LOW = ("3C84", "W31", "Taurus A")
#: the chapter's azimuth encoder offset (arcmin): the report's 12.24' is measured, short, by
#: a first scan at 21 deg; 16' is missed there (12' across)
COLD_START_W6_ARCMIN = 16.0


class _RecordingAntenna:
    """Wraps an antenna and remembers every scan the controller makes: the offsets it set
    and the integrations it received (read after the simulation ran)."""

    def __init__(self, antenna):
        self._antenna = antenna
        self.channels = antenna.channels
        self.scans: list[list[tuple[tuple[float, float], Any]]] = []
        self._offset = (0.0, 0.0)

    def __getattr__(self, name: str):
        return getattr(self._antenna, name)

    def track(self, trajectory, label: str = ""):
        self._offset = (0.0, 0.0)
        self.scans.append([])
        return self._antenna.track(trajectory, label)

    def set_offset(self, d_az_deg: float, d_el_deg: float):
        self._offset = (d_az_deg, d_el_deg)
        return self._antenna.set_offset(d_az_deg, d_el_deg)

    def integrate(self, seconds: float):
        event = self._antenna.integrate(seconds)
        self.scans[-1].append((self._offset, event))
        return event


def _trace(label: str, scan: list) -> Any:
    """A :class:`~antsim.figures.demo.ScanTrace` (sky offsets, power above the baseline of the
    mean of both channels) from the recorded integrations of one cross scan."""
    import numpy as np

    from antsim.figures.demo import ScanTrace

    half = len(scan) // 2
    axes = []
    for part, axis in ((scan[:half], 0), (scan[half:], 1)):
        offsets, powers = [], []
        for (d_az, d_el), event in part:
            integ = event.value
            if axis == 0:
                offsets.append(d_az * 60.0 * math.cos(math.radians(integ.enc_el_deg)))
            else:
                offsets.append(d_el * 60.0)
            powers.append(float(np.mean(list(integ.power_k.values()))))
        offsets_a, powers_a = np.array(offsets), np.array(powers)
        ends = np.argsort(np.abs(offsets_a))[-2:]  # the two outer (+-4 step) positions
        axes.append((offsets_a, powers_a - powers_a[ends].mean()))
    return ScanTrace(label, axes[0][0], axes[0][1], axes[1][0], axes[1][1])


def _cold_observe(cold, name: str):
    """One scan of source ``name`` by a controller without a model, at the campaign's start
    (a fresh world): (outcome, the recording antenna, the target), or None when
    the source is not up."""
    import simpy

    from antsim.world.world import World
    from controller.program.campaign import ControlProgram
    from controller.protocol import AntennaError

    env = simpy.Environment()
    world = World(cold, env, cold.seed)
    antenna = _RecordingAntenna(world.antenna)
    program = ControlProgram(cold.controller, antenna)
    targets = [t for t in program.targets if t.name == name]
    if not targets:
        return None
    try:
        outcome = env.run(until=env.process(program.observe(env, targets[0])))
    except AntennaError:  # below the horizon or the limits at the start
        return None
    return outcome, antenna, targets[0]


def _true_error_arcmin(cold, row) -> tuple[float, float]:
    """The injected geometry's error (indicated - true) at a row's position: (dA cos E, dE)
    arcmin. The simulation knows it; the controller does not."""
    d_az, d_el = cold.truth_model.offset_rad(math.radians(row["az_deg"]),
                                             math.radians(row["el_deg"]))
    return (float(d_az) * math.cos(math.radians(row["el_deg"])) * ARCMIN_PER_RAD,
            float(d_el) * ARCMIN_PER_RAD)


def tell(story: Story, scenario, figdir: Path) -> dict[str, Any]:
    """Tell chapter 1 with ``scenario`` (its controller's model replaced by none); its
    figure goes to ``figdir``. Returns the numbers it quoted (for demo.json)."""
    from antsim.figures.demo import scan_trace_figure
    from controller.pointing.model import PointingModel

    ch = story.chapter("1. A cold start: where the antenna misses")
    truth = cold_truth = scenario.truth_model.as_dict()
    report_w6 = truth.get("W6", math.nan) / 60.0
    if "W6" in truth:
        cold_truth = {**truth, "W6": 60.0 * COLD_START_W6_ARCMIN}
    cold = replace(scenario, truth_model=PointingModel(list(cold_truth), list(cold_truth.values()),
                                                       name=scenario.truth_model.name))
    cold = cold.with_controller_model(PointingModel("none"))
    w6 = cold_truth.get("W6", math.nan) / 60.0
    hpbw = cold.beam.hpbw_arcmin
    story.say(ch, (
        "A radio telescope is pointed by commanding its two axes, azimuth and elevation, to "
        "where the source should be. But no real mount is perfect: encoders have zero offsets, "
        "axes are tilted, the structure sags under gravity. Here we start with no pointing "
        f"model at all, and the 45-ft's azimuth encoder reads {w6:.2f} arcminutes ahead (the "
        f"1990 report's W6, its azimuth encoder offset, was {report_w6:.2f}'; suppose its zero "
        "was lost further since). On the sky an azimuth error shrinks with "
        f"the cosine of the elevation: {w6:.2f}' cos E is {w6 * math.cos(math.radians(20)):.1f}' "
        f"at 20 deg, {w6 * math.cos(math.radians(60)):.1f}' at 60 deg, against a {hpbw:g}' "
        "beam. Where the antenna misses depends on where it looks."))
    numbers: dict[str, Any] = {}
    for name in COLD_START_HIGH:
        got = _cold_observe(cold, name)
        if got is None:
            continue
        outcome, _, target = got
        row = outcome.rows[-1]
        true_xel, true_el = _true_error_arcmin(cold, row)
        found = ("the first scan found it" if outcome.searches == 0 else
                 f"it took {outcome.searches} wide search(es)")
        story.say(ch, (
            f"First {target.name}, at {row['el_deg']:.0f} deg elevation: the mount's errors "
            f"there are {true_xel:+.1f}' across and {true_el:+.1f}' in elevation (the "
            f"simulation knows them; the controller does not), and {found}: the scan "
            f"measured {row['xel_arcmin'] + row['applied_xel_arcmin']:+.2f}' and "
            f"{row['el_arcmin'] + row['applied_el_arcmin']:+.2f}'. High in the sky the "
            "azimuth offset is only a fraction of the beam."))
        numbers["cold_start_high"] = {"source": target.name, "el_deg": row["el_deg"],
                                      "searches": outcome.searches,
                                      "true_arcmin": (true_xel, true_el)}
        break
    for name in COLD_START_LOW:
        got = _cold_observe(cold, name)
        if got is None or got[0].searches == 0 or len(got[1].scans) < 3:
            continue
        outcome, antenna, target = got
        break
    else:
        story.say(ch, "(No source low in the sky at the start of this scenario was missed "
                      "by its first scan: there is no search to show.)")
        numbers["cold_start_searches"] = 0
        return numbers
    row = outcome.rows[-1]
    true_xel, true_el = _true_error_arcmin(cold, row)
    step = cold.controller.scan.step_arcmin
    wide = step * cold.controller.search.step_factor
    labels = [f"1: first scan, no model (step {step:g}')",
              f"2: wide search (step {wide:g}')",
              "3: scan with the search's correction"]
    traces = [_trace(labels[min(k, 2)] if k < 3 else f"{k + 1}: scan", s)
              for k, s in enumerate(antenna.scans)]
    corr_xel, corr_el = row["applied_xel_arcmin"], row["applied_el_arcmin"]
    fig = scan_trace_figure(
        traces[:3], figdir / "demo1_cold_start.png", hpbw_arcmin=hpbw,
        ylabel="power above the baseline (K, mean of XR and XL)",
        title=f"A cold start on {target.name}: a miss, a wide search, a hit",
        caption=(f"Power above the baseline along the two halves of each cross scan on "
                 f"{target.name} at {row['el_deg']:.0f} deg elevation. Scan 1 (no pointing "
                 f"model) passes {true_xel:+.1f}' beside the source in cross-elevation (the "
                 "azimuth encoder offset, seen low in the sky) and sees at most the edge of "
                 "the beam. The wide search (twice the step) catches it; scan 3, with the "
                 "offset the search found, sees the peak."),
        formats=("png",))
    story.figure(ch, fig)
    peak_first = max(float(traces[0].az_power_k.max()), float(traces[0].el_power_k.max()))
    peak_last = max(float(traces[2].az_power_k.max()), float(traces[2].el_power_k.max()))
    adopted = (f"adopted that as a running correction (its elevation scan had passed the "
               f"source {abs(corr_xel):.0f}' to the side, too far to trust)" if corr_el == 0
               else f"adopted that and {corr_el:+.1f}' in elevation as a running correction")
    story.say(ch, (
        f"Then {target.name}, rising at {row['el_deg']:.0f} deg: there the errors are "
        f"{true_xel:+.1f}' across and {true_el:+.1f}' in elevation. Scan 1 found at most "
        f"{peak_first:.2f} K above the baseline, and the reduction could not place the "
        f"source: a miss. The controller then made a wide cross scan with {wide:g}' steps, "
        f"found the source {corr_xel:+.1f}' away in cross-elevation and {adopted}. Scan 3 "
        f"sees {peak_last:.2f} K: the source is in the beam, and the scan measures the rest, "
        f"{row['xel_arcmin']:+.2f}' and {row['el_arcmin']:+.2f}'. The controller keeps the "
        "correction as an azimuth offset, "
        f"{corr_xel / math.cos(math.radians(row['el_deg'])):+.1f}', so that it fits every "
        "elevation as an encoder offset does. That is how a cold start goes: search, then "
        "measure."))
    numbers.update({"cold_start_source": target.name, "cold_start_el_deg": row["el_deg"],
                    "cold_start_searches": outcome.searches,
                    "cold_start_peaks_k": (peak_first, peak_last),
                    "cold_start_true_arcmin": (true_xel, true_el),
                    "cold_start_correction_arcmin": (corr_xel, corr_el),
                    "cold_start_final_arcmin": (row["xel_arcmin"], row["el_arcmin"])})
    return numbers

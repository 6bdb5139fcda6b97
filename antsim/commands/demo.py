"""`antsim demo [--out DIR]`: the teaching walk-through, from a cold start to a closed loop.

Five chapters, each printed to stdout as it runs and collected into ``DIR/demo.html``:

1. A cold start: with no pointing model the 45-ft's azimuth encoder offset (the 1990
   report's W6 = 12.24') is 12.24' cos E on the sky: inside the 11' beam for Cassiopeia A
   high in the sky, beyond it for a source rising at 20 deg, which the first scan misses; the
   controller's wide search finds it and the next scan is centred.
2. The first campaign: 24 hours of five-point scans from that cold start.
3. The fit: the 1990 report's ten-term model recovers the injected coefficients.
4. Closing the loop: a second (12-hour) campaign with the fitted model points to the accuracy
   the fit promised.
5. A hidden effect: a third campaign on an antenna with an uneven azimuth track (a term the
   ten-term model does not have); ``antsim diagnose`` is asked to find it.

Every campaign is written as ``antsim run`` would write it (recordings, fits, model.dat; a
full report for the first), under ``DIR/1-first-campaign`` etc., with the scenario files
used, so that a student can repeat any step from the command line.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import textwrap
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from antsim.bundled import find, shown
from antsim.outdir import write_file
from controller.errors import InputError
from controller.units import ARCMIN_PER_RAD

#: the hidden effect of chapter 5: an uneven azimuth track, dE = HESA2 sin 2A_H (arcsec; TPOINT's
#: harmonic azimuth A_H = -A_N, controller/pointing/terms.py), i.e. a correction of +60" sin 2A_N
HIDDEN_TERM = "HESA2"
HIDDEN_ARCSEC = -60.0
#: length of the closed-loop campaign (h): long enough for ~130 scans over day and night
CLOSED_LOOP_HOURS = 12.0
#: seeds of the three campaigns (a new night's noise for each)
SEEDS = (1, 2, 3)
#: the cold start is shown on a source high in the sky, then on one low in the sky (where the
#: azimuth encoder offset is nearly all on the sky), each the first of its list that is up
COLD_START_HIGH = ("Cassiopeia A", "Cygnus A")
COLD_START_LOW = ("3C84", "W31", "Taurus A")


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--out", default="antsim-demo",
                        help="output directory (default: ./antsim-demo); an earlier demo's "
                             "directory is overwritten, any other non-empty one refused")
    parser.add_argument("--scenario", default="ghigo1990",
                        help="the 1990 scenario: a name or a TOML file (default: ghigo1990, "
                             "the one that comes with antsim)")
    parser.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                        help="a progress bar, or none (default: a bar on a terminal, a line "
                             "every few seconds to stderr off one)")
    parser.epilog = ("Runs three campaigns (24 h, 12 h, 24 h of simulated time); about half a "
                     "minute. Writes DIR/demo.html, DIR/demo.json (the numbers quoted) and "
                     "DIR/figures/.")


def main(args: argparse.Namespace) -> int:
    from antsim.outdir import LOCK_NAME, DirectoryLock, output_dir
    from antsim.progress import Progress

    scenario_path = find(args.scenario, field="--scenario")
    if Path(args.out).exists() and not Path(args.out).is_dir():
        raise InputError("command line", "--out", args.out, "exists and is not a directory")
    if Path(args.out).is_dir() and not (Path(args.out) / "demo.html").exists() and any(
            p.name != LOCK_NAME for p in Path(args.out).iterdir()):
        raise InputError("command line", "--out", args.out,
                         "is not empty and holds no earlier demo", "choose a new directory")
    out = output_dir(args.out)
    with DirectoryLock(out, "--out", "antsim demo"), Progress("demo", args.progress) as progress:
        run_demo(out, scenario_path, echo=progress.write, on_chapter=progress.stage)
    return 0


# ---------------------------------------------------------------------------------------------
# chapters
# ---------------------------------------------------------------------------------------------
@dataclass
class Chapter:
    """One step of the story: a title, captions (plain text), and report blocks."""

    title: str
    blocks: list = field(default_factory=list)


class _Story:
    """Collects chapters for demo.html and prints their captions as they are told."""

    def __init__(self, echo: Callable[[str], None],
                 on_chapter: Callable[[str], None] | None = None):
        self.echo = echo
        self.on_chapter = on_chapter
        self.chapters: list[Chapter] = []

    def chapter(self, title: str) -> Chapter:
        if self.on_chapter is not None:
            self.on_chapter(title)
        self.chapters.append(Chapter(title))
        self.echo("")
        self.echo(title)
        self.echo("=" * len(title))
        return self.chapters[-1]

    def say(self, chapter: Chapter, text: str) -> None:
        from antsim.figures.html import Paragraph

        chapter.blocks.append(Paragraph(text))
        self.echo(textwrap.fill(text, width=92))
        self.echo("")

    def command(self, chapter: Chapter, text: str) -> None:
        from antsim.figures.html import Preformatted

        chapter.blocks.append(Preformatted(text, caption="Try it yourself"))
        self.echo("  $ " + text.replace("\n", "\n  $ "))
        self.echo("")

    def figure(self, chapter: Chapter, figure) -> None:
        from antsim.figures.html import Figure

        chapter.blocks.append(Figure.of(figure))
        self.echo(f"  [figure: {figure.path}]")

    def table(self, chapter: Chapter, table) -> None:
        chapter.blocks.append(table)


def _edit(text: str, old: str, new: str, where: str) -> str:
    """``text`` with ``old`` (which must occur exactly once) replaced by ``new``."""
    if text.count(old) != 1:
        raise InputError(where, "scenario text", old,
                         f"occurs {text.count(old)} times (the demo expects it once)",
                         "use the ghigo1990 scenario that comes with antsim")
    return text.replace(old, new)


def run_demo(out: Path, scenario_path: Path,
             echo: Callable[[str], None] = print,
             on_chapter: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Tell the story into ``out``; returns the numbers a test or a teacher may want.
    ``on_chapter`` is told each chapter's title as it starts (the command's progress)."""
    from antsim.figures.html import Section, write_report
    from antsim.scenario import load_scenario

    t0 = time.perf_counter()
    out.mkdir(parents=True, exist_ok=True)
    figdir = out / "figures"
    story = _Story(echo, on_chapter)
    base_text = scenario_path.read_text(encoding="utf-8")
    scenario = load_scenario(scenario_path)
    numbers: dict[str, Any] = {}
    echo(f"antsim demo: the pointing of the NRAO Green Bank 45-ft, 8-9 February 1990 -> {out}")

    numbers.update(_cold_start(story, scenario, figdir))
    first, fits, more = _first_campaign(story, scenario, scenario_path, out)
    numbers.update(more)
    numbers.update(_the_fit(story, first, fits, out))
    numbers.update(_closed_loop(story, base_text, scenario_path, out, first, fits, figdir,
                                numbers["first_sky_rms_arcsec"]))
    numbers.update(_hidden_effect(story, base_text, scenario_path, out, figdir,
                                  numbers["fit_sky_rms_arcsec"]))

    sections = [Section(c.title, c.blocks) for c in story.chapters]
    path = write_report(
        out / "demo.html", "How a radio telescope is pointed: a walk-through with antsim",
        sections, subtitle="The NRAO Green Bank 45-ft at X-band, 8-9 February 1990 "
                           "(simulated): from a cold start to a closed loop")
    numbers["wall_s"] = time.perf_counter() - t0
    numbers["html"] = str(path)
    numbers["chapters"] = [c.title for c in story.chapters]
    write_file(out / "demo.json", json.dumps(numbers, indent=2, default=str) + "\n")
    echo(f"\nwrote {path} ({len(story.chapters)} chapters) and demo.json in "
         f"{numbers['wall_s']:.1f} s")
    return numbers


# ---------------------------------------------------------------------------------------------
# 1. the cold start
# ---------------------------------------------------------------------------------------------
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


def _cold_start(story: _Story, scenario, figdir: Path) -> dict[str, Any]:
    from antsim.figures.demo import scan_trace_figure
    from controller.pointing.model import PointingModel

    ch = story.chapter("1. A cold start: where the antenna misses")
    cold = scenario.with_controller_model(PointingModel("none"))
    w6 = cold.truth_model.as_dict().get("W6", math.nan) / 60.0
    hpbw = cold.beam.hpbw_arcmin
    story.say(ch, (
        "A radio telescope is pointed by commanding its two axes, azimuth and elevation, to "
        "where the source should be. But no real mount is perfect: encoders have zero offsets, "
        "axes are tilted, the structure sags under gravity. Here we start with no pointing "
        f"model at all. The 45-ft's azimuth encoder reads {w6:.2f} arcminutes ahead (the 1990 "
        f"report's W6, its azimuth encoder offset). On the sky an azimuth error shrinks with "
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


# ---------------------------------------------------------------------------------------------
# 2. the first campaign, 3. the fit
# ---------------------------------------------------------------------------------------------
def _campaign(scenario, out: Path, seed: int, model, report: bool):
    from antsim.run.outputs import run_fits, write_outputs
    from antsim.simulate.runner import run_campaign

    result = run_campaign(scenario, out, seed=seed, model=model, show_progress=False)
    write_outputs(result, report=report)
    return result, run_fits(result)


def _first_campaign(story: _Story, scenario, scenario_path: Path, out: Path):
    import numpy as np

    from antsim.figures.html import Figure
    from controller.pointing.model import PointingModel

    ch = story.chapter("2. The first campaign: 24 hours of cross scans")
    story.say(ch, (
        "Now the real work of a pointing run: for 24 hours the controller visits the eight "
        "bright sources of the 1990 run in turn, spreading them over the sky, and on each "
        "makes a five-point cross scan: integrations at -4, -1, 0, +1 and +4 steps of 7' in "
        "azimuth, then in elevation. From the powers it computes where the source really was "
        "(Clark's method). Still no pointing model: only the running correction from the "
        "first search."))
    run_dir = out / "1-first-campaign"
    result, fits = _campaign(scenario, run_dir, SEEDS[0], PointingModel("none"), report=True)
    rows = [r for r in result.rows if r["polarization"] == "AVG" and r["good"]]
    xel = np.array([60 * (r["xel_arcmin"] + r["model_xel_arcmin"] + r["applied_xel_arcmin"])
                    for r in rows])
    el = np.array([60 * (r["el_arcmin"] + r["model_el_arcmin"] + r["applied_el_arcmin"])
                   for r in rows])
    figs = {p.stem: p for p in (run_dir / "figures").glob("*.png")}
    for stem, title, caption in (
            ("fig1_sky", "Where the antenna looked (the 1990 report's Fig. 1)",
             "Each dot is one scan: azimuth around the circle (North up, East right), zenith "
             "distance outwards. The sources rise in the east and set in the west; a good "
             "pointing run covers as much of the sky as it can."),
            ("fig2_total_errors", "How wrong the bare mount is (Fig. 2a-d)",
             "The total pointing error of every scan, against elevation and azimuth. The "
             "cross-elevation error (a) falls steeply from the horizon to the zenith: the "
             "azimuth encoder offset seen on the sky, W6 cos E, as the 1990 report's Fig. 2a "
             "showed; the elevation error, a few arcminutes, changes smoothly with elevation "
             "(gravity, refraction) and azimuth (a tilted azimuth axis).")):
        if stem in figs:
            ch.blocks.append(Figure(figs[stem], title, caption))
            story.echo(f"  [figure: {figs[stem]}]")
    el_deg = np.array([r["el_deg"] for r in rows])
    low, high = xel[el_deg < 25.0], xel[el_deg > 65.0]
    story.say(ch, (
        f"{result.n_scans} scans ({len(rows)} good), {result.program.searches} wide "
        f"search(es). Without a model the cross-elevation error ranges from "
        f"{xel.min() / 60:+.1f}' to {xel.max() / 60:+.1f}': "
        + (f"{low.mean() / 60:+.1f}' on average below 25 deg and {high.mean() / 60:+.1f}' "
           "above 65 deg, the azimuth encoder offset shrinking on the sky as cos E (plus "
           "the collimation and axis terms). " if low.size and high.size else "")
        + f"The elevation error averages {el.mean() / 60:+.2f}'. These are not noise: they "
        "are the mount's geometry, repeatable, and therefore fittable. The full report of "
        f"this campaign is {run_dir / 'report.html'}."))
    story.command(ch, f"antsim run {shown(scenario_path)} --out {run_dir} --model none")
    sky = float(np.sqrt(np.mean(xel ** 2 + el ** 2)))
    return result, fits, {"first_scans": result.n_scans,
                          "first_searches": result.program.searches,
                          "first_xel_low_high_arcmin": (
                              float(low.mean() / 60) if low.size else math.nan,
                              float(high.mean() / 60) if high.size else math.nan),
                          "first_sky_rms_arcsec": sky}


def _pulls(fit, truth: dict[str, float]) -> dict[str, float]:
    """(fit - truth) / honest sigma per term that has a truth (TPOINT sigma if no honest)."""
    sigma = fit.sigma_honest_arcsec if fit.sigma_honest_arcsec is not None \
        else fit.sigma_arcsec
    return {n: (float(v) - truth[n]) / float(s)
            for n, v, s in zip(fit.names, fit.values_arcsec, sigma, strict=True)
            if n in truth and s > 0}


def _the_fit(story: _Story, result, fits, out: Path) -> dict[str, Any]:
    from antsim.figures.html import Figure
    from antsim.run.report import fit_summary_table, truth_pull_table, truth_terms_arcsec

    ch = story.chapter("3. The fit: ten numbers that describe the mount")
    fit = fits["A"]
    truth = truth_terms_arcsec(result.truth)
    run_dir = out / "1-first-campaign"
    story.say(ch, (
        "The 1990 report describes the 45-ft's errors with ten terms, W1..W10: encoder zero "
        "offsets, collimation, axis non-perpendicularity, gravitational sag, refraction, and "
        "the tilt of the azimuth axis. Each term has a signature (constant, sec E, tan E, "
        "cos E, cot E, cos A, sin A, ...) and a least-squares fit finds the mix that best "
        "matches the measured errors. As in the report, the fit is robust: a least-absolute-"
        "deviation fit first, then outliers (gusts of wind, bad scans) are rejected and least "
        f"squares finishes. Fit A used {fit.n_used} of {fit.n_input} scans."))
    story.table(ch, fit_summary_table(fits))
    figs = {p.stem: p for p in (run_dir / "figures").glob("*.png")}
    if "fig3_residuals" in figs:
        ch.blocks.append(Figure(
            figs["fig3_residuals"], "What the model leaves (Fig. 3a-d)",
            "The residuals after fit A: from arcminutes down to about half an arcminute. "
            "What is left is wind, thermal bending in sunshine and receiver noise: no "
            "pattern with elevation or azimuth (the black binned means stay near zero)."))
        story.echo(f"  [figure: {figs['fig3_residuals']}]")
    w6 = fit.names.index("W6") if "W6" in fit.names else None
    if truth:
        story.table(ch, truth_pull_table(fit, truth))
        if w6 is not None and "W6" in truth:
            pulls = _pulls(fit, truth)
            worst = max(pulls, key=lambda k: abs(pulls[k]))
            verdict = (
                "all within 3 honest sigmas of the truth: the fit recovered the mount."
                if abs(pulls[worst]) <= 3 else
                f"{worst} is {abs(pulls[worst]):.1f} honest sigmas off. Scans that start "
                "several arcminutes off the source are less accurate: the source sits on the "
                "flank of the beam, and the partly resolved sources (Cas A, Tau A) shrink the "
                "measured offsets by about 9%. That is why observatories iterate (chapter 4).")
            story.say(ch, (
                f"The simulation knows the truth, so we can check: W6 came out "
                f"{fit.values_arcsec[w6] / 60:.2f}' +- {fit.sigma_arcsec[w6] / 60:.2f}' "
                f"against the injected {truth['W6'] / 60:.2f}'. The pull, (fit - truth) / "
                "sigma, should be of order 1. The 'honest' sigma allows for residuals that are "
                "correlated in time (the Sun heats the structure for hours), which TPOINT's "
                "formal sigma ignores. Of the ten coefficients, " + verdict))
    story.say(ch, (
        f"Sky rms after the fit: {fit.sky_rms_arcsec:.1f}\" (xel {fit.xel_rms_arcsec:.1f}\", "
        f"el {fit.el_rms_arcsec:.1f}\"). The 1990 report found 23\" and 38\" for its fit A. "
        f"The fitted model is written as {run_dir / 'model.dat'}, a TPOINT model file in "
        "TPOINT's term names and signs (W6 is IA, W1 is -IE: TPOINT writes the correction, "
        "the report the error), each line saying which W it was."))
    story.command(ch, f"antsim fit {run_dir / 'recordings.ecsv'} --model ghigo10")
    return {"fit_sky_rms_arcsec": fit.sky_rms_arcsec,
            "fit_w6_arcmin": fit.values_arcsec[w6] / 60 if w6 is not None else math.nan}


# ---------------------------------------------------------------------------------------------
# 4. the closed loop
# ---------------------------------------------------------------------------------------------
def _closed_loop(story: _Story, base_text: str, scenario_path: Path, out: Path, first, fits,
                 figdir: Path, first_sky: float) -> dict[str, Any]:
    import numpy as np

    from antsim.figures.charts import histogram_figure
    from antsim.run.inuse import pointing_errors, pointing_in_use
    from antsim.run.report import truth_terms_arcsec
    from antsim.scenario import load_scenario
    from controller.pointing.modelio import load_model

    ch = story.chapter("4. Closing the loop: observing with the fitted model")
    model_path = out / "1-first-campaign" / "model.dat"
    text = _edit(base_text, "duration_h = 24.0", f"duration_h = {CLOSED_LOOP_HOURS:g}",
                 str(scenario_path))
    scen_path = out / "2-closed-loop.toml"
    write_file(scen_path, text)
    story.say(ch, (
        "A model is only worth something if it points the telescope. The controller now adds "
        "the fitted model to every command, and we observe again: a new night's noise "
        f"(seed {SEEDS[1]}), {CLOSED_LOOP_HOURS:g} hours. What the five-point scans measure "
        "now is the error that is left with the model in use. If the model is right, that "
        "error should be as small as the residuals of the fit promised."))
    model = load_model(model_path)
    result, refits = _campaign(load_scenario(scen_path), out / "2-closed-loop", SEEDS[1],
                               model, report=False)
    xel, el = pointing_errors(result.rows)
    in_use = pointing_in_use(result.rows, model)
    sky, xel_rms, el_rms = ((in_use.sky_rms_arcsec, in_use.xel_rms_arcsec, in_use.el_rms_arcsec)
                            if in_use is not None else (math.nan,) * 3)
    fit = fits["A"]
    used = np.asarray(fit.used, bool)
    hpbw_arcsec = first.scenario.beam.hpbw_arcmin * 60.0
    fig = histogram_figure(
        {"campaign 2: pointing errors with the fitted model": (xel, el),
         "campaign 1: residuals of fit A": (fit.residual_xel_arcsec[used],
                                             fit.residual_el_arcsec[used])},
        figdir / "demo4_closed_loop.png",
        title="Closing the loop: errors with the model in use against the fit's residuals",
        caption="Filled: what the scans of the second campaign measured, with the fitted "
                "model in use (the pointing error that is left). Line: the residuals of the "
                "fit of the first campaign. They agree: the model points the antenna as well "
                "as it fitted the data.")
    story.figure(ch, fig)
    ratio = sky / fit.sky_rms_arcsec
    searches = result.program.searches
    verdict = ("The two agree: the loop is closed" if 0.8 <= ratio <= 1.25 else
               f"That is {ratio:.2f} times the fit's residuals: the model does not point as "
               "well as it fitted" if ratio > 1.25 else
               "That is smaller than the fit's residuals: this campaign was kinder (fewer "
               "hours, less sunshine)")
    story.say(ch, (
        f"{xel.size} good scans, {searches} search(es)"
        + (": every source was in the beam at the first try. " if searches == 0 else ". ")
        + f"Pointing error rms with the fitted model: {sky:.1f}\" on the sky (xel "
        f"{xel_rms:.1f}\", el {el_rms:.1f}"
        f"\"), against {fit.sky_rms_arcsec:.1f}\" left by the fit of the first campaign. "
        f"{verdict}. The error went from {first_sky / 60:.1f}' rms without a model to "
        f"{sky / 60:.2f}', "
        f"{100 * sky / hpbw_arcsec:.0f}% of the {hpbw_arcsec / 60:g}' beam."))
    numbers: dict[str, Any] = {}
    refit = refits.get("A")
    truth = truth_terms_arcsec(first.truth)
    if refit is not None and "W6" in truth and "W6" in refit.names:
        j, k = refit.names.index("W6"), fit.names.index("W6")
        before, after = _pulls(fit, truth).get("W6"), _pulls(refit, truth).get("W6")
        numbers["refit_w6_arcmin"] = refit.values_arcsec[j] / 60
        story.say(ch, (
            "And the loop can go round again: fitting this second campaign, whose scans were "
            f"all close to centred, gives W6 = {refit.values_arcsec[j] / 60:.2f}' +- "
            f"{refit.sigma_arcsec[j] / 60:.2f}' (first fit {fit.values_arcsec[k] / 60:.2f}', "
            f"truth {truth['W6'] / 60:.2f}'; pull {after:+.1f} against {before:+.1f}) with "
            f"sky rms {refit.sky_rms_arcsec:.1f}\". A real observatory repeats the run now and "
            "then: the mount changes, and each pass starts closer to the truth."))
    story.command(ch, f"antsim run {scen_path} --out {out / '2-closed-loop'} --seed {SEEDS[1]} "
                      f"--model {model_path}")
    numbers.update({"closed_loop_sky_rms_arcsec": sky, "closed_loop_searches": searches,
                    "closed_loop_scans": result.n_scans})
    return numbers


# ---------------------------------------------------------------------------------------------
# 5. a hidden effect
# ---------------------------------------------------------------------------------------------
def run_diagnose_json(recordings: Path, scenario: Path, out_dir: Path
                      ) -> tuple[dict | None, str]:
    """``antsim diagnose RECORDINGS --scenario SCENARIO --json --out DIR`` in this process.

    Returns (the JSON document of DESIGN section 4, "") when the command succeeds, else
    (None, what it said). The demo relies only on that documented contract, not on the
    diagnose package's Python API.
    """
    from antsim.cli import main as cli_main

    stdout, stderr = io.StringIO(), io.StringIO()
    argv = ["diagnose", str(recordings), "--scenario", str(scenario), "--json",
            "--out", str(out_dir), "--no-progress"]
    with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
        try:
            status = cli_main(argv)
        except SystemExit as exc:  # argparse refusing an option the command does not have
            status = exc.code if isinstance(exc.code, int) else 2
        except Exception as exc:  # a teaching tool reports a failing feature and goes on
            status, stderr = 1, io.StringIO(f"it failed: {type(exc).__name__}: {exc}")
    message = " ".join((stderr.getvalue() or stdout.getvalue()).split())
    if status != 0:
        if len(message) > 200:
            message = message[:197] + "..."
        return None, message or f"exit status {status}"
    try:
        doc = json.loads(stdout.getvalue())
    except json.JSONDecodeError:
        return None, "its output was not JSON: " + stdout.getvalue()[:200]
    if not isinstance(doc, dict) or "findings" not in doc:
        return None, "its JSON has no 'findings'"
    return doc, ""


def _hidden_effect(story: _Story, base_text: str, scenario_path: Path, out: Path,
                   figdir: Path, reference_rms_arcsec: float) -> dict[str, Any]:
    import numpy as np

    from antsim.figures.charts import pointing_errors_figure
    from antsim.figures.diagnose import before_after_figures
    from antsim.scenario import load_scenario
    from controller.pointing.fitting import fit_model
    from controller.pointing.modelio import load_model
    from controller.pointing.terms import TermError, get_term
    from controller.pointing.variants import VARIANTS, columns, pointing_data, variant_mask

    ch = story.chapter("5. A hidden effect: what the model does not know")
    block = (f"\n# demo chapter 5: the hidden effect, an uneven azimuth track\n"
             f"[[truth.effects]]\neffect = \"terms\"\n{HIDDEN_TERM} = {HIDDEN_ARCSEC:g}\n")
    scen_path = out / "3-hidden-effect.toml"
    write_file(scen_path, base_text.rstrip("\n") + "\n" + block)
    run_dir = out / "3-hidden-effect"
    story.say(ch, (
        "Real antennas have more faults than any model lists. We now observe a third time "
        f"(seed {SEEDS[2]}, 24 hours, the fitted model in use) with an antenna that has a "
        "fault the ten-term model cannot describe. We do not say which yet. Fit the ten "
        "terms again and look at what is left."))
    model = load_model(out / "1-first-campaign" / "model.dat")
    result, fits = _campaign(load_scenario(scen_path), run_dir, SEEDS[2], model, report=False)
    fit = fits["A"]
    cols = columns(result.rows)
    mask = variant_mask(cols, VARIANTS[0])
    data = pointing_data(cols, mask)
    sun = np.asarray(cols["sun_el_deg"], float)[mask]
    fig = pointing_errors_figure(
        np.degrees(data.az_rad), np.degrees(data.el_rad), fit.residual_xel_arcsec,
        fit.residual_el_arcsec, figdir / "demo5_hidden_residuals.png", sun_el_deg=sun,
        rejected=~np.asarray(fit.used, bool), what="residual",
        title="Residuals of the ten-term fit on an antenna with a hidden fault",
        caption="Look at panel (d): the elevation residuals rise and fall twice as the "
                "antenna goes once around in azimuth. Noise does not do that; a mechanical "
                "fault that repeats with azimuth does.")
    story.figure(ch, fig)
    story.say(ch, (
        f"Sky rms {fit.sky_rms_arcsec:.1f}\" (el {fit.el_rms_arcsec:.1f}\") against "
        f"{reference_rms_arcsec:.1f}\" for the first campaign's fit, and the binned means in "
        "panel (d) wave with azimuth. Something "
        "repeatable is missing from the model. Finding out what is the job of antsim "
        "diagnose: it tests the residuals against the noise the simulation predicts, locates "
        "the excess (which axis, which part of the sky, which time of day) and tries the "
        "physical effects it knows, keeping one only if it is clearly significant."))
    numbers: dict[str, Any] = {"hidden_fit_sky_rms_arcsec": fit.sky_rms_arcsec}
    doc, why = run_diagnose_json(run_dir / "recordings.ecsv", scenario_path,
                                 run_dir / "diagnose")
    story.command(ch, f"antsim diagnose {run_dir / 'recordings.ecsv'} --scenario "
                      f"{shown(scenario_path)} --out {run_dir / 'diagnose'}")
    if doc is None:
        story.say(ch, (
            "This chapter needs the diagnose feature (antsim diagnose), which this "
            "installation does not provide yet. When it does, the demo runs it here on these "
            "recordings and shows what it found, with the residuals before and after. (What "
            f"the command said: {why})"))
        numbers["diagnose"] = None
    else:
        numbers["diagnose"] = doc
        findings = doc.get("findings") or []
        if not findings:
            story.say(ch, "antsim diagnose reported no mismatch: it found nothing the "
                          "ten-term model misses.")
        else:
            best = findings[0]
            story.say(ch, (
                f"antsim diagnose names the effect: {best.get('effect')} (terms "
                f"{', '.join(best.get('terms') or []) or 'none'}). "
                f"{best.get('explanation', '')} Where: {best.get('where', '')}. Sky rms "
                f"{best.get('sky_rms_before_arcsec', math.nan):.1f}\" before, "
                f"{best.get('sky_rms_after_arcsec', math.nan):.1f}\" after."))
            extra = []
            for term in best.get("terms") or []:
                try:
                    get_term(term)
                    extra.append(term)
                except TermError:
                    pass
            if extra:
                after = fit_model(data, [*fit.names, *extra], robust=True, name="diagnosed")
                for f in before_after_figures(fit, after, data, figdir, "demo5_diagnose",
                                              before_name="ten terms",
                                              after_name="ten terms + " + ", ".join(extra)):
                    story.figure(ch, f)
                numbers["after_sky_rms_arcsec"] = after.sky_rms_arcsec
    story.say(ch, (
        f"The answer: the simulation was given {HIDDEN_TERM} = {HIDDEN_ARCSEC:g}\", an "
        "elevation error proportional to sin 2A, which is what an uneven azimuth rail does "
        "(the antenna rocks as its wheels roll over two high and two low places per turn; "
        "BIMA saw 6\" of it). It is in the scenario file this chapter wrote, "
        f"{scen_path}, as a [[truth.effects]] block."))
    return numbers

"""Chapter 5 of the walk-through, a hidden effect: a third campaign (24 hours, the fitted
model in use) on an antenna with an uneven azimuth track, a fault the ten-term model cannot
describe. Its residuals show it against azimuth; ``antsim diagnose`` is asked to name it (in
this process, through its documented JSON output), and the ten terms refitted with what it
names show what the fault cost."""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path
from typing import Any

from antsim.bundled import shown
from antsim.outdir import write_file

from .campaign import YOURS, run_campaign_like_antsim_run
from .story import Story

__all__ = ["DIRECTORY", "HIDDEN_ARCSEC", "HIDDEN_TERM", "SEED", "run_diagnose_json", "tell"]

#: the hidden effect: an uneven azimuth track, dE = HESA2 sin 2A_T (arcsec; TPOINT's azimuth
#: A_T = 180 deg - A_N, controller/pointing/terms.py), i.e. a correction of +60" sin 2A_N
HIDDEN_TERM = "HESA2"
HIDDEN_ARCSEC = -60.0
#: the campaign's seed (a new night's noise)
SEED = 3
#: where it is written, in the demo's directory (its scenario beside it, with .toml)
DIRECTORY = "3-hidden-effect"


def run_diagnose_json(recordings: Path, scenario: Path, out_dir: Path
                      ) -> tuple[dict | None, str]:
    """``antsim diagnose RECORDINGS --scenario SCENARIO --json --out DIR`` in this process.

    Returns (the JSON document the command prints, docs/diagnose.md, "") when the command
    succeeds, else (None, what it said). The demo relies only on that documented contract,
    not on the diagnose package's Python API.
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


def tell(story: Story, base_text: str, scenario_path: Path, out: Path, model_path: Path,
         figdir: Path, reference_rms_arcsec: float) -> dict[str, Any]:
    """Tell chapter 5: the scenario ``base_text`` (read from ``scenario_path``) with the
    hidden effect added, observed with the model ``model_path`` in use; figures go to
    ``figdir``. ``reference_rms_arcsec``: the first campaign's fit's Sky RMS. Returns the
    numbers quoted."""
    import numpy as np

    from antsim.figures.charts import pointing_errors_figure
    from antsim.scenario import load_scenario
    from controller.pointing.modelio import load_model
    from controller.pointing.variants import VARIANTS, columns, pointing_data, variant_mask

    ch = story.chapter("5. A hidden effect: what the model does not know")
    block = (f"\n# demo chapter 5: the hidden effect, an uneven azimuth track\n"
             f"[[truth.effects]]\neffect = \"terms\"\n{HIDDEN_TERM} = {HIDDEN_ARCSEC:g}\n")
    scen_path = out / f"{DIRECTORY}.toml"
    write_file(scen_path, base_text.rstrip("\n") + "\n" + block)
    run_dir = out / DIRECTORY
    story.say(ch, (
        "Real antennas have more faults than any model lists. We now observe a third time "
        f"(seed {SEED}, 24 hours, the fitted model in use) with an antenna that has a "
        "fault the ten-term model cannot describe. We do not say which yet. Fit the ten "
        "terms again and look at what is left."))
    hidden = run_campaign_like_antsim_run(load_scenario(scen_path), run_dir, SEED,
                                          load_model(model_path), report=False)
    fit = hidden.fits["A"]
    cols = columns(hidden.result.rows)
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
    yours = out / YOURS / DIRECTORY
    story.command(ch, f"antsim run {scen_path} --seed {SEED} --model {model_path} "
                      f"--out {yours}")
    story.command(ch, f"antsim diagnose {yours / 'recordings.ecsv'} --scenario "
                      f"{shown(scenario_path)} --out {yours / 'diagnose'}")
    if doc is None:
        story.say(ch, (
            "This chapter needs the diagnose feature (antsim diagnose), which this "
            "installation does not provide yet. When it does, the demo runs it here on these "
            "recordings and shows what it found, with the residuals before and after. (What "
            f"the command said: {why})"))
        numbers["diagnose"] = None
    else:
        numbers["diagnose"] = doc
        numbers.update(_finding(story, ch, doc, fit, data, figdir))
    story.say(ch, (
        f"The answer: the simulation was given {HIDDEN_TERM} = {HIDDEN_ARCSEC:g}\", an "
        "elevation error proportional to sin 2A, which is what an uneven azimuth rail does "
        "(the antenna rocks as its wheels roll over two high and two low places per turn; "
        "BIMA saw 6\" of it). It is in the scenario file this chapter wrote, "
        f"{scen_path}, as a [[truth.effects]] block."))
    return numbers


def _finding(story: Story, ch, doc: dict, fit, data, figdir: Path) -> dict[str, Any]:
    """What diagnose named, in its words, and the ten terms refitted with the terms it
    named: the Sky RMS before and after quoted are those of the figures drawn."""
    from antsim.figures.diagnose import before_after_figures
    from controller.pointing.fitting import fit_model
    from controller.pointing.terms import TermError, get_term

    findings = doc.get("findings") or []
    if not findings:
        story.say(ch, "antsim diagnose reported no mismatch: it found nothing the "
                      "ten-term model misses.")
        return {}
    best = findings[0]
    story.say(ch, (
        f"antsim diagnose names the effect: {best.get('effect')} (terms "
        f"{', '.join(best.get('terms') or []) or 'none'}). "
        f"{best.get('explanation', '')} Where (the size of the effect it fitted, and where "
        f"it is largest): {best.get('where', '')}."))
    extra = []
    for term in best.get("terms") or []:
        with contextlib.suppress(TermError):
            get_term(term)
            extra.append(term)
    if not extra:
        return {}
    after = fit_model(data, [*fit.names, *extra], robust=True, name="diagnosed")
    story.say(ch, (
        f"Fitted with the ten terms, robustly as fit A, {', '.join(extra)} take the sky rms "
        f"from {fit.sky_rms_arcsec:.1f}\" to {after.sky_rms_arcsec:.1f}\" (el "
        f"{fit.el_rms_arcsec:.1f}\" to {after.el_rms_arcsec:.1f}\"): the figures below, "
        "before and after."))
    for f in before_after_figures(fit, after, data, figdir, "demo5_diagnose",
                                  before_name="ten terms",
                                  after_name="ten terms + " + ", ".join(extra)):
        story.figure(ch, f)
    return {"after_sky_rms_arcsec": after.sky_rms_arcsec}

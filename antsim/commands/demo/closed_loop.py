"""Chapter 4 of the walk-through, closing the loop: a second campaign (12 hours, a new
night's noise) with the model fitted in chapter 3 in use; what its scans measure is the
error the model leaves, which should be as small as the fit's residuals promised. Its own
fit comes closer to the truth: the loop can go round again."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from antsim.outdir import write_file

from .campaign import YOURS, Campaign, honest_words, pulls, run_campaign_like_antsim_run
from .story import Story, edit_scenario

__all__ = ["DIRECTORY", "HOURS", "SEED", "tell"]

#: length of the closed-loop campaign (h): long enough for ~130 scans over day and night
HOURS = 12.0
#: its seed (a new night's noise)
SEED = 2
#: where it is written, in the demo's directory (its scenario beside it, with .toml)
DIRECTORY = "2-closed-loop"


def tell(story: Story, base_text: str, scenario_path: Path, out: Path, first: Campaign,
         figdir: Path, first_sky_arcsec: float) -> dict[str, Any]:
    """Tell chapter 4: the scenario ``base_text`` (read from ``scenario_path``) cut to
    :data:`HOURS`, observed with the ``first`` campaign's model.dat in use; its figure goes
    to ``figdir``. ``first_sky_arcsec``: the first campaign's rms without a model. Returns
    the numbers quoted."""
    import numpy as np

    from antsim.figures.charts import histogram_figure
    from antsim.run.inuse import pointing_errors, pointing_in_use
    from antsim.run.report import truth_terms_arcsec
    from antsim.scenario import load_scenario
    from controller.pointing.modelio import load_model

    ch = story.chapter("4. Closing the loop: observing with the fitted model")
    model_path = first.directory / "model.dat"
    text = edit_scenario(base_text, "duration_h = 24.0", f"duration_h = {HOURS:g}",
                         str(scenario_path))
    scen_path = out / f"{DIRECTORY}.toml"
    write_file(scen_path, text)
    story.say(ch, (
        "A model is only worth something if it points the telescope. The controller now adds "
        "the fitted model to every command, and we observe again: a new night's noise "
        f"(seed {SEED}), {HOURS:g} hours. What the five-point scans measure "
        "now is the error that is left with the model in use. If the model is right, that "
        "error should be as small as the residuals of the fit promised."))
    model = load_model(model_path)
    loop = run_campaign_like_antsim_run(load_scenario(scen_path), out / DIRECTORY, SEED,
                                        model, report=False)
    result = loop.result
    xel, el = pointing_errors(result.rows)
    in_use = pointing_in_use(result.rows, model)
    sky, xel_rms, el_rms = ((in_use.sky_rms_arcsec, in_use.xel_rms_arcsec, in_use.el_rms_arcsec)
                            if in_use is not None else (math.nan,) * 3)
    fit = first.fits["A"]
    used = np.asarray(fit.used, bool)
    hpbw_arcsec = first.result.scenario.beam.hpbw_arcmin * 60.0
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
        f"{verdict}. The error went from {first_sky_arcsec / 60:.1f}' rms without a model to "
        f"{sky / 60:.2f}', "
        f"{100 * sky / hpbw_arcsec:.0f}% of the {hpbw_arcsec / 60:g}' beam. The command at "
        "the end of this chapter repeats this campaign, with its report, into a directory of "
        "your own."))
    numbers: dict[str, Any] = {}
    refit = loop.fits.get("A")
    truth = truth_terms_arcsec(first.result.truth)
    if refit is not None and "W6" in truth and "W6" in refit.names \
            and refit.sigma_honest_arcsec is not None:
        j, k = refit.names.index("W6"), fit.names.index("W6")
        before, after = pulls(fit, truth).get("W6"), pulls(refit, truth).get("W6")
        numbers["refit_w6_arcmin"] = refit.values_arcsec[j] / 60
        story.say(ch, (
            "And the loop can go round again: fitting this second campaign, whose scans were "
            f"all close to centred, gives W6 = {refit.values_arcsec[j] / 60:.2f}' +- "
            f"{refit.sigma_honest_arcsec[j] / 60:.2f}' ({honest_words(refit)}; first fit "
            f"{fit.values_arcsec[k] / 60:.2f}', truth {truth['W6'] / 60:.2f}'; pull "
            f"{after:+.1f} against {before:+.1f}) with sky rms {refit.sky_rms_arcsec:.1f}\". "
            "A real observatory repeats the run now and then: the mount changes, and each "
            "pass starts closer to the truth."))
    story.command(ch, f"antsim run {scen_path} --seed {SEED} --model {model_path} "
                      f"--out {out / YOURS / DIRECTORY}")
    numbers.update({"closed_loop_sky_rms_arcsec": sky, "closed_loop_searches": searches,
                    "closed_loop_scans": result.n_scans})
    return numbers

"""Chapter 3 of the walk-through, the fit: the 1990 report's ten terms W1..W10 fitted robustly
to the first campaign (its fit A), and the coefficients against the recoverable truth (the
mount's terms plus what the fit makes of the uncorrected refraction, the heating and the
repeatable irregularities), with pulls in TPOINT's sigma and in the honest one."""

from __future__ import annotations

import math
from typing import Any

from .campaign import Campaign, honest_words, pulls
from .story import Story

__all__ = ["tell"]


def tell(story: Story, first: Campaign) -> dict[str, Any]:
    """Tell chapter 3 on the ``first`` campaign's fits. Returns the numbers quoted."""
    from antsim.run.report import (
        fit_summary_table,
        recoverable_terms_arcsec,
        recoverable_words,
        truth_pull_table,
    )

    ch = story.chapter("3. The fit: ten numbers that describe the mount")
    fit = first.fits["A"]
    truth = recoverable_terms_arcsec(first.result.truth)
    run_dir = first.directory
    story.say(ch, (
        "The 1990 report describes the 45-ft's errors with ten terms, W1..W10: encoder zero "
        "offsets, collimation, axis non-perpendicularity, gravitational sag, refraction, and "
        "the tilt of the azimuth axis. Each term has a signature (constant, sec E, tan E, "
        "cos E, cot E, cos A, sin A, ...) and a least-squares fit finds the mix that best "
        "matches the measured errors. As in the report, the fit is robust: a least-absolute-"
        "deviation fit first, then outliers (gusts of wind, bad scans) are rejected and least "
        f"squares finishes. Fit A used {fit.n_used} of {fit.n_input} scans."))
    story.table(ch, fit_summary_table(first.fits))
    figs = {p.stem: p for p in (run_dir / "figures").glob("*.png")}
    if "fig3_residuals" in figs:
        story.page_figure(
            ch, figs["fig3_residuals"], "What the model leaves (Fig. 3a-d)",
            "The residuals after fit A: from arcminutes down to about half an arcminute. "
            "What is left is wind, thermal bending in sunshine and receiver noise: no "
            "pattern with elevation or azimuth (the black binned means stay near zero).")
    w6 = fit.names.index("W6") if "W6" in fit.names else None
    if truth:
        story.say(ch, recoverable_words(first.result.truth))
        story.table(ch, truth_pull_table(fit, truth, "Coefficients against the recoverable truth"))
        if w6 is not None and "W6" in truth and fit.sigma_honest_arcsec is not None:
            pull = pulls(fit, truth)
            worst = max(pull, key=lambda k: abs(pull[k]))
            verdict = (
                "all within 3 honest sigmas of the truth: the fit recovered what it can."
                if abs(pull[worst]) <= 3 else
                f"{worst} is {abs(pull[worst]):.1f} honest sigmas off. Scans that start "
                "several arcminutes off the source are less accurate: the source sits on the "
                "flank of the beam, and the partly resolved sources (Cas A, Tau A) shrink the "
                "measured offsets by about 9%. That is why observatories iterate (chapter 4).")
            story.say(ch, (
                f"The simulation knows the truth, so we can check: W6 came out "
                f"{fit.values_arcsec[w6] / 60:.2f}' +- "
                f"{fit.sigma_honest_arcsec[w6] / 60:.2f}' ({honest_words(fit)}; TPOINT's "
                f"formal sigma is {fit.sigma_arcsec[w6] / 60:.2f}') against the recoverable "
                f"{truth['W6'] / 60:.2f}'. The pull, (fit - truth) / sigma, should be of "
                "order 1. The honest sigma allows for residuals that are correlated in time "
                "(the Sun heats the structure for hours), which TPOINT's formal sigma "
                "ignores. Of the ten coefficients, " + verdict))
    story.say(ch, (
        f"Sky rms after the fit: {fit.sky_rms_arcsec:.1f}\" (xel {fit.xel_rms_arcsec:.1f}\", "
        f"el {fit.el_rms_arcsec:.1f}\"). The 1990 report found 23\" and 38\" for its fit A. "
        f"The fitted model is written as {run_dir / 'model.dat'}, a TPOINT model file in "
        "TPOINT's term names and signs (W6 is IA, W1 is -IE: TPOINT writes the correction, "
        "the report the error), each line saying which W it was. The command below fits the "
        "same recordings and prints the same coefficients and sigmas."))
    story.command(ch, f"antsim fit {run_dir / 'recordings.ecsv'} --model ghigo10")
    return {"fit_sky_rms_arcsec": fit.sky_rms_arcsec,
            "fit_w6_arcmin": fit.values_arcsec[w6] / 60 if w6 is not None else math.nan}

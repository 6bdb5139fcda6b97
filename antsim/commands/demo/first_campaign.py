"""Chapter 2 of the walk-through, the first campaign: 24 hours of five-point cross scans over
the eight sources of the 1990 run, still without a pointing model, written with its report
as ``antsim run`` writes one (the 1990 report's Figs. 1 and 2 shown from it)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from antsim.bundled import shown

from .campaign import YOURS, Campaign, run_campaign_like_antsim_run
from .story import Story

__all__ = ["DIRECTORY", "SEED", "tell"]

#: the campaign's seed (each campaign of the demo has its own night's noise)
SEED = 1
#: where it is written, in the demo's directory
DIRECTORY = "1-first-campaign"


def tell(story: Story, scenario, scenario_path: Path, out: Path
         ) -> tuple[Campaign, dict[str, Any]]:
    """Tell chapter 2: run the campaign of ``scenario`` (read from ``scenario_path``) into
    ``out/1-first-campaign``. Returns the campaign and the numbers quoted."""
    import numpy as np

    from controller.pointing.model import PointingModel

    ch = story.chapter("2. The first campaign: 24 hours of cross scans")
    story.say(ch, (
        "Now the real work of a pointing run: for 24 hours the controller visits the eight "
        "bright sources of the 1990 run in turn, spreading them over the sky, and on each "
        "makes a five-point cross scan: integrations at -4, -1, 0, +1 and +4 steps of 7' in "
        "azimuth, then in elevation. From the powers it computes where the source really was "
        "(Clark's method). Still no pointing model: only the running correction from the "
        "first search."))
    run_dir = out / DIRECTORY
    first = run_campaign_like_antsim_run(scenario, run_dir, SEED, PointingModel("none"),
                                         report=True)
    result = first.result
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
            story.page_figure(ch, figs[stem], title, caption)
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
        f"this campaign is {run_dir / 'report.html'}; the command below repeats the campaign "
        "into a directory of your own, to the same bytes."))
    story.command(ch, f"antsim run {shown(scenario_path)} --seed {SEED} --model none "
                      f"--out {out / YOURS / DIRECTORY}")
    sky = float(np.sqrt(np.mean(xel ** 2 + el ** 2)))
    return first, {"first_scans": result.n_scans,
                   "first_searches": result.program.searches,
                   "first_xel_low_high_arcmin": (
                       float(low.mean() / 60) if low.size else math.nan,
                       float(high.mean() / 60) if high.size else math.nan),
                   "first_sky_rms_arcsec": sky}

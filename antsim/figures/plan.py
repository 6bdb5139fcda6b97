"""Figures comparing a plan's variants, written by ``antsim plan --out DIR``.

Grouped bars per term and variant come from :func:`antsim.figures.charts.comparison_figure` (the
project's variant-comparison API); the duration answers' sigma-against-time curves are drawn
here with matplotlib's object API on an Agg canvas (no pyplot, no global state, PNG metadata
without dates: same inputs, same bytes).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from antsim.outdir import replacing

from .charts import comparison_figure, plain_log_ticks
from .style import FigureFile, keeping

__all__ = ["draw_duration", "plan_figures"]

DPI = 100


def plan_figures(doc: dict[str, Any], out_dir: str | Path) -> list[FigureFile]:
    """Write the figures of a plan document (``antsim plan --json``) into ``out_dir``;
    returns them with their titles and captions (for ``report.html``)."""
    out = Path(out_dir)
    written: list[FigureFile] = []
    plans = doc["plans"]

    def series(key: str) -> dict[str, dict[str, float]]:
        return {p["name"]: {t: v[key] for t, v in p["terms"].items() if v[key] is not None}
                for p in plans}

    written.append(comparison_figure(
        series("sigma_fisher_arcsec"), out / "sigma_predicted.png",
        title="Predicted sigma of each term (Fisher: design + noise model)",
        ylabel="sigma (arcsec)", log=True,
        caption="The standard error of each term predicted from the schedule the controller "
                "would produce and the noise model of the physics, per variant (log scale)."))
    written.append(comparison_figure(
        series("sigma_mc_arcsec"), out / "sigma_monte_carlo.png",
        title="Monte Carlo sigma of each term (scatter of the fits)",
        ylabel="sigma (arcsec)", log=True,
        caption="The scatter of each term over the fits of simulated campaigns: "
                + ", ".join(f"{p['n_monte_carlo']} ({p['name']})" for p in plans)
                + " (log scale)."))
    ratio = {p["name"]: {t: v["sigma_mc_arcsec"] / v["sigma_fisher_arcsec"]
                         for t, v in p["terms"].items()
                         if v["sigma_mc_arcsec"] and v["sigma_fisher_arcsec"]}
             for p in plans}
    written.append(comparison_figure(
        ratio, out / "sigma_mc_over_predicted.png",
        title="Monte Carlo sigma / predicted sigma (1 = agreement)", ylabel="ratio",
        caption="Sampling error of the Monte Carlo sigma: about 1/sqrt(2N), with N "
                + ", ".join(f"{p['n_monte_carlo']} ({p['name']})" for p in plans) + "."))
    written.append(comparison_figure(
        series("bias_arcsec"), out / "bias.png",
        title="Bias of each term (mean fit minus truth)", ylabel="bias (arcsec)",
        caption="Deterministic errors (mean thermal, source structure) bias the terms the "
                "same way in every campaign; more time does not remove them."))
    for k, a in enumerate(doc.get("answers", {}).get("duration", [])):
        written.append(_duration_figure(a, out / f"duration_{k + 1}.png"))
    for k, a in enumerate(doc.get("answers", {}).get("sources", [])):
        checked = [c for c in a["checked"] if c.get("feasible")]
        if checked:
            terms = a["terms"] or list(checked[0]["sigma_arcsec"])
            values = {", ".join(c["sources"]): {t: c["sigma_arcsec"][t] for t in terms}
                      for c in checked}
            written.append(comparison_figure(
                values, out / f"sources_{k + 1}.png",
                title=f"Predicted sigma for source lists ({a['based_on']})",
                ylabel="sigma (arcsec)", log=True))
    return written


def _duration_figure(answer: dict[str, Any], path: Path) -> FigureFile:
    """Predicted sigma of the question's terms against the number of hours, days or nights."""
    one = answer["target_arcsec"]  # one target for every term, or None: each its own
    goal = f"{one:g}\"" if one is not None else "their targets"
    title = f"How long for {', '.join(answer['terms'])} to reach {goal}"
    with matplotlib.rc_context():
        matplotlib.rcdefaults()
        fig = Figure(figsize=(7.0, 4.2), dpi=DPI)
        FigureCanvasAgg(fig)
        draw_duration(fig.add_axes((0.11, 0.13, 0.85, 0.74)), answer)
        fig.suptitle(title, fontsize=11)
        if not keeping():
            path.parent.mkdir(parents=True, exist_ok=True)
            with replacing(path) as fh:  # whole or not at all; an error names the file
                fig.savefig(fh, format="png", dpi=DPI, metadata={"Software": "antsim"})
    caption = (f"Predicted sigma against the number of {answer['unit']}s of "
               f"'{answer['based_on']}': " + (
                   f"the target is reached after {answer['answer']['count']} "
                   f"{answer['unit']}s." if answer["reached"] else
                   "the target is not reached within the range tried."))
    return FigureFile(path, title, caption, figure=fig if keeping() else None)


def draw_duration(ax, answer: dict[str, Any]) -> None:
    """The curve of a duration answer on ``ax``: each term's predicted sigma (or its sigma
    over its target) against the count, the target, the answer; log axes with plain ticks
    (:func:`antsim.figures.charts.plain_log_ticks`)."""
    curve = answer["curve"]
    x = [c["count"] for c in curve]
    one = answer["target_arcsec"]
    for term in answer["terms"]:
        per = 1.0 if one is not None else answer["targets_arcsec"][term]
        ax.plot(x, [c["sigma_arcsec"][term] / per for c in curve], marker="o", ms=3,
                label=term)
    ax.axhline(one if one is not None else 1.0, color="k", ls="--", lw=1,
               label=f"target {one:g}\"" if one is not None else "each term's target")
    if answer["reached"]:
        ax.axvline(answer["answer"]["count"], color="tab:red", lw=1,
                   label=f"answer: {answer['answer']['count']} {answer['unit']}s")
    if x and max(x) / max(min(x), 1) > 5:
        ax.set_xscale("log")
        plain_log_ticks(ax.xaxis)
    ax.set_yscale("log")
    plain_log_ticks(ax.yaxis)
    ax.set_xlabel(f"{answer['unit']}s of '{answer['based_on']}'")
    ax.set_ylabel("predicted sigma (arcsec)" if one is not None
                  else "predicted sigma / the term's target")
    ax.grid(True, alpha=0.35)
    ax.legend(fontsize=8)

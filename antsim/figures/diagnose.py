"""The figures of ``antsim diagnose --out DIR``: residuals before and after a finding."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from controller.pointing.data import PointingData
from controller.pointing.result import FitResult

from .charts import (
    QUIVER_ARCSEC_PER_DEG,
    check_fit_data,
    error_panels,
    histogram_figure,
    quiver,
    sky_axes,
)
from .style import Canvas, FigureFile, figure_file

__all__ = ["before_after_figures"]


def before_after_figures(before_fit: FitResult, after_fit: FitResult, data: PointingData,
                         out_dir: str | Path, label: str = "diagnose", *,
                         after_data: PointingData | None = None, before_name: str = "before",
                         after_name: str = "after",
                         formats: Sequence[str] = ("png",)) -> list[FigureFile]:
    """Residuals of two fits side by side (for ``antsim diagnose``): the fit of the model as
    it was (``before_fit``) and of the model with the effect added (``after_fit``), both of
    ``data`` (or of ``after_data`` for the after fit, e.g. re-simulated recordings).

    Writes into ``out_dir``: ``{label}_residuals.png`` (xel and el residuals against
    elevation and azimuth, before above, after below), ``{label}_histograms.png`` and
    ``{label}_quiver.png`` (the two sky maps); returns their :class:`FigureFile` s.
    """
    after_data = data if after_data is None else after_data
    check_fit_data(before_fit, data, "before_fit")
    check_fit_data(after_fit, after_data, "after_fit")
    out = Path(out_dir)
    files = []
    pairs = ((before_name, before_fit, data), (after_name, after_fit, after_data))
    title = (f"Residuals before ({before_name}) and after ({after_name}): sky rms "
             f"{before_fit.sky_rms_arcsec:.1f}\" \N{RIGHTWARDS ARROW} "
             f"{after_fit.sky_rms_arcsec:.1f}\"")
    with Canvas(14.0, 7.5) as fig:
        grid = fig.subplots(2, 4)
        fig.subplots_adjust(left=0.05, right=0.99, bottom=0.08, top=0.88, hspace=0.42,
                            wspace=0.28)
        for row, (name, fit, d) in enumerate(pairs):
            error_panels(grid[row], np.degrees(d.az_rad), np.degrees(d.el_rad),
                          fit.residual_xel_arcsec, fit.residual_el_arcsec,
                          rejected=~np.asarray(fit.used, bool), what="residual",
                          letters="abcd" if row == 0 else "efgh")
            grid[row, 0].annotate(f"{name}: {', '.join(fit.names)}", (0.0, 1.18),
                                  xycoords="axes fraction", fontsize=9, fontweight="bold")
        caption = (f"Top: residuals of the fit {before_name} (terms "
                   f"{', '.join(before_fit.names)}); bottom: {after_name} (terms "
                   f"{', '.join(after_fit.names)}). A signature that is gone from the bottom "
                   "row was explained by what was added.")
        files.append(figure_file(fig, out / f"{label}_residuals.png", title, caption,
                                  formats))
    used = {name: (np.asarray(f.residual_xel_arcsec)[f.used],
                   np.asarray(f.residual_el_arcsec)[f.used]) for name, f, _ in pairs}
    files.append(histogram_figure(
        used, out / f"{label}_histograms.png",
        title=f"Residual histograms {before_name} and {after_name} (used points)",
        caption=f"Residuals of the used points {before_name} (filled) and {after_name} "
                "(line); a narrower histogram is a better model.", formats=formats))
    with Canvas(13.0, 6.8) as fig:
        axes = fig.subplots(1, 2)
        fig.subplots_adjust(left=0.01, right=0.99, bottom=0.02, top=0.86, wspace=0.04)
        for ax, (name, fit, d) in zip(axes, pairs, strict=True):
            sky_axes(ax)
            quiver(ax, np.degrees(d.az_rad), np.degrees(d.el_rad), fit.residual_xel_arcsec,
                    fit.residual_el_arcsec, fit.used)
            ax.set_title(f"{name}: sky rms {fit.sky_rms_arcsec:.1f}\"", fontsize=10)
        files.append(figure_file(
            fig, out / f"{label}_quiver.png",
            f"Residuals on the sky, {before_name} and {after_name}",
            f"Residual arrows on the sky (60\" = {60 / QUIVER_ARCSEC_PER_DEG:g}\N{DEGREE SIGN}"
            f" of zenith distance), {before_name} (left) and {after_name} (right).",
            formats))
    return files

"""The figures of ``antsim diagnose --out DIR``: residuals before and after a finding, or
before only when nothing was found.

Scales follow the data: histogram bins and the sky map's arrows from the spread of the
residuals of the model as it was (:func:`antsim.figures.charts.histogram_bin_arcsec`,
:func:`antsim.figures.charts.quiver_scale`), one scale for both rows so that a smaller
"after" is seen smaller; the captions state the bin width and the arrows' scale.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from controller.pointing.data import PointingData

from .charts import (
    check_fit_data,
    error_panels,
    histogram_bin_arcsec,
    histogram_figure,
    quiver,
    quiver_scale,
    sky_axes,
)
from .style import Canvas, FigureFile, figure_file

__all__ = ["Residuals", "before_after_figures", "before_figures"]


@dataclass(frozen=True)
class Residuals:
    """What the figures draw of a fit: its term ``names``, the residuals (arcsec, indicated
    minus true) of every observation, which were ``used``, and the Sky RMS to print (the
    fit's own, e.g. :class:`controller.pointing.result.FitResult`'s, or a diagnosis's).
    A :class:`~controller.pointing.result.FitResult` can be passed wherever this is."""

    names: Sequence[str]
    residual_xel_arcsec: np.ndarray
    residual_el_arcsec: np.ndarray
    used: np.ndarray
    sky_rms_arcsec: float


def _rms_text(value: float) -> str:
    """A Sky RMS as the diagnosis's text prints it (two decimals)."""
    return f"{value:.2f}\""


def before_after_figures(before_fit, after_fit, data: PointingData, out_dir: str | Path,
                         label: str = "diagnose", *, after_data: PointingData | None = None,
                         before_name: str = "before", after_name: str = "after",
                         formats: Sequence[str] = ("png",)) -> list[FigureFile]:
    """Residuals of two fits side by side (for ``antsim diagnose``): the fit of the model as
    it was (``before_fit``) and of the model with the effect added (``after_fit``), both of
    ``data`` (or of ``after_data`` for the after fit, e.g. re-simulated recordings). The fits
    are :class:`Residuals` or :class:`~controller.pointing.result.FitResult` s.

    Writes into ``out_dir``: ``{label}_residuals.png`` (xel and el residuals against
    elevation and azimuth, before above, after below), ``{label}_histograms.png`` and
    ``{label}_quiver.png`` (the two sky maps); returns their :class:`FigureFile` s.
    """
    after_data = data if after_data is None else after_data
    check_fit_data(before_fit, data, "before_fit")
    check_fit_data(after_fit, after_data, "after_fit")
    title = (f"Residuals before ({before_name}) and after ({after_name}): sky rms "
             f"{_rms_text(before_fit.sky_rms_arcsec)} \N{RIGHTWARDS ARROW} "
             f"{_rms_text(after_fit.sky_rms_arcsec)}")
    caption = (f"Top: residuals of the fit {before_name} (terms "
               f"{', '.join(before_fit.names)}); bottom: {after_name} (terms "
               f"{', '.join(after_fit.names)}). A signature that is gone from the bottom "
               "row was explained by what was added.")
    return _figures(((before_name, before_fit, data), (after_name, after_fit, after_data)),
                    Path(out_dir), label, title, caption, formats)


def before_figures(before_fit, data: PointingData, out_dir: str | Path,
                   label: str = "diagnose", *, before_name: str = "baseline",
                   nothing_found: str = "",
                   formats: Sequence[str] = ("png",)) -> list[FigureFile]:
    """The residuals of the model as it was alone, when nothing was found: the same three
    files as :func:`before_after_figures` with one row, one series and one map; every
    caption begins with ``nothing_found`` (what was tested and why nothing was kept)."""
    check_fit_data(before_fit, data, "before_fit")
    title = (f"Residuals of the {before_name} (nothing found): sky rms "
             f"{_rms_text(before_fit.sky_rms_arcsec)}")
    caption = (f"Residuals of the fit {before_name} (terms {', '.join(before_fit.names)}). "
               "Noise without a pattern is what a model that misses nothing leaves.")
    return _figures(((before_name, before_fit, data),), Path(out_dir), label, title, caption,
                    formats, lead=nothing_found)


def _figures(rows, out: Path, label: str, title: str, caption: str,
             formats: Sequence[str], lead: str = "") -> list[FigureFile]:
    """The residual panels, histograms and sky maps of one or two (name, fit, data)."""
    lead = f"{lead.rstrip('.')}. " if lead else ""
    files = []
    first = rows[0][1]
    used0 = np.asarray(first.used, bool)
    first_used = (np.asarray(first.residual_xel_arcsec)[used0],
                  np.asarray(first.residual_el_arcsec)[used0])
    with Canvas(14.0, 3.9 + 3.6 * (len(rows) - 1)) as fig:
        grid = np.atleast_2d(fig.subplots(len(rows), 4))
        top = 0.88 if len(rows) == 2 else 0.78
        fig.subplots_adjust(left=0.05, right=0.99, bottom=0.08 * (3 - len(rows)) ** 0.5,
                            top=top, hspace=0.42, wspace=0.28)
        for row, (name, fit, d) in enumerate(rows):
            error_panels(grid[row], np.degrees(d.az_rad), np.degrees(d.el_rad),
                         fit.residual_xel_arcsec, fit.residual_el_arcsec,
                         rejected=~np.asarray(fit.used, bool), what="residual",
                         letters="abcd" if row == 0 else "efgh")
            grid[row, 0].annotate(f"{name}: {', '.join(fit.names)}", (0.0, 1.18),
                                  xycoords="axes fraction", fontsize=9, fontweight="bold")
        files.append(figure_file(fig, out / f"{label}_residuals.png", title, lead + caption,
                                 formats))
    used = {name: (np.asarray(f.residual_xel_arcsec)[np.asarray(f.used, bool)],
                   np.asarray(f.residual_el_arcsec)[np.asarray(f.used, bool)])
            for name, f, _ in rows}
    names = [name for name, _, _ in rows]
    hist_caption = (f"Residuals of the used points {names[0]} (filled) and {names[1]} "
                    "(line); a narrower histogram is a better model" if len(rows) == 2 else
                    f"Residuals of the used points {names[0]}, with the normal curve of "
                    "their rms")
    files.append(histogram_figure(
        used, out / f"{label}_histograms.png",
        title=f"Residual histograms {' and '.join(names)} (used points)",
        caption=lead + hist_caption, bin_arcsec=histogram_bin_arcsec(
            *first_used, drawn=[v for pair in used.values() for v in pair]),
        formats=formats))
    scale = quiver_scale(*first_used)  # one scale for both maps: a smaller after looks so
    with Canvas(6.8 * len(rows) - 0.6, 6.8) as fig:
        axes = np.atleast_1d(fig.subplots(1, len(rows)))
        fig.subplots_adjust(left=0.01, right=0.99, bottom=0.02, top=0.86, wspace=0.04)
        for ax, (name, fit, d) in zip(axes, rows, strict=True):
            sky_axes(ax)
            quiver(ax, np.degrees(d.az_rad), np.degrees(d.el_rad), fit.residual_xel_arcsec,
                   fit.residual_el_arcsec, fit.used, scale=scale)
            ax.set_title(f"{name}: sky rms {_rms_text(fit.sky_rms_arcsec)}", fontsize=10)
        where = f", {names[0]} (left) and {names[1]} (right)" if len(rows) == 2 else ""
        files.append(figure_file(
            fig, out / f"{label}_quiver.png", f"Residuals on the sky, {' and '.join(names)}",
            f"{lead}Residual arrows on the sky ({scale.words()}){where}.", formats))
    return files

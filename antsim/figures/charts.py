"""Figure types more than one page draws: errors against elevation and azimuth, residual
arrows on the sky, histograms, grouped bars.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

from controller.pointing.data import PointingData
from controller.pointing.result import FitResult

from .style import (
    REJECT_COLOR,
    SERIES_COLORS,
    Canvas,
    FigureFile,
    binned_mean,
    day_night_groups,
    figure_file,
    rms,
)

__all__ = ["QuiverScale", "check_fit_data", "comparison_figure", "error_panels",
           "histogram_bin_arcsec", "histogram_edges", "histogram_figure", "nice_step",
           "plain_log_ticks", "pointing_errors_figure", "quiver", "quiver_scale",
           "residual_quiver_figure", "sky_axes", "spread_arcsec"]


# ---------------------------------------------------------------------------------------------
# scales from the data's spread
# ---------------------------------------------------------------------------------------------
def spread_arcsec(*values) -> float:
    """A robust spread (arcsec) of the finite values given: 1.4826 times the median absolute
    value (the standard deviation of zero-mean Gaussian residuals, unmoved by a few outliers),
    or their rms when that is zero; NaN when there is nothing finite."""
    v = np.concatenate([np.ravel(np.asarray(x, float)) for x in values]) if values \
        else np.empty(0)
    v = v[np.isfinite(v)]
    if not v.size:
        return math.nan
    mad = 1.4826 * float(np.median(np.abs(v)))
    return mad if mad > 0 else rms(v)


def plain_log_ticks(axis) -> None:
    """Ticks of a log-scaled matplotlib ``axis`` at 1, 2 and 5 times the powers of ten,
    labelled as plain numbers ("20", "0.5"; not matplotlib's "2x10^1"), no minor labels."""
    axis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
    axis.set_major_formatter(FuncFormatter(lambda v, _pos: f"{v:g}"))
    axis.set_minor_formatter(NullFormatter())


def nice_step(x: float) -> float:
    """The largest of 1, 2, 5 times a power of ten that is at most ``x`` (> 0)."""
    if not (math.isfinite(x) and x > 0):
        raise ValueError(f"nice_step needs a positive finite number, got {x!r}")
    power = 10.0 ** math.floor(math.log10(x))
    for m in (5.0, 2.0, 1.0):
        if m * power <= x * (1 + 1e-9):
            return m * power
    return power  # pragma: no cover (m = 1 always fits)


#: bins per standard deviation of the residuals (about 15 bins across +-3 sigma)
BINS_PER_SIGMA = 2.5
#: at most this many bins over the drawn range (long tails widen the bins instead)
MAX_BINS = 80


def histogram_bin_arcsec(*values, drawn=None) -> float:
    """A bin width (arcsec, a 1-2-5 number) for histograms of ``values``: about
    1 / :data:`BINS_PER_SIGMA` of their spread (:func:`spread_arcsec`), widened so that
    the range of everything ``drawn`` (default: ``values``) takes at most :data:`MAX_BINS`
    bins."""
    s = spread_arcsec(*values)
    if not (math.isfinite(s) and s > 0):
        return 1.0
    v = np.concatenate([np.ravel(np.asarray(x, float)) for x in (drawn or values)])
    top = float(np.max(np.abs(v[np.isfinite(v)])))
    step = nice_step(s / BINS_PER_SIGMA)
    while 2.0 * top / step > MAX_BINS:
        step = nice_step(step * 2.5)  # the next 1-2-5 step up
    return step


@dataclass(frozen=True)
class QuiverScale:
    """How residual arrows are drawn on a :func:`sky_axes` map: ``arcsec_per_deg`` of
    residual per degree of zenith distance, and the key arrow's length ``key_arcsec``."""

    arcsec_per_deg: float
    key_arcsec: float

    @property
    def key_deg(self) -> float:
        return self.key_arcsec / self.arcsec_per_deg

    def words(self) -> str:
        """'20" of residual is drawn as 6 deg on the map' (for captions)."""
        return (f"{self.key_arcsec:g}\" of residual is drawn as {self.key_deg:g}"
                f"\N{DEGREE SIGN} on the map")


#: degrees of zenith distance of the key arrow (about the spacing of neighbouring scans)
QUIVER_KEY_DEG = 6.0


def quiver_scale(xel, el) -> QuiverScale:
    """The arrows' scale for residuals ``xel``, ``el`` (arcsec): the key a 1-2-5 number near
    twice the residuals' spread per axis (a typical arrow is about half the key), drawn
    :data:`QUIVER_KEY_DEG` long."""
    s = spread_arcsec(xel, el)
    key = nice_step(2.0 * s) if math.isfinite(s) and s > 0 else 1.0
    return QuiverScale(key / QUIVER_KEY_DEG, key)


# ---------------------------------------------------------------------------------------------
# errors or residuals against elevation and azimuth (Figs. 2 and 3 of a run)
# ---------------------------------------------------------------------------------------------
def error_panels(axes, az_deg, el_deg, xel, el, *, sun_el_deg=None, rejected=None,
                  what: str = "error", letters: str = "abcd", binned: bool = True,
                  rejected_label: str = "rejected by the fit") -> None:
    """Four panels: xel and el (arcsec) against elevation and against azimuth (deg)."""
    az_deg = np.asarray(az_deg, float)
    el_deg = np.asarray(el_deg, float)
    rejected = (np.zeros(az_deg.shape, bool) if rejected is None
                else np.asarray(rejected, bool))
    groups = ([("observations", np.ones(az_deg.shape, bool), SERIES_COLORS[0])]
              if sun_el_deg is None else day_night_groups(sun_el_deg))
    panels = [
        (axes[0], el_deg, xel, "elevation (deg)", f"cross-elevation {what} (arcsec)",
         (0.0, 90.0)),
        (axes[1], el_deg, el, "elevation (deg)", f"elevation {what} (arcsec)", (0.0, 90.0)),
        (axes[2], az_deg, xel, "azimuth (deg, N = 0, E = 90)",
         f"cross-elevation {what} (arcsec)", (0.0, 360.0)),
        (axes[3], az_deg, el, "azimuth (deg, N = 0, E = 90)", f"elevation {what} (arcsec)",
         (0.0, 360.0)),
    ]
    for k, (ax, x, y, xlabel, ylabel, xlim) in enumerate(panels):
        y = np.asarray(y, float)
        for label, sel, color in groups:
            keep = sel & ~rejected
            if keep.any():
                ax.scatter(x[keep], y[keep], s=9, color=color, alpha=0.8, lw=0,
                           label=f"{label} ({int(keep.sum())})")
        if rejected.any():
            ax.scatter(x[rejected], y[rejected], s=28, marker="x", color=REJECT_COLOR,
                       lw=1.2, label=f"{rejected_label} ({int(rejected.sum())})")
        if binned and (~rejected).sum() >= 6:
            edges = np.linspace(xlim[0], xlim[1], 10 if xlim[1] <= 90 else 13)
            cx, my, ey = binned_mean(x[~rejected], y[~rejected], edges)
            if cx.size:
                ax.errorbar(cx, my, yerr=ey, color="k", lw=1.2, capsize=2, marker="s", ms=3,
                            label="binned mean \N{PLUS-MINUS SIGN} s.e.")
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_xlim(*xlim)
        if xlim[1] > 90:
            ax.set_xticks(np.arange(0, 361, 45))
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        used_y = y[~rejected]
        ax.set_title(f"({letters[k]}) rms {rms(used_y):.1f}\" over {used_y.size} points",
                     fontsize=9)
    axes[0].legend(loc="lower left", fontsize=7, framealpha=0.8)


def pointing_errors_figure(az_deg, el_deg, xel_arcsec, el_arcsec, path: str | Path, *,
                           sun_el_deg=None, rejected=None, what: str = "error",
                           rejected_label: str = "rejected by the fit",
                           title: str = "", caption: str = "",
                           formats: Sequence[str] = ("png",)) -> FigureFile:
    """Figs. 2a-d / 3a-d: cross-elevation and elevation errors (arcsec, indicated minus
    true) against elevation and azimuth (deg); points coloured by day/twilight/night when
    ``sun_el_deg`` is given; ``rejected`` points marked with red crosses; binned means."""
    title = title or "Total pointing errors against elevation and azimuth"
    with Canvas(10.0, 8.0) as fig:
        grid = fig.subplots(2, 2)
        fig.subplots_adjust(left=0.08, right=0.98, bottom=0.07, top=0.91, hspace=0.32,
                            wspace=0.22)
        error_panels(grid.ravel(), az_deg, el_deg, xel_arcsec, el_arcsec,
                      sun_el_deg=sun_el_deg, rejected=rejected, what=what,
                      rejected_label=rejected_label)
        return figure_file(fig, Path(path), title, caption or title, formats)


# ---------------------------------------------------------------------------------------------
# residuals on the sky
# ---------------------------------------------------------------------------------------------
def sky_axes(ax, el_limit_deg: float | None = 10.0) -> None:
    """Cartesian sky map axes: x = z sin A, y = z cos A (deg), North up, East right."""
    theta = np.linspace(0.0, 2.0 * math.pi, 181)
    for zd in (30.0, 60.0, 90.0):
        ax.plot(zd * np.sin(theta), zd * np.cos(theta), color="0.75", lw=0.7)
        ax.text(zd * math.sin(math.radians(135)), zd * math.cos(math.radians(135)),
                f"{90 - zd:g}\N{DEGREE SIGN}", fontsize=7, color="0.4")
    if el_limit_deg is not None:
        zl = 90.0 - el_limit_deg
        ax.plot(zl * np.sin(theta), zl * np.cos(theta), "k--", lw=0.6)
    for label, a in (("N", 0.0), ("E", 90.0), ("S", 180.0), ("W", 270.0)):
        ax.text(97.0 * math.sin(math.radians(a)), 97.0 * math.cos(math.radians(a)), label,
                ha="center", va="center", fontsize=9, fontweight="bold")
    ax.set_xlim(-102.0, 102.0)
    ax.set_ylim(-102.0, 102.0)
    ax.set_aspect("equal")
    ax.grid(False)
    ax.set_xticks([])
    ax.set_yticks([])


def quiver(ax, az_deg, el_deg, xel, el, used, *, key: bool = True,
           scale: QuiverScale | None = None) -> QuiverScale:
    """Arrows of (xel, el) residuals at each position on a :func:`sky_axes` map, at
    ``scale`` (default: :func:`quiver_scale` of the used residuals); returns the scale."""
    a = np.radians(np.asarray(az_deg, float))
    zd = 90.0 - np.asarray(el_deg, float)
    x, y = zd * np.sin(a), zd * np.cos(a)
    xel = np.asarray(xel, float)
    el = np.asarray(el, float)
    # increasing azimuth is (cos A, -sin A) on the map; increasing elevation (-sin A, -cos A)
    u = xel * np.cos(a) - el * np.sin(a)
    v = -xel * np.sin(a) - el * np.cos(a)
    used = np.asarray(used, bool)
    if scale is None:
        scale = quiver_scale(xel[used], el[used])
    for sel, color in ((used, "#1f4e9c"), (~used, REJECT_COLOR)):
        if sel.any():
            q = ax.quiver(x[sel], y[sel], u[sel], v[sel], color=color, angles="xy",
                          scale_units="xy", scale=scale.arcsec_per_deg, width=0.003,
                          headwidth=3.5)
            if key and color != REJECT_COLOR:
                ax.quiverkey(q, 0.86, 0.04, scale.key_arcsec, f"{scale.key_arcsec:g}\"",
                             labelpos="E", coordinates="axes", fontproperties={"size": 8})
    ax.scatter(x, y, s=3, color="k", zorder=3)
    return scale


def check_fit_data(fit: FitResult, data: PointingData, name: str) -> None:
    n = len(np.asarray(fit.residual_xel_arcsec))
    if n != len(data):
        raise ValueError(f"{name} has residuals for {n} observations but the pointing data "
                         f"hold {len(data)}: pass the PointingData the fit was made from")


def residual_quiver_figure(data: PointingData, fit: FitResult, path: str | Path, *,
                           title: str = "", formats: Sequence[str] = ("png",)) -> FigureFile:
    """The residuals of ``fit`` as arrows on a map of the sky (North up, East right, zenith
    at the centre; the arrows' scale from the residuals' spread, :func:`quiver_scale`);
    rejected points in red."""
    check_fit_data(fit, data, "fit")
    title = title or "Residuals after the fit on the sky"
    with Canvas(7.5, 7.5) as fig:
        ax = fig.add_axes((0.03, 0.03, 0.94, 0.88))
        sky_axes(ax)
        scale = quiver(ax, np.degrees(data.az_rad), np.degrees(data.el_rad),
                       fit.residual_xel_arcsec, fit.residual_el_arcsec, fit.used)
        ax.text(-100.0, -100.0, f"{fit.n_used} used (blue), {fit.n_rejected} rejected (red)\n"
                f"sky rms {fit.sky_rms_arcsec:.1f}\"", fontsize=8, va="bottom")
        caption = ("Each arrow is one scan's residual after the fit (indicated minus true: "
                   "cross-elevation along increasing azimuth, elevation towards the zenith), "
                   f"drawn at the position observed; {scale.words()}. Random noise "
                   "points every way; arrows that agree with their neighbours are a term the "
                   "model lacks.")
        return figure_file(fig, Path(path), title, caption, formats)


# ---------------------------------------------------------------------------------------------
# histograms and grouped bars
# ---------------------------------------------------------------------------------------------
def histogram_edges(values, bin_arcsec: float) -> np.ndarray:
    """Bin edges (arcsec) of width ``bin_arcsec`` centred on its multiples, symmetric about
    zero and just covering every finite value."""
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    top = float(np.max(np.abs(v))) if v.size else bin_arcsec
    n = max(1, math.ceil(top / bin_arcsec - 0.5 + 1e-9))  # bins beside the one at zero
    return bin_arcsec * (np.arange(-n, n + 2) - 0.5)


def histogram_figure(series: Mapping[str, tuple[Any, Any]], path: str | Path, *,
                     title: str = "", caption: str = "", bin_arcsec: float | None = None,
                     gaussian: bool = True,
                     formats: Sequence[str] = ("png",)) -> FigureFile:
    """Histograms of cross-elevation and elevation values (arcsec) for each named series
    ``{label: (xel, el)}``, with the rms in the legend and, if ``gaussian``, the normal
    curve of the first series' rms. Bins of ``bin_arcsec`` (default: from the first
    series' spread, :func:`histogram_bin_arcsec`), the axis just covering every value; the
    caption ends with the bin width."""
    if not series:
        raise ValueError("histogram_figure needs at least one series")
    title = title or "Residual histograms"
    all_values = np.concatenate([np.concatenate([np.ravel(x), np.ravel(y)])
                                 for x, y in series.values()]).astype(float)
    if bin_arcsec is None:
        bin_arcsec = histogram_bin_arcsec(*next(iter(series.values())), drawn=[all_values])
    edges = histogram_edges(all_values, bin_arcsec)
    caption = (caption or title).rstrip(".") + f". Bins of {bin_arcsec:g}\"."
    with Canvas(10.0, 4.4) as fig:
        axes = fig.subplots(1, 2)
        fig.subplots_adjust(left=0.07, right=0.98, bottom=0.12, top=0.84, wspace=0.2)
        for a, (ax, axis_name) in enumerate(zip(axes, ("cross-elevation", "elevation"),
                                                strict=True)):
            for k, (label, values) in enumerate(series.items()):
                v = np.asarray(values[a], float)
                v = v[np.isfinite(v)]
                color = SERIES_COLORS[k % len(SERIES_COLORS)]
                ax.hist(v, bins=edges, histtype="stepfilled" if k == 0 else "step",
                        alpha=0.45 if k == 0 else 1.0, color=color, lw=1.5,
                        label=f"{label}: N {v.size}, rms {rms(v):.1f}\"")
                s = rms(v)
                if gaussian and k == 0 and v.size > 1 and s > 0:
                    x = np.linspace(edges[0], edges[-1], 300)
                    ax.plot(x, v.size * bin_arcsec * np.exp(-0.5 * (x / s) ** 2)
                            / (s * math.sqrt(2 * math.pi)), "k-", lw=1,
                            label=f"normal, \N{GREEK SMALL LETTER SIGMA} = {s:.1f}\"")
            ax.set_xlim(edges[0], edges[-1])
            ax.set_xlabel(f"{axis_name} (arcsec)")
            ax.set_ylabel(f"number per {bin_arcsec:g}\" bin")
            ax.set_title(f"({'ab'[a]}) {axis_name}", fontsize=9)
            ax.legend(loc="upper right", fontsize=7)
        return figure_file(fig, Path(path), title, caption, formats)


def comparison_figure(values: Mapping[str, Mapping[str, float]], path: str | Path, *,
                      title: str, ylabel: str, xlabel: str = "", caption: str = "",
                      log: bool = False,
                      formats: Sequence[str] = ("png",)) -> FigureFile:
    """A grouped bar chart of ``{series: {category: value}}``: one group per category (in
    first-seen order), one bar per series, e.g. the sigma of each term (category) for each
    plan or fit variant (series). Missing or non-finite values leave a gap."""
    if not values:
        raise ValueError("comparison_figure needs at least one series")
    categories: list[str] = list(dict.fromkeys(c for s in values.values() for c in s))
    if not categories:
        raise ValueError("comparison_figure: the series have no categories")
    n = len(values)
    width = 0.8 / n
    with Canvas(10.0, 4.8) as fig:
        ax = fig.add_axes((0.08, 0.12, 0.90, 0.70))
        x0 = np.arange(len(categories), dtype=float)
        for k, (label, series) in enumerate(values.items()):
            y = np.array([float(series.get(c, math.nan)) for c in categories])
            ok = np.isfinite(y) & ((y > 0) if log else True)
            ax.bar(x0[ok] - 0.4 + width * (k + 0.5), y[ok], width=width * 0.92,
                   color=SERIES_COLORS[k % len(SERIES_COLORS)], label=label)
        if log:
            ax.set_yscale("log")
            plain_log_ticks(ax.yaxis)
        ax.set_xticks(x0)
        ax.set_xticklabels(categories)
        ax.set_xlim(-0.6, len(categories) - 0.4)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.01), ncol=min(n, 8), fontsize=7,
                  frameon=False)
        return figure_file(fig, Path(path), title, caption or title, formats)

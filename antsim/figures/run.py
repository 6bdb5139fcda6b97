"""Figures of a pointing run, in the style of the 1990 report (Ghigo), and the diagnostics
TPOINT and katpoint users expect.

Per run (:func:`run_figures`): Fig. 1 the sky distribution of the observations (polar
alt-az: azimuth as the angle, North up and East to the right, zenith distance as the
radius); Fig. 2a-d the total pointing errors against elevation and azimuth; Fig. 3a-d the
residuals after fit A (rejected points marked); Fig. 4 the amplitude of the strong sources
against elevation with the report's gain curve (section V); a quiver map of the residuals
on the sky; residual histograms; residuals against time with the daylight marked; the
coefficients of fits A-F against the truth; the coefficient sigmas and the rms of every fit.

For other commands: :func:`before_after_figures` (``antsim diagnose``: residuals of two fits
of the same observations), :func:`comparison_figure` (``antsim plan``: a grouped bar chart
of any ``{series: {category: value}}``), :func:`histogram_figure` and
:func:`scan_trace_figure` (the teaching walk-through).

Conventions: errors and residuals are "indicated minus true" (the sign of the recordings'
corrections and of :class:`controller.pointing.fitting.PointingData`), cross-elevation = dA cos E,
arcsec unless a label says otherwise; azimuth North = 0, East = 90 deg.

Determinism: matplotlib's object API on the non-interactive Agg canvas (pyplot is never
imported: no global figure state, no GUI backend), matplotlib's default style reset for every
figure, fixed size and resolution (:data:`FIG_DPI`), no timestamps: PNG metadata carry only
``Software: antsim``, SVG files a fixed ``svg.hashsalt`` and no date. The same inputs give
byte-identical files.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from controller.pointing.fitting import FitResult, PointingData
from controller.pointing.variants import VARIANTS, columns, pointing_data, variant_mask
from controller.program.scheduler import DAY_SUN_MIN_DEG, NIGHT_SUN_MAX_DEG

__all__ = [
    "FIG_DPI",
    "REPORT_GAIN_CURVE",
    "REPORT_TABLE2_ARCSEC",
    "STRONG_SOURCES",
    "FigureFile",
    "ScanTrace",
    "amplitude_figure",
    "before_after_figures",
    "coefficients_figure",
    "comparison_figure",
    "histogram_figure",
    "pointing_errors_figure",
    "residual_quiver_figure",
    "residual_time_figure",
    "run_figures",
    "scan_trace_figure",
    "sky_distribution_figure",
]

#: resolution of every PNG (dots per inch); figure sizes are given in inches
FIG_DPI = 100
#: the strong sources of the report's gain-curve figure (Fig. 4)
STRONG_SOURCES = ("Cassiopeia A", "Cygnus A")
#: relative gain against elevation, Ghigo (1990) section V: flat above 30 deg, 95% at 20 deg,
#: 90% at 10 deg; (elevation deg, relative gain) pairs, linear in between
REPORT_GAIN_CURVE: tuple[tuple[float, float], ...] = (
    (10.0, 0.90), (20.0, 0.95), (30.0, 1.0), (90.0, 1.0))
#: Ghigo (1990) Table 2: rms of (xel, el) residuals per fit, arcsec
REPORT_TABLE2_ARCSEC: dict[str, tuple[float, float]] = {
    "A": (23.0, 38.0), "B": (23.0, 35.0), "C": (28.0, 43.0),
    "D": (24.0, 40.0), "E": (18.0, 26.0), "F": (31.0, 41.0),
}

_DAY_COLOR = "#d95f02"
_TWILIGHT_COLOR = "#8c8c8c"
_NIGHT_COLOR = "#1f4e9c"
_REJECT_COLOR = "#d62728"
_SERIES_COLORS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b",
                  "#e377c2", "#7f7f7f", "#bcbd22", "#17becf")
#: pinned settings on top of matplotlib's defaults (the user's matplotlibrc is ignored)
_STYLE = {
    "figure.dpi": FIG_DPI,
    "savefig.dpi": FIG_DPI,
    "font.size": 9.0,
    "axes.titlesize": 10.0,
    "axes.grid": True,
    "grid.alpha": 0.35,
    "legend.fontsize": 8.0,
    "svg.hashsalt": "antsim",
    "svg.fonttype": "path",
    "path.simplify": True,
    # a fixed title height: matplotlib otherwise measures every tick label of the axes to
    # lift the title above any on top (none of ours has labels there: same pixels, ~4% less
    # drawing time)
    "axes.titley": 1.0,
}
_PNG_METADATA = {"Software": "antsim"}
#: zlib level of the PNGs: 3 encodes in 2/3 of the time of PIL's default 6 for files <1% larger
_PNG_COMPRESS_LEVEL = 3
_SVG_METADATA = {"Creator": "antsim", "Date": None}


@dataclass(frozen=True)
class FigureFile:
    """A figure written to disk: ``path`` (the PNG), a ``title`` saying what is plotted and a
    ``caption`` for a report; ``extra`` lists the same figure in other formats (e.g. SVG)."""

    path: Path
    title: str
    caption: str
    extra: tuple[Path, ...] = ()


@dataclass(frozen=True)
class ScanTrace:
    """The powers of one cross scan for plotting: sky offsets (arcmin; azimuth scan in
    cross-elevation) and total powers (K) of each axis, and a label for the legend."""

    label: str
    az_offsets_arcmin: np.ndarray
    az_power_k: np.ndarray
    el_offsets_arcmin: np.ndarray
    el_power_k: np.ndarray


# ---------------------------------------------------------------------------------------------
# drawing machinery
# ---------------------------------------------------------------------------------------------
class _Canvas:
    """``with _Canvas(w, h) as fig:`` a Figure on an Agg canvas inside matplotlib's default
    style plus :data:`_STYLE` (restored afterwards)."""

    def __init__(self, width_in: float, height_in: float):
        self.size = (width_in, height_in)

    def __enter__(self):
        import matplotlib
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        self._rc = matplotlib.rc_context()
        self._rc.__enter__()
        matplotlib.rcdefaults()
        matplotlib.rcParams.update(_STYLE)
        self.fig = Figure(figsize=self.size, dpi=FIG_DPI)
        FigureCanvasAgg(self.fig)
        return self.fig

    def __exit__(self, *exc) -> None:
        self._rc.__exit__(*exc)


def _save(fig, path: Path, formats: Sequence[str]) -> tuple[Path, tuple[Path, ...]]:
    """Write ``fig`` as ``path`` (PNG) and in any further ``formats`` beside it."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    unknown = set(formats) - {"png", "svg"}
    if unknown:
        raise ValueError(f"unknown figure format(s) {sorted(unknown)}: use 'png' and/or 'svg'")
    png = path.with_suffix(".png")
    fig.savefig(png, format="png", dpi=FIG_DPI, metadata=_PNG_METADATA,
                pil_kwargs={"compress_level": _PNG_COMPRESS_LEVEL})
    extra = []
    if "svg" in formats:
        svg = path.with_suffix(".svg")
        fig.savefig(svg, format="svg", metadata=_SVG_METADATA)
        extra.append(svg)
    return png, tuple(extra)


def _figure_file(fig, path: Path, title: str, caption: str,
                 formats: Sequence[str]) -> FigureFile:
    fig.suptitle(title, fontsize=11, fontweight="bold")
    png, extra = _save(fig, path, formats)
    return FigureFile(png, title, caption, extra)


def _rms(x: np.ndarray) -> float:
    x = np.asarray(x, dtype=float)
    return float(np.sqrt(np.mean(x * x))) if x.size else math.nan


def _binned_mean(x: np.ndarray, y: np.ndarray, edges: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Bin centres, means and standard errors of ``y`` in bins of ``x`` (bins with fewer than
    three points left out)."""
    idx = np.digitize(x, edges) - 1
    centres, means, errors = [], [], []
    for k in range(len(edges) - 1):
        sel = y[idx == k]
        if sel.size >= 3:
            centres.append(0.5 * (edges[k] + edges[k + 1]))
            means.append(sel.mean())
            errors.append(sel.std(ddof=1) / math.sqrt(sel.size))
    return np.array(centres), np.array(means), np.array(errors)


def _day_night_groups(sun_el_deg: np.ndarray) -> list[tuple[str, np.ndarray, str]]:
    """(label, mask, colour) for day, twilight and night by the Sun's elevation (the
    thresholds of fits D and E)."""
    sun = np.asarray(sun_el_deg, dtype=float)
    day = sun > DAY_SUN_MIN_DEG
    night = sun < NIGHT_SUN_MAX_DEG
    return [
        (f"day (Sun > {DAY_SUN_MIN_DEG:g}\N{DEGREE SIGN})", day, _DAY_COLOR),
        ("twilight", ~day & ~night, _TWILIGHT_COLOR),
        (f"night (Sun < {NIGHT_SUN_MAX_DEG:g}\N{DEGREE SIGN})", night, _NIGHT_COLOR),
    ]


# ---------------------------------------------------------------------------------------------
# the run's observations
# ---------------------------------------------------------------------------------------------
def _as_columns(rows, names: Sequence[str]) -> dict[str, np.ndarray]:
    """Columns of recordings given as a list of row dicts or an astropy Table."""
    if isinstance(rows, Sequence) and (not rows or isinstance(rows[0], Mapping)):
        return {n: np.array([r[n] for r in rows]) for n in names}
    return {n: np.asarray(rows[n]) for n in names}


@dataclass(frozen=True)
class _Observations:
    """The rows of one polarization as arrays; totals are measured + model + applied."""

    az_deg: np.ndarray
    el_deg: np.ndarray
    xel_arcsec: np.ndarray
    el_arcsec: np.ndarray
    t_s: np.ndarray
    sun_el_deg: np.ndarray
    source: np.ndarray
    amp_k: np.ndarray
    good: np.ndarray

    @classmethod
    def from_rows(cls, rows, polarization: str = "AVG") -> _Observations:
        names = ("polarization", "az_deg", "el_deg", "xel_arcmin", "el_arcmin",
                 "model_xel_arcmin", "model_el_arcmin", "applied_xel_arcmin",
                 "applied_el_arcmin", "t_s", "sun_el_deg", "source", "xel_amp_k", "el_amp_k",
                 "good")
        c = _as_columns(rows, names)
        sel = c["polarization"] == polarization
        f = {k: c[k][sel].astype(float) for k in names if k not in ("polarization", "source",
                                                                      "good")}
        return cls(
            az_deg=f["az_deg"], el_deg=f["el_deg"],
            xel_arcsec=60.0 * (f["xel_arcmin"] + f["model_xel_arcmin"]
                               + f["applied_xel_arcmin"]),
            el_arcsec=60.0 * (f["el_arcmin"] + f["model_el_arcmin"] + f["applied_el_arcmin"]),
            t_s=f["t_s"], sun_el_deg=f["sun_el_deg"], source=c["source"][sel].astype(str),
            amp_k=0.5 * (f["xel_amp_k"] + f["el_amp_k"]), good=c["good"][sel].astype(bool))


def _fit_a_data(rows) -> tuple[PointingData, np.ndarray]:
    """Fit A's input (the rows variant A selects, as the fitter saw them) and the Sun's
    elevation at those rows (deg)."""
    cols = columns(rows)
    mask = variant_mask(cols, VARIANTS[0])
    return pointing_data(cols, mask), np.asarray(cols["sun_el_deg"], dtype=float)[mask]


# ---------------------------------------------------------------------------------------------
# Fig. 1: sky distribution
# ---------------------------------------------------------------------------------------------
def sky_distribution_figure(az_deg, el_deg, path: str | Path, *, source=None, good=None,
                            el_limit_deg: float | None = None, title: str = "",
                            formats: Sequence[str] = ("png",)) -> FigureFile:
    """Fig. 1: where the observations were on the sky, a polar alt-az plot (azimuth as the
    angle, North up, East right; zenith distance as the radius, deg), coloured by source;
    scans the reduction flagged are open circles."""
    az = np.radians(np.asarray(az_deg, dtype=float))
    zd = 90.0 - np.asarray(el_deg, dtype=float)
    source = np.full(az.shape, "observations") if source is None else np.asarray(source)
    good = np.ones(az.shape, bool) if good is None else np.asarray(good, dtype=bool)
    title = title or "Fig. 1  Sky distribution of the observations"
    with _Canvas(8.0, 6.5) as fig:
        ax = fig.add_axes((0.06, 0.08, 0.62, 0.80), projection="polar")
        ax.set_theta_zero_location("N")
        ax.set_theta_direction(-1)
        names = list(dict.fromkeys(source.tolist()))
        for k, name in enumerate(names):
            sel = source == name
            color = _SERIES_COLORS[k % len(_SERIES_COLORS)]
            ax.scatter(az[sel & good], zd[sel & good], s=14, color=color,
                       label=f"{name} ({int(sel.sum())})", zorder=3)
            if (sel & ~good).any():
                ax.scatter(az[sel & ~good], zd[sel & ~good], s=18, facecolors="none",
                           edgecolors=color, zorder=3)
        if el_limit_deg is not None:
            theta = np.linspace(0.0, 2.0 * math.pi, 181)
            ax.plot(theta, np.full(theta.shape, 90.0 - el_limit_deg), "k--", lw=0.8,
                    label=f"elevation limit {el_limit_deg:g}\N{DEGREE SIGN}")
        ax.set_rlim(0.0, 90.0)
        ax.set_rticks([15, 30, 45, 60, 75])
        ax.set_rlabel_position(112.5)
        ax.set_xticks(np.radians(np.arange(0, 360, 45)))
        ax.set_xticklabels(["N 0\N{DEGREE SIGN}", "45\N{DEGREE SIGN}", "E 90\N{DEGREE SIGN}",
                            "135\N{DEGREE SIGN}", "S 180\N{DEGREE SIGN}", "225\N{DEGREE SIGN}",
                            "W 270\N{DEGREE SIGN}", "315\N{DEGREE SIGN}"])
        ax.legend(loc="upper left", bbox_to_anchor=(1.08, 1.0), title="source (scans)",
                  frameon=False)
        n_bad = int((~good).sum())
        fig.text(0.70, 0.08, f"{az.size} scans; {n_bad} flagged by the\n"
                 "reduction (open circles)\nazimuth: angle (North up, East right)\n"
                 "radius: zenith distance\n= 90\N{DEGREE SIGN} \N{MINUS SIGN} elevation (deg)",
                 fontsize=8, va="bottom")
        caption = (f"Where the {az.size} scans pointed: azimuth as the angle (North up, East to "
                   "the right), zenith distance as the radius (the zenith at the centre, the "
                   "horizon at the rim). A fit can only determine the terms whose signature "
                   "these positions sample: gaps in the sky are gaps in what the model knows.")
        return _figure_file(fig, Path(path), title, caption, formats)


# ---------------------------------------------------------------------------------------------
# Figs. 2 and 3: errors or residuals against elevation and azimuth
# ---------------------------------------------------------------------------------------------
def _error_panels(axes, az_deg, el_deg, xel, el, *, sun_el_deg=None, rejected=None,
                  what: str = "error", letters: str = "abcd", binned: bool = True,
                  rejected_label: str = "rejected by the fit") -> None:
    """Four panels: xel and el (arcsec) against elevation and against azimuth (deg)."""
    az_deg = np.asarray(az_deg, float)
    el_deg = np.asarray(el_deg, float)
    rejected = (np.zeros(az_deg.shape, bool) if rejected is None
                else np.asarray(rejected, bool))
    groups = ([("observations", np.ones(az_deg.shape, bool), _SERIES_COLORS[0])]
              if sun_el_deg is None else _day_night_groups(sun_el_deg))
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
            ax.scatter(x[rejected], y[rejected], s=28, marker="x", color=_REJECT_COLOR,
                       lw=1.2, label=f"{rejected_label} ({int(rejected.sum())})")
        if binned and (~rejected).sum() >= 6:
            edges = np.linspace(xlim[0], xlim[1], 10 if xlim[1] <= 90 else 13)
            cx, my, ey = _binned_mean(x[~rejected], y[~rejected], edges)
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
        ax.set_title(f"({letters[k]}) rms {_rms(used_y):.1f}\" over {used_y.size} points",
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
    with _Canvas(10.0, 8.0) as fig:
        grid = fig.subplots(2, 2)
        fig.subplots_adjust(left=0.08, right=0.98, bottom=0.07, top=0.91, hspace=0.32,
                            wspace=0.22)
        _error_panels(grid.ravel(), az_deg, el_deg, xel_arcsec, el_arcsec,
                      sun_el_deg=sun_el_deg, rejected=rejected, what=what,
                      rejected_label=rejected_label)
        return _figure_file(fig, Path(path), title, caption or title, formats)


# ---------------------------------------------------------------------------------------------
# Fig. 4: amplitude against elevation
# ---------------------------------------------------------------------------------------------
def _gain_curve(el_deg: np.ndarray, curve: Sequence[tuple[float, float]]) -> np.ndarray:
    pts = np.array(curve, dtype=float)
    return np.interp(el_deg, pts[:, 0], pts[:, 1])


def amplitude_figure(el_deg, amp_k, source, path: str | Path, *, good=None,
                     sources: Sequence[str] = STRONG_SOURCES,
                     gain_curve: Sequence[tuple[float, float]] = REPORT_GAIN_CURVE,
                     title: str = "", formats: Sequence[str] = ("png",),
                     fitted=None) -> FigureFile:
    """Fig. 4: amplitude (K, mean of the two scan axes) of the strong ``sources`` against
    elevation (deg), and the same normalised by each source's median above 30 deg, with the
    report's relative gain curve (section V: flat above 30 deg, 95% at 20, 90% at 10).
    ``fitted``: a gain curve fitted to this run (``controller.gaincurve.ElevationGainFit``),
    drawn dashed with its knots and their errors."""
    el_deg = np.asarray(el_deg, float)
    amp_k = np.asarray(amp_k, float)
    source = np.asarray(source).astype(str)
    good = np.ones(el_deg.shape, bool) if good is None else np.asarray(good, bool)
    title = title or "Fig. 4  Amplitude against elevation, strong sources"
    present = [s for s in sources if ((source == s) & good).any()]
    with _Canvas(10.0, 4.6) as fig:
        ax_abs, ax_rel = fig.subplots(1, 2)
        fig.subplots_adjust(left=0.07, right=0.98, bottom=0.12, top=0.84, wspace=0.25)
        grid = np.linspace(5.0, 90.0, 200)
        for k, name in enumerate(present):
            sel = (source == name) & good & np.isfinite(amp_k)
            color = _SERIES_COLORS[k % len(_SERIES_COLORS)]
            ax_abs.scatter(el_deg[sel], amp_k[sel], s=12, color=color,
                           label=f"{name} ({int(sel.sum())})")
            high = sel & (el_deg > 30.0)
            ref = float(np.median(amp_k[high])) if high.any() else float(np.median(amp_k[sel]))
            ax_rel.scatter(el_deg[sel], amp_k[sel] / ref, s=12, color=color,
                           label=f"{name} / {ref:.2f} K")
        ax_rel.plot(grid, _gain_curve(grid, gain_curve), "k-", lw=1.5,
                    label="1990 report, section V")
        if fitted is not None:
            ax_rel.plot(grid, fitted.gain(grid), "r--", lw=1.3,
                        label="fitted, opacity-corrected amplitudes")
            ax_rel.errorbar(fitted.knots_deg[:-1], fitted.gains, yerr=fitted.sigma, fmt="rs",
                            ms=4, capsize=2)
        if not present:
            for ax in (ax_abs, ax_rel):
                ax.text(0.5, 0.5, "no good scans of " + " or ".join(sources), ha="center",
                        va="center", transform=ax.transAxes)
        ax_abs.set_xlabel("elevation (deg)")
        ax_abs.set_ylabel("amplitude (K, antenna temperature)")
        ax_abs.set_title("(a) measured amplitude", fontsize=9)
        ax_rel.set_xlabel("elevation (deg)")
        ax_rel.set_ylabel("relative gain (amplitude / median above 30\N{DEGREE SIGN})")
        ax_rel.set_title("(b) relative gain and the report's curve", fontsize=9)
        for ax in (ax_abs, ax_rel):
            ax.set_xlim(0.0, 90.0)
            if ax.get_legend_handles_labels()[0]:  # none without the strong sources
                ax.legend(loc="lower right", fontsize=7)
        caption = ("The amplitude of the two strongest sources against elevation. The 45-ft's "
                   "gain is flat above 30\N{DEGREE SIGN} and falls to 95% at 20\N{DEGREE SIGN} "
                   "and 90% at 10\N{DEGREE SIGN} (1990 report, section V; black line). The "
                   "measured amplitudes also include atmospheric extinction, exp(-tau / sin E), "
                   "and scatter from pointing errors during the scan.")
        if fitted is not None:
            caption += (" The red dashed line and squares (with 1-sigma errors) are the gain "
                        "curve fitted to this run: amplitudes corrected for the cross-axis "
                        "pointing offset and for extinction with the measured zenith opacity, "
                        "each source scaled by its own fitted peak (controller.gaincurve).")
        return _figure_file(fig, Path(path), title, caption, formats)


# ---------------------------------------------------------------------------------------------
# residual maps, histograms and time series
# ---------------------------------------------------------------------------------------------
#: quiver scale: arcsec of residual per degree of zenith distance on the sky map
_QUIVER_ARCSEC_PER_DEG = 10.0


def _sky_axes(ax, el_limit_deg: float | None = 10.0) -> None:
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


def _quiver(ax, az_deg, el_deg, xel, el, used, *, key: bool = True) -> None:
    """Arrows of (xel, el) residuals at each position on a :func:`_sky_axes` map."""
    a = np.radians(np.asarray(az_deg, float))
    zd = 90.0 - np.asarray(el_deg, float)
    x, y = zd * np.sin(a), zd * np.cos(a)
    xel = np.asarray(xel, float)
    el = np.asarray(el, float)
    # increasing azimuth is (cos A, -sin A) on the map; increasing elevation (-sin A, -cos A)
    u = xel * np.cos(a) - el * np.sin(a)
    v = -xel * np.sin(a) - el * np.cos(a)
    used = np.asarray(used, bool)
    for sel, color in ((used, "#1f4e9c"), (~used, _REJECT_COLOR)):
        if sel.any():
            q = ax.quiver(x[sel], y[sel], u[sel], v[sel], color=color, angles="xy",
                          scale_units="xy", scale=_QUIVER_ARCSEC_PER_DEG, width=0.003,
                          headwidth=3.5)
            if key and color != _REJECT_COLOR:
                ax.quiverkey(q, 0.86, 0.04, 60.0, "60\"", labelpos="E", coordinates="axes",
                             fontproperties={"size": 8})
    ax.scatter(x, y, s=3, color="k", zorder=3)


def residual_quiver_figure(data: PointingData, fit: FitResult, path: str | Path, *,
                           title: str = "", formats: Sequence[str] = ("png",)) -> FigureFile:
    """The residuals of ``fit`` as arrows on a map of the sky (North up, East right, zenith
    at the centre; 60" of residual = 6 deg of zenith distance); rejected points in red."""
    _check_fit_data(fit, data, "fit")
    title = title or "Residuals after the fit on the sky"
    with _Canvas(7.5, 7.5) as fig:
        ax = fig.add_axes((0.03, 0.03, 0.94, 0.88))
        _sky_axes(ax)
        _quiver(ax, np.degrees(data.az_rad), np.degrees(data.el_rad), fit.residual_xel_arcsec,
                fit.residual_el_arcsec, fit.used)
        ax.text(-100.0, -100.0, f"{fit.n_used} used (blue), {fit.n_rejected} rejected (red)\n"
                f"sky rms {fit.sky_rms_arcsec:.1f}\"", fontsize=8, va="bottom")
        caption = ("Each arrow is one scan's residual after the fit (indicated minus true: "
                   "cross-elevation along increasing azimuth, elevation towards the zenith), "
                   f"drawn at the position observed; 60\" of residual is drawn as "
                   f"{60 / _QUIVER_ARCSEC_PER_DEG:g}\N{DEGREE SIGN} on the map. Random noise "
                   "points every way; arrows that agree with their neighbours are a term the "
                   "model lacks.")
        return _figure_file(fig, Path(path), title, caption, formats)


def histogram_figure(series: Mapping[str, tuple[Any, Any]], path: str | Path, *,
                     title: str = "", caption: str = "", bin_arcsec: float = 10.0,
                     gaussian: bool = True,
                     formats: Sequence[str] = ("png",)) -> FigureFile:
    """Histograms of cross-elevation and elevation values (arcsec) for each named series
    ``{label: (xel, el)}``, with the rms in the legend and, if ``gaussian``, the normal
    curve of the first series' rms."""
    if not series:
        raise ValueError("histogram_figure needs at least one series")
    title = title or "Residual histograms"
    all_values = np.concatenate([np.concatenate([np.ravel(x), np.ravel(y)])
                                 for x, y in series.values()]).astype(float)
    all_values = all_values[np.isfinite(all_values)]
    top = max(bin_arcsec, float(np.max(np.abs(all_values))) if all_values.size else 1.0)
    edges = np.arange(-top - bin_arcsec, top + 2 * bin_arcsec, bin_arcsec)
    edges -= 0.5 * bin_arcsec
    with _Canvas(10.0, 4.4) as fig:
        axes = fig.subplots(1, 2)
        fig.subplots_adjust(left=0.07, right=0.98, bottom=0.12, top=0.84, wspace=0.2)
        for a, (ax, axis_name) in enumerate(zip(axes, ("cross-elevation", "elevation"),
                                                strict=True)):
            for k, (label, values) in enumerate(series.items()):
                v = np.asarray(values[a], float)
                v = v[np.isfinite(v)]
                color = _SERIES_COLORS[k % len(_SERIES_COLORS)]
                ax.hist(v, bins=edges, histtype="stepfilled" if k == 0 else "step",
                        alpha=0.45 if k == 0 else 1.0, color=color, lw=1.5,
                        label=f"{label}: N {v.size}, rms {_rms(v):.1f}\"")
                s = _rms(v)
                if gaussian and k == 0 and v.size > 1 and s > 0:
                    x = np.linspace(edges[0], edges[-1], 300)
                    ax.plot(x, v.size * bin_arcsec * np.exp(-0.5 * (x / s) ** 2)
                            / (s * math.sqrt(2 * math.pi)), "k-", lw=1,
                            label=f"normal, \N{GREEK SMALL LETTER SIGMA} = {s:.1f}\"")
            ax.set_xlabel(f"{axis_name} (arcsec)")
            ax.set_ylabel(f"number per {bin_arcsec:g}\" bin")
            ax.set_title(f"({'ab'[a]}) {axis_name}", fontsize=9)
            ax.legend(loc="upper right", fontsize=7)
        return _figure_file(fig, Path(path), title, caption or title, formats)


def residual_time_figure(fit: FitResult, data: PointingData, path: str | Path, *,
                         sun_el_deg=None, start_label: str = "", title: str = "",
                         formats: Sequence[str] = ("png",)) -> FigureFile:
    """Residuals of ``fit`` (arcsec) against time since the start of the campaign (h), with
    the hours when the Sun was up shaded (needs ``data.t_s``; ``sun_el_deg`` per point)."""
    _check_fit_data(fit, data, "fit")
    if data.t_s is None:
        raise ValueError("residual_time_figure needs observation times (PointingData.t_s)")
    title = title or "Residuals after the fit against time"
    t_h = np.asarray(data.t_s, float) / 3600.0
    order = np.argsort(t_h, kind="stable")
    rejected = ~np.asarray(fit.used, bool)
    with _Canvas(10.0, 5.6) as fig:
        axes = fig.subplots(2, 1, sharex=True)
        fig.subplots_adjust(left=0.08, right=0.98, bottom=0.10, top=0.89, hspace=0.12)
        for ax, y, name in zip(axes, (fit.residual_xel_arcsec, fit.residual_el_arcsec),
                               ("cross-elevation", "elevation"), strict=True):
            y = np.asarray(y, float)
            if sun_el_deg is not None:
                sun = np.asarray(sun_el_deg, float)
                ax.fill_between(t_h[order], 0, 1, where=(sun[order] > DAY_SUN_MIN_DEG),
                                transform=ax.get_xaxis_transform(), color="#fdd49e",
                                alpha=0.6, step="mid", lw=0, label="Sun above the horizon")
            ax.scatter(t_h[~rejected], y[~rejected], s=9, color="#1f4e9c", lw=0,
                       label="used")
            if rejected.any():
                ax.scatter(t_h[rejected], y[rejected], s=28, marker="x", color=_REJECT_COLOR,
                           label="rejected")
            span = max(float(t_h.max() - t_h.min()), 1.0) if t_h.size else 1.0
            edges = np.arange(t_h.min(), t_h.max() + span / 24 + 1e-9, span / 24) \
                if t_h.size else np.array([0.0, 1.0])
            cx, my, ey = _binned_mean(t_h[~rejected], y[~rejected], edges)
            if cx.size:
                ax.errorbar(cx, my, yerr=ey, color="k", lw=1.2, capsize=2, marker="s", ms=3,
                            label="binned mean \N{PLUS-MINUS SIGN} s.e.")
            ax.axhline(0.0, color="k", lw=0.6)
            ax.set_ylabel(f"{name}\nresidual (arcsec)")
        axes[0].legend(loc="upper right", fontsize=7, ncol=4)
        axes[1].set_xlabel("time since the start of the campaign (h)"
                           + (f", {start_label}" if start_label else ""))
        caption = ("Residuals in the order they were observed. Thermal effects show as "
                   "structure that follows the Sun (shaded: daytime); a constant scatter "
                   "over the whole run is what noise and wind look like.")
        return _figure_file(fig, Path(path), title, caption, formats)


# ---------------------------------------------------------------------------------------------
# coefficients and comparisons
# ---------------------------------------------------------------------------------------------
def coefficients_figure(fits: Mapping[str, FitResult | None], path: str | Path, *,
                        truth_arcsec: Mapping[str, float] | None = None, title: str = "",
                        formats: Sequence[str] = ("png",)) -> FigureFile:
    """Each fit's coefficients minus the truth (arcsec) with TPOINT's sigma (thin, capped)
    and the honest sigma (thick, faint) as error bars; without a truth, minus the first
    fit's value."""
    present = {k: f for k, f in fits.items() if f is not None}
    if not present:
        raise ValueError("coefficients_figure needs at least one fit")
    first = next(iter(present.values()))
    names = list(first.names)
    if truth_arcsec:
        reference = np.array([truth_arcsec.get(n, math.nan) for n in names], float)
        ref_label = "truth"
    else:
        reference = np.asarray(first.values_arcsec, float)
        ref_label = f"fit {next(iter(present))}"
    title = title or f"Coefficients of the fits minus the {ref_label}"
    width = 0.8 / len(present)
    with _Canvas(10.0, 5.0) as fig:
        ax = fig.add_axes((0.08, 0.12, 0.90, 0.74))
        x0 = np.arange(len(names), dtype=float)
        for k, (label, fit) in enumerate(present.items()):
            idx = [fit.names.index(n) if n in fit.names else -1 for n in names]
            value = np.array([fit.values_arcsec[i] if i >= 0 else math.nan for i in idx])
            sigma = np.array([fit.sigma_arcsec[i] if i >= 0 else math.nan for i in idx])
            honest = (np.array([fit.sigma_honest_arcsec[i] if i >= 0 else math.nan
                                for i in idx]) if fit.sigma_honest_arcsec is not None
                      else np.full(len(names), math.nan))
            x = x0 - 0.4 + width * (k + 0.5)
            y = value - reference
            color = _SERIES_COLORS[k % len(_SERIES_COLORS)]
            ax.errorbar(x, y, yerr=np.where(np.isfinite(honest), honest, 0.0), fmt="none",
                        ecolor=color, elinewidth=4, alpha=0.3)
            ax.errorbar(x, y, yerr=np.where(np.isfinite(sigma), sigma, 0.0), fmt="o",
                        color=color, ms=4, capsize=2, lw=1, label=f"fit {label}")
        ax.axhline(0.0, color="k", lw=0.8)
        ax.set_xticks(x0)
        ax.set_xticklabels(names)
        ax.set_xlim(-0.6, len(names) - 0.4)
        ax.set_xlabel("term")
        ax.set_ylabel(f"fitted value \N{MINUS SIGN} {ref_label} (arcsec)")
        ax.legend(loc="upper left", ncol=min(len(present), 6), fontsize=7)
        ax.text(0.99, 0.02, "thin bars: TPOINT sigma; thick faint bars: honest sigma",
                transform=ax.transAxes, ha="right", fontsize=7)
        caption = (f"How far each fit's coefficients are from the {ref_label}, with two error "
                   "bars: TPOINT's formal sigma (assumes independent residuals) and the honest "
                   "sigma (a jackknife over one-hour blocks, widened for its few degrees of "
                   "freedom), which allows for residuals "
                   "correlated in time. A point more than two or three honest sigmas from zero "
                   "is a real disagreement.")
        return _figure_file(fig, Path(path), title, caption, formats)


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
    with _Canvas(10.0, 4.8) as fig:
        ax = fig.add_axes((0.08, 0.12, 0.90, 0.70))
        x0 = np.arange(len(categories), dtype=float)
        for k, (label, series) in enumerate(values.items()):
            y = np.array([float(series.get(c, math.nan)) for c in categories])
            ok = np.isfinite(y) & ((y > 0) if log else True)
            ax.bar(x0[ok] - 0.4 + width * (k + 0.5), y[ok], width=width * 0.92,
                   color=_SERIES_COLORS[k % len(_SERIES_COLORS)], label=label)
        if log:
            from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

            ax.set_yscale("log")
            ax.yaxis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
            ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _pos: f"{v:g}"))
            ax.yaxis.set_minor_formatter(NullFormatter())
        ax.set_xticks(x0)
        ax.set_xticklabels(categories)
        ax.set_xlim(-0.6, len(categories) - 0.4)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.01), ncol=min(n, 8), fontsize=7,
                  frameon=False)
        return _figure_file(fig, Path(path), title, caption or title, formats)


# ---------------------------------------------------------------------------------------------
# before/after (diagnose) and scan traces (teaching)
# ---------------------------------------------------------------------------------------------
def _check_fit_data(fit: FitResult, data: PointingData, name: str) -> None:
    n = len(np.asarray(fit.residual_xel_arcsec))
    if n != len(data):
        raise ValueError(f"{name} has residuals for {n} observations but the pointing data "
                         f"hold {len(data)}: pass the PointingData the fit was made from")


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
    _check_fit_data(before_fit, data, "before_fit")
    _check_fit_data(after_fit, after_data, "after_fit")
    out = Path(out_dir)
    files = []
    pairs = ((before_name, before_fit, data), (after_name, after_fit, after_data))
    title = (f"Residuals before ({before_name}) and after ({after_name}): sky rms "
             f"{before_fit.sky_rms_arcsec:.1f}\" \N{RIGHTWARDS ARROW} "
             f"{after_fit.sky_rms_arcsec:.1f}\"")
    with _Canvas(14.0, 7.5) as fig:
        grid = fig.subplots(2, 4)
        fig.subplots_adjust(left=0.05, right=0.99, bottom=0.08, top=0.88, hspace=0.42,
                            wspace=0.28)
        for row, (name, fit, d) in enumerate(pairs):
            _error_panels(grid[row], np.degrees(d.az_rad), np.degrees(d.el_rad),
                          fit.residual_xel_arcsec, fit.residual_el_arcsec,
                          rejected=~np.asarray(fit.used, bool), what="residual",
                          letters="abcd" if row == 0 else "efgh")
            grid[row, 0].annotate(f"{name}: {', '.join(fit.names)}", (0.0, 1.18),
                                  xycoords="axes fraction", fontsize=9, fontweight="bold")
        caption = (f"Top: residuals of the fit {before_name} (terms "
                   f"{', '.join(before_fit.names)}); bottom: {after_name} (terms "
                   f"{', '.join(after_fit.names)}). A signature that is gone from the bottom "
                   "row was explained by what was added.")
        files.append(_figure_file(fig, out / f"{label}_residuals.png", title, caption,
                                  formats))
    used = {name: (np.asarray(f.residual_xel_arcsec)[f.used],
                   np.asarray(f.residual_el_arcsec)[f.used]) for name, f, _ in pairs}
    files.append(histogram_figure(
        used, out / f"{label}_histograms.png",
        title=f"Residual histograms {before_name} and {after_name} (used points)",
        caption=f"Residuals of the used points {before_name} (filled) and {after_name} "
                "(line); a narrower histogram is a better model.", formats=formats))
    with _Canvas(13.0, 6.8) as fig:
        axes = fig.subplots(1, 2)
        fig.subplots_adjust(left=0.01, right=0.99, bottom=0.02, top=0.86, wspace=0.04)
        for ax, (name, fit, d) in zip(axes, pairs, strict=True):
            _sky_axes(ax)
            _quiver(ax, np.degrees(d.az_rad), np.degrees(d.el_rad), fit.residual_xel_arcsec,
                    fit.residual_el_arcsec, fit.used)
            ax.set_title(f"{name}: sky rms {fit.sky_rms_arcsec:.1f}\"", fontsize=10)
        files.append(_figure_file(
            fig, out / f"{label}_quiver.png",
            f"Residuals on the sky, {before_name} and {after_name}",
            f"Residual arrows on the sky (60\" = {60 / _QUIVER_ARCSEC_PER_DEG:g}\N{DEGREE SIGN}"
            f" of zenith distance), {before_name} (left) and {after_name} (right).",
            formats))
    return files


def scan_trace_figure(traces: Sequence[ScanTrace], path: str | Path, *, hpbw_arcmin: float,
                      title: str = "", caption: str = "", ylabel: str = "total power (K)",
                      formats: Sequence[str] = ("png",)) -> FigureFile:
    """Total power (K) against sky offset (arcmin) for the azimuth (cross-elevation) and
    elevation halves of one or more cross scans, with the beam's half-power width marked."""
    if not traces:
        raise ValueError("scan_trace_figure needs at least one scan")
    title = title or "Cross scans"
    with _Canvas(10.0, 4.6) as fig:
        axes = fig.subplots(1, 2, sharey=True)
        fig.subplots_adjust(left=0.07, right=0.98, bottom=0.12, top=0.84, wspace=0.08)
        for ax, axis_name in zip(axes, ("azimuth scan (cross-elevation offset)",
                                        "elevation scan (elevation offset)"), strict=True):
            ax.axvspan(-hpbw_arcmin / 2, hpbw_arcmin / 2, color="0.9", lw=0,
                       label=f"half-power beam width ({hpbw_arcmin:g}')")
            ax.set_xlabel(f"{axis_name} (arcmin)")
            ax.axvline(0.0, color="k", lw=0.6)
        for k, trace in enumerate(traces):
            color = _SERIES_COLORS[k % len(_SERIES_COLORS)]
            for ax, x, y in ((axes[0], trace.az_offsets_arcmin, trace.az_power_k),
                             (axes[1], trace.el_offsets_arcmin, trace.el_power_k)):
                x = np.asarray(x, float)
                y = np.asarray(y, float)
                order = np.argsort(x)
                ax.plot(x[order], y[order], "-o", color=color, ms=5, lw=1.2, label=trace.label)
        axes[0].set_ylabel(ylabel)
        axes[0].legend(loc="upper left", fontsize=7)
        return _figure_file(fig, Path(path), title, caption or title, formats)


# ---------------------------------------------------------------------------------------------
# all figures of a run
# ---------------------------------------------------------------------------------------------
def run_figures(rows, fits: Mapping[str, FitResult | None], out_dir: str | Path, *,
                truth_arcsec: Mapping[str, float] | None = None, name: str = "",
                start_label: str = "", el_limit_deg: float | None = None,
                reference_rms: Mapping[str, tuple[float, float]] | None = None,
                gain_curve: Sequence[tuple[float, float]] = REPORT_GAIN_CURVE,
                formats: Sequence[str] = ("png",), gain_fit=None) -> list[FigureFile]:
    """The figures of one run into ``out_dir``, in the report's order: see the module
    docstring.

    ``rows``: the recordings (row dicts or an astropy Table); ``fits``: fits A-F as from
    :func:`antsim.run.outputs.run_fits` (None for a variant with too few observations; the
    figures that need fit A are left out when it is None); ``truth_arcsec``: the injected
    coefficients by term name, if known; ``name``: prefixed to the titles;
    ``el_limit_deg``: the scheduler's elevation limit, drawn on the sky; ``reference_rms``:
    ``{fit: (xel, el)}`` published rms (arcsec) drawn beside the run's; ``gain_fit``: the
    run's fitted elevation gain curve, drawn on Fig. 4.
    """
    out = Path(out_dir)
    prefix = f"{name}: " if name else ""
    obs = _Observations.from_rows(rows, "AVG")
    files = _recording_figures(obs, out, prefix, el_limit_deg, formats)
    fit_a = fits.get("A")
    if fit_a is not None:
        data, sun = _fit_a_data(rows)
        files.append(_residuals_figure(fit_a, data, sun, out, prefix, formats))
    files.append(amplitude_figure(
        obs.el_deg, obs.amp_k, obs.source, out / "fig4_amplitude.png", good=obs.good,
        gain_curve=gain_curve, title=f"Fig. 4  {prefix}amplitude against elevation, strong "
        "sources", formats=formats, fitted=gain_fit))
    if fit_a is not None:
        files += _fit_a_figures(fit_a, data, sun, out, prefix, start_label, formats)
        present = {k: v for k, v in fits.items() if v is not None}
        files += _fits_figures(present, out, prefix, truth_arcsec, reference_rms, formats)
    return files


def _recording_figures(obs: _Observations, out: Path, prefix: str,
                       el_limit_deg: float | None, formats: Sequence[str]) -> list[FigureFile]:
    """Fig. 1 and Fig. 2a-d: what the recordings alone show."""
    defined = np.isfinite(obs.xel_arcsec) & np.isfinite(obs.el_arcsec)
    return [
        sky_distribution_figure(
            obs.az_deg, obs.el_deg, out / "fig1_sky.png", source=obs.source, good=obs.good,
            el_limit_deg=el_limit_deg,
            title=f"Fig. 1  {prefix}sky distribution of the observations", formats=formats),
        pointing_errors_figure(
            obs.az_deg[defined], obs.el_deg[defined],
            obs.xel_arcsec[defined], obs.el_arcsec[defined], out / "fig2_total_errors.png",
            sun_el_deg=obs.sun_el_deg[defined], rejected=~obs.good[defined],
            rejected_label="flagged by the reduction",
            title=f"Fig. 2a-d  {prefix}total pointing errors against elevation and azimuth",
            caption="The total pointing error of every scan (what the reduction measured plus "
                    "the pointing model and corrections in use: the error the antenna would "
                    "make with no model), cross-elevation and elevation, against elevation "
                    "and azimuth. Red crosses are scans the reduction flagged (S/N < 4, ...). "
                    "The large constant elevation error is the encoder zero offset (W6).",
            formats=formats),
    ]


def _residuals_figure(fit_a: FitResult, data: PointingData, sun: np.ndarray, out: Path,
                      prefix: str, formats: Sequence[str]) -> FigureFile:
    """Fig. 3a-d: the residuals after fit A."""
    return pointing_errors_figure(
        np.degrees(data.az_rad), np.degrees(data.el_rad),
        fit_a.residual_xel_arcsec, fit_a.residual_el_arcsec, out / "fig3_residuals.png",
        sun_el_deg=sun,
        rejected=~np.asarray(fit_a.used, bool), what="residual",
        title=f"Fig. 3a-d  {prefix}residuals after fit A against elevation and azimuth",
        caption=f"What fit A ({fit_a.model.name}, {fit_a.n_used} of {fit_a.n_input} "
                "scans) leaves unexplained, against elevation and azimuth. Red crosses are "
                "the scans the robust fit rejected. The black line is the mean in bins: "
                "where it leaves zero, the model misses a term with that signature.",
        formats=formats)


def _fit_a_figures(fit_a: FitResult, data: PointingData, sun: np.ndarray, out: Path,
                   prefix: str, start_label: str, formats: Sequence[str]) -> list[FigureFile]:
    """Fit A's residuals on the sky, as histograms and against time."""
    used = np.asarray(fit_a.used, bool)
    series = {"used": (fit_a.residual_xel_arcsec[used], fit_a.residual_el_arcsec[used])}
    if (~used).any():
        series["rejected"] = (fit_a.residual_xel_arcsec[~used],
                              fit_a.residual_el_arcsec[~used])
    return [
        residual_quiver_figure(
            data, fit_a, out / "fig5_residual_quiver.png",
            title=f"{prefix}residuals after fit A on the sky", formats=formats),
        histogram_figure(
            series, out / "fig6_residual_histograms.png",
            title=f"{prefix}histograms of the residuals after fit A",
            caption="The residuals of the scans fit A used, with the normal curve of the same "
                    "rms; the scans the robust fit rejected are drawn separately. Long tails "
                    "beyond the curve are outliers (gusts, bad scans).", formats=formats),
        residual_time_figure(
            fit_a, data, out / "fig7_residuals_time.png", sun_el_deg=sun,
            start_label=start_label, title=f"{prefix}residuals after fit A against time",
            formats=formats),
    ]


def _fits_figures(present: Mapping[str, FitResult], out: Path, prefix: str,
                  truth_arcsec: Mapping[str, float] | None,
                  reference_rms: Mapping[str, tuple[float, float]] | None,
                  formats: Sequence[str]) -> list[FigureFile]:
    """Fits A-F side by side: coefficients, TPOINT sigmas and residual rms (Table 2)."""
    sigmas = {f"fit {k}": dict(zip(v.names, (float(s) for s in v.sigma_arcsec),
                                   strict=True)) for k, v in present.items()}
    rms: dict[str, dict[str, float]] = {
        "xel rms": {k: v.xel_rms_arcsec for k, v in present.items()}}
    if reference_rms:
        rms["xel rms, 1990 report"] = {k: v[0] for k, v in reference_rms.items()
                                       if k in present}
    rms["el rms"] = {k: v.el_rms_arcsec for k, v in present.items()}
    if reference_rms:
        rms["el rms, 1990 report"] = {k: v[1] for k, v in reference_rms.items()
                                      if k in present}
    return [
        coefficients_figure(
            present, out / "fig8_coefficients.png", truth_arcsec=truth_arcsec,
            title=f"{prefix}coefficients of fits A-F"
                  + (" minus the injected truth" if truth_arcsec else " minus fit A"),
            formats=formats),
        comparison_figure(
            sigmas, out / "fig9_term_sigmas.png", log=True, xlabel="term",
            title=f"{prefix}TPOINT sigma of each term, fits A-F",
            ylabel="sigma (arcsec, log scale)",
            caption="The formal (TPOINT) uncertainty of each coefficient in each fit: fewer "
                    "points (fits D, E) or a narrower spread on the sky make it larger; "
                    "strongly correlated terms (e.g. W1, W2, W3) are the least determined.",
            formats=formats),
        comparison_figure(
            rms, out / "fig10_fit_rms.png",
            title=f"{prefix}rms of the residuals, fits A-F",
            xlabel="fit (Table 2: A all, B XR, C XL, D day, E night, F unfiltered)",
            ylabel="rms (arcsec)",
            caption="Table 2 as a chart: the rms of the cross-elevation and elevation "
                    "residuals of each fit" + (", beside the 1990 report's values"
                                               if reference_rms else "") + ".",
            formats=formats),
    ]

"""The figures of a run's report (``antsim run``), in the style of the 1990 report (Ghigo),
and the diagnostics TPOINT and katpoint users expect.

:func:`run_figures` draws, in the report's order: Fig. 1 the sky distribution of the
observations (polar alt-az: azimuth as the angle, North up and East to the right, zenith
distance as the radius); Fig. 2a-d the total pointing errors against elevation and azimuth;
when the controller pointed with a model, the errors with that model and without it; Fig.
3a-d the residuals after fit A (rejected points marked); Fig. 4 the amplitude of the strong
sources against elevation with the report's gain curve (section V); a quiver map of
the residuals on the sky; residual histograms; residuals against time with the daylight
marked; the coefficients of fits A-F against the truth; the coefficient sigmas and the rms
of every fit. Figures other pages draw too are in :mod:`antsim.figures.charts`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from antsim.documents import GHIGO1990_GAIN_CURVE
from controller.astro.sun import DAY_SUN_MIN_DEG
from controller.pointing.data import PointingData
from controller.pointing.result import FitResult
from controller.pointing.variants import VARIANTS, columns, pointing_data, variant_mask

from .charts import (
    check_fit_data,
    comparison_figure,
    histogram_figure,
    pointing_errors_figure,
    residual_quiver_figure,
)
from .style import (
    REJECT_COLOR,
    SERIES_COLORS,
    Canvas,
    FigureFile,
    binned_mean,
    figure_file,
    rms,
)

__all__ = [
    "REPORT_GAIN_CURVE",
    "STRONG_SOURCES",
    "amplitude_figure",
    "coefficients_figure",
    "in_use_figure",
    "residual_time_figure",
    "run_figures",
    "sky_distribution_figure",
]

#: the strong sources of the report's gain-curve figure (Fig. 4)
STRONG_SOURCES = ("Cassiopeia A", "Cygnus A")
#: relative gain against elevation, Ghigo (1990) section V (antsim.documents)
REPORT_GAIN_CURVE = GHIGO1990_GAIN_CURVE


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
    #: the corrections the model in use applied (arcsec; zero without a model)
    model_xel_arcsec: np.ndarray
    model_el_arcsec: np.ndarray
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
            model_xel_arcsec=60.0 * f["model_xel_arcmin"],
            model_el_arcsec=60.0 * f["model_el_arcmin"],
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
    with Canvas(8.0, 6.5) as fig:
        ax = fig.add_axes((0.06, 0.08, 0.62, 0.80), projection="polar")
        ax.set_theta_zero_location("N")
        ax.set_theta_direction(-1)
        names = list(dict.fromkeys(source.tolist()))
        for k, name in enumerate(names):
            sel = source == name
            color = SERIES_COLORS[k % len(SERIES_COLORS)]
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
        return figure_file(fig, Path(path), title, caption, formats)


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
    ``fitted``: a gain curve fitted to this run (``controller.scans.gaincurve.ElevationGainFit``),
    drawn dashed with its knots and their errors."""
    el_deg = np.asarray(el_deg, float)
    amp_k = np.asarray(amp_k, float)
    source = np.asarray(source).astype(str)
    good = np.ones(el_deg.shape, bool) if good is None else np.asarray(good, bool)
    title = title or "Fig. 4  Amplitude against elevation, strong sources"
    present = [s for s in sources if ((source == s) & good).any()]
    with Canvas(10.0, 4.6) as fig:
        ax_abs, ax_rel = fig.subplots(1, 2)
        fig.subplots_adjust(left=0.07, right=0.98, bottom=0.12, top=0.84, wspace=0.25)
        grid = np.linspace(5.0, 90.0, 200)
        for k, name in enumerate(present):
            sel = (source == name) & good & np.isfinite(amp_k)
            color = SERIES_COLORS[k % len(SERIES_COLORS)]
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
                        "each source scaled by its own fitted peak (controller.scans.gaincurve).")
        return figure_file(fig, Path(path), title, caption, formats)


# ---------------------------------------------------------------------------------------------
# residuals against time, coefficients
# ---------------------------------------------------------------------------------------------
def residual_time_figure(fit: FitResult, data: PointingData, path: str | Path, *,
                         sun_el_deg=None, start_label: str = "", title: str = "",
                         formats: Sequence[str] = ("png",)) -> FigureFile:
    """Residuals of ``fit`` (arcsec) against time since the start of the campaign (h), with
    the hours when the Sun was up shaded (needs ``data.t_s``; ``sun_el_deg`` per point)."""
    check_fit_data(fit, data, "fit")
    if data.t_s is None:
        raise ValueError("residual_time_figure needs observation times (PointingData.t_s)")
    title = title or "Residuals after the fit against time"
    t_h = np.asarray(data.t_s, float) / 3600.0
    order = np.argsort(t_h, kind="stable")
    rejected = ~np.asarray(fit.used, bool)
    with Canvas(10.0, 5.6) as fig:
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
                ax.scatter(t_h[rejected], y[rejected], s=28, marker="x", color=REJECT_COLOR,
                           label="rejected")
            span = max(float(t_h.max() - t_h.min()), 1.0) if t_h.size else 1.0
            edges = np.arange(t_h.min(), t_h.max() + span / 24 + 1e-9, span / 24) \
                if t_h.size else np.array([0.0, 1.0])
            cx, my, ey = binned_mean(t_h[~rejected], y[~rejected], edges)
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
        return figure_file(fig, Path(path), title, caption, formats)


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
    with Canvas(10.0, 5.0) as fig:
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
            color = SERIES_COLORS[k % len(SERIES_COLORS)]
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
        return figure_file(fig, Path(path), title, caption, formats)


# ---------------------------------------------------------------------------------------------
# all figures of a run
# ---------------------------------------------------------------------------------------------
def run_figures(rows, fits: Mapping[str, FitResult | None], out_dir: str | Path, *,
                truth_arcsec: Mapping[str, float] | None = None, name: str = "",
                start_label: str = "", el_limit_deg: float | None = None,
                reference_rms: Mapping[str, tuple[float, float]] | None = None,
                gain_curve: Sequence[tuple[float, float]] = REPORT_GAIN_CURVE,
                formats: Sequence[str] = ("png",), gain_fit=None,
                model_in_use: str | None = None) -> list[FigureFile]:
    """The figures of one run into ``out_dir``, in the report's order: see the module
    docstring.

    ``rows``: the recordings (row dicts or an astropy Table); ``fits``: fits A-F as from
    :func:`antsim.run.outputs.run_fits` (None for a variant with too few observations; the
    figures that need fit A are left out when it is None); ``truth_arcsec``: the injected
    coefficients by term name, if known; ``name``: prefixed to the titles;
    ``el_limit_deg``: the scheduler's elevation limit, drawn on the sky; ``reference_rms``:
    ``{fit: (xel, el)}`` published rms (arcsec) drawn beside the run's; ``gain_fit``: the
    run's fitted elevation gain curve, drawn on Fig. 4; ``model_in_use``: the name of the
    pointing model the controller applied, if any (:func:`in_use_figure`, after Fig. 2).
    """
    out = Path(out_dir)
    prefix = f"{name}: " if name else ""
    obs = _Observations.from_rows(rows, "AVG")
    files = _recording_figures(obs, out, prefix, el_limit_deg, formats)
    if model_in_use is not None:
        files.append(in_use_figure(obs, model_in_use, out / "fig_model_in_use.png", prefix,
                                   formats))
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
                    "An azimuth encoder offset is an error across the sky that falls with "
                    "elevation as cos E (a): the 1990 report's W6, 12.24', which its section "
                    "IV gives as the reason for Fig. 2a's strong dependence on elevation.",
            formats=formats),
    ]


def in_use_figure(obs: _Observations, model: str, path: str | Path, prefix: str = "",
                  formats: Sequence[str] = ("png",)) -> FigureFile:
    """How the model in use pointed: in the good scans, the pointing error left with the
    model in use (what the scan measured, plus a search's correction) against the error
    without it (the model's correction added back), cross-elevation and elevation against
    elevation and azimuth (arcsec)."""
    good = obs.good & np.isfinite(obs.xel_arcsec) & np.isfinite(obs.el_arcsec)
    without = (obs.xel_arcsec[good], obs.el_arcsec[good])
    with_model = (without[0] - obs.model_xel_arcsec[good],
                  without[1] - obs.model_el_arcsec[good])
    az, el = obs.az_deg[good], obs.el_deg[good]
    title = f"Model in use  {prefix}pointing errors with it ({model}) and without it"
    with Canvas(10.0, 8.0) as fig:
        grid = fig.subplots(2, 2)
        fig.subplots_adjust(left=0.08, right=0.98, bottom=0.07, top=0.91, hspace=0.32,
                            wspace=0.22)
        for k, (ax, x, axis, xlabel, xlim) in enumerate((
                (grid[0, 0], el, 0, "elevation (deg)", (0.0, 90.0)),
                (grid[0, 1], el, 1, "elevation (deg)", (0.0, 90.0)),
                (grid[1, 0], az, 0, "azimuth (deg, N = 0, E = 90)", (0.0, 360.0)),
                (grid[1, 1], az, 1, "azimuth (deg, N = 0, E = 90)", (0.0, 360.0)))):
            name = ("cross-elevation", "elevation")[axis]
            ax.scatter(x, without[axis], s=9, color=SERIES_COLORS[1], alpha=0.6, lw=0,
                       label=f"without the model: rms {rms(without[axis]):.1f}\"")
            ax.scatter(x, with_model[axis], s=9, color=SERIES_COLORS[0], alpha=0.9, lw=0,
                       label=f"with it: rms {rms(with_model[axis]):.1f}\"")
            ax.axhline(0.0, color="k", lw=0.6)
            ax.set_xlim(*xlim)
            if xlim[1] > 90:
                ax.set_xticks(np.arange(0, 361, 45))
            ax.set_xlabel(xlabel)
            ax.set_ylabel(f"{name} error (arcsec)")
            ax.set_title(f"({'abcd'[k]}) {name} error over {x.size} good scans", fontsize=9)
            ax.legend(loc="lower left", fontsize=7, framealpha=0.8)
        caption = (f"The pointing error of every good scan with the model in use ({model}): "
                   "what the scan measured plus any correction the controller added on top "
                   "of the model (a search's), against the error the antenna would have made "
                   "without the model (the model's correction added back). Sky rms "
                   f"{math.hypot(rms(with_model[0]), rms(with_model[1])):.1f}\" with it, "
                   f"{math.hypot(rms(without[0]), rms(without[1])):.1f}\" without.")
        return figure_file(fig, Path(path), title, caption, formats)


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
                    "strongly correlated terms (e.g. the 1990 model's W6, W9, W10) are the "
                    "least determined.",
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

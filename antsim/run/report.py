"""The report of a run (``antsim run``): ``DIR/report.html`` and the figures in it.

:func:`write_run_report` builds it with :mod:`antsim.figures.html`: the fits A-F in the style of
the 1990 report's Table 2, the coefficients (Table 3), the coefficients against the injected
truth with pulls, fit A's warnings and correlations, the figures of
:mod:`antsim.figures.run`, the scenario text and the software versions.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from antsim.documents import Reference, reference_for
from antsim.figures.html import Block, Figure, Paragraph, Preformatted, Section, Table, write_report
from antsim.figures.run import run_figures
from controller.astro.sun import NIGHT_SUN_MAX_DEG
from controller.pointing.result import FitResult
from controller.pointing.signs import sign_convention
from controller.pointing.terms import get_term
from controller.pointing.variants import VARIANTS

from .sources import points_per_source

if TYPE_CHECKING:
    from antsim.figures.style import FigureFile
    from antsim.simulate.runner import RunResult

    from .inuse import Pointing

__all__ = ["coefficient_table", "fit_summary_table", "recoverable_terms_arcsec",
           "recoverable_words", "report_figures", "source_points_table", "truth_pull_table",
           "truth_terms_arcsec", "write_run_report"]

#: |pull| above which a table cell is highlighted
PULL_WARN = 3.0


# ---------------------------------------------------------------------------------------------
# tables of fits
# ---------------------------------------------------------------------------------------------
def fit_summary_table(fits: Mapping[str, FitResult | None],
                      reference_rms: Mapping[str, tuple[float, float]] | None = None,
                      night_sun_max_deg: float = NIGHT_SUN_MAX_DEG) -> Table:
    """Table 2 style: per fit A-F, the data, N, used, xel/el/sky rms (arcsec), and the
    published xel/el rms if ``reference_rms`` is given; fit E's night is the Sun below
    ``night_sun_max_deg``."""
    header = ["fit", "data", "N", "used", "xel rms (\")", "el rms (\")", "sky rms (\")"]
    if reference_rms:
        header += ["report xel rms (\")", "report el rms (\")"]
    rows = []
    for v in VARIANTS:
        fit = fits.get(v.name)
        ref = list(reference_rms.get(v.name, (None, None))) if reference_rms else []
        if fit is None and v.thermal:
            continue  # fit T only where thermal terms can be driven
        if fit is None:
            rows.append([v.name, v.describe(night_sun_max_deg), None, None, None, None, None,
                         *ref])
        else:
            rows.append([v.name, v.describe(night_sun_max_deg), fit.n_input, fit.n_used,
                         float(fit.xel_rms_arcsec), float(fit.el_rms_arcsec),
                         float(fit.sky_rms_arcsec), *ref])
    return Table(header, rows, caption="Residuals of the fits (the 1990 report's Table 2)")


def coefficient_table(fits: Mapping[str, FitResult | None],
                      reference: Reference | None = None) -> Table:
    """Table 3 style: coefficients (arcsec) of each fit present, fit A's TPOINT sigma and
    honest sigma, and the document's value and standard error (its arcmin times 60) beside
    them when ``reference`` is given."""
    present = [v.name for v in VARIANTS if fits.get(v.name) is not None]
    if not present:
        return Table(["term"], [], caption="Coefficients: no fit had enough observations")
    names = fits[present[0]].names
    fit_a = fits.get("A")
    terms = dict(reference.terms) if reference is not None else {}
    labels = dict(reference.labels) if reference is not None else {}
    honest = fit_a.sigma_honest_arcsec if fit_a is not None else None
    rows = []
    for j, term in enumerate(names):
        row: list[Any] = [term]
        for p in present:
            fit = fits[p]
            row.append(float(fit.values_arcsec[fit.names.index(term)])
                       if term in fit.names else None)
        row.append(float(fit_a.sigma_arcsec[j]) if fit_a is not None else None)
        row.append(float(honest[j]) if honest is not None else None)
        if terms:
            value, se = terms.get(term, (None, None))
            row += [_arcsec(value), _arcsec(se)] + ([labels.get(term, "")] if labels else [])
        rows.append(row)
    header = ["term", *(f"fit {p} (\")" for p in present), "TPOINT sigma A (\")",
              "honest sigma A (\")"]
    if terms:
        header += [f"{reference.column} (\")", f"{reference.column} s.e. (\")"] \
            + (["its name"] if labels else [])
    caption = (f"Coefficients (arcsec; the 1990 report's Table 3). Sign: "
               f"{sign_convention(names)}")
    if honest is not None:
        caption += (f". Honest sigma: a jackknife over {fit_a.honest_clusters_words}, "
                    "widened for its degrees of freedom (docs/outputs.md)")
    if terms:
        caption += f". Beside them {reference.citation}'s, its arcmin times 60"
    return Table(header, rows, caption=caption, number_format="+.2f")


def _arcsec(arcmin: float | None) -> float | None:
    return None if arcmin is None else 60.0 * arcmin


def thermal_table(fit: FitResult, truth_arcsec: Mapping[str, float] | None = None) -> Table:
    """Fit T's thermal terms: value and honest sigma (arcsec per kelvin of structure
    temperature difference, or per unit of a proxy), and the truth where it is known."""
    honest = (fit.sigma_honest_arcsec if fit.sigma_honest_arcsec is not None
              else [math.nan] * len(fit.names))
    rows = []
    for name, value, h in zip(fit.names, fit.values_arcsec, honest, strict=True):
        term = get_term(name)
        if term.kind != "thermal":
            continue
        truth = (truth_arcsec or {}).get(name)
        rows.append([name, term.description, float(value), float(h),
                     *([truth] if truth_arcsec else [])])
    header = ["term", "meaning", "fit T", "honest sigma", *(["truth"] if truth_arcsec else [])]
    return Table(header, rows, number_format="+.2f",
                 caption="Fit T's thermal terms (arcsec per kelvin of the temperature "
                         "difference, or per unit of a proxy)")


def source_points_table(points: Mapping[str, int], reference: Reference | None) -> Table:
    """Table 1 style: the points per source fit A used, beside the document's."""
    report = dict(reference.source_points) if reference is not None else {}
    names = list(report) + [n for n in points if n not in report]
    rows = [[n, points.get(n, 0), *([report[n]] if report else [])] for n in names]
    rows.append(["all", sum(points.values()), *([sum(report.values())] if report else [])])
    return Table(["source", "fit A", *([f"{reference.column}"] if report else [])], rows,
                 caption="Points per source in fit A (the 1990 report's Table 1)"
                         + (f", beside {reference.citation}'s" if report else ""))


def truth_pull_table(fit: FitResult, truth_arcsec: Mapping[str, float],
                     caption: str = "Coefficients against the injected truth") -> Table:
    """Fitted coefficients against a truth (arcsec; the recoverable one where
    ``truth.json`` has it, :func:`recoverable_terms_arcsec`) with pulls
    (fit - truth) / sigma, for TPOINT's sigma and the honest (cluster-robust) one."""
    honest = (fit.sigma_honest_arcsec if fit.sigma_honest_arcsec is not None
              else [math.nan] * len(fit.names))
    rows, highlight = [], set()
    for i, (name, value, sigma, h) in enumerate(zip(fit.names, fit.values_arcsec,
                                                    fit.sigma_arcsec, honest, strict=True)):
        truth = truth_arcsec.get(name)
        diff = float(value) - truth if truth is not None else math.nan
        pull_t = diff / float(sigma) if truth is not None and sigma > 0 else math.nan
        pull_h = diff / float(h) if truth is not None and h > 0 else math.nan
        for j, pull in ((5, pull_t), (7, pull_h)):
            if math.isfinite(pull) and abs(pull) > PULL_WARN:
                highlight.add((i, j))
        rows.append([name, truth, float(value), diff, float(sigma), pull_t, float(h), pull_h])
    return Table(["term", "truth (\")", "fit (\")", "fit \N{MINUS SIGN} truth (\")",
                  "TPOINT sigma (\")", "pull (TPOINT)", "honest sigma (\")", "pull (honest)"],
                 rows, caption=caption, number_format=".2f",
                 highlight=frozenset(highlight))


def _correlation_table(fit: FitResult) -> Table:
    names = list(fit.names)
    rows = [[n, *(float(x) for x in fit.correlation[i])] for i, n in enumerate(names)]
    highlight = {(i, j + 1) for i in range(len(names)) for j in range(len(names))
                 if i != j and abs(fit.correlation[i][j]) > 0.95}
    return Table(["", *names], rows, caption="Correlations of fit A's coefficients",
                 number_format="+.2f", highlight=frozenset(highlight))


# ---------------------------------------------------------------------------------------------
# the report of a run
# ---------------------------------------------------------------------------------------------
def truth_terms_arcsec(truth: Mapping[str, Any] | None) -> dict[str, float]:
    """``{term: value_arcsec}`` from a ``truth.json`` document (empty when absent)."""
    if not truth:
        return {}
    return {k: float(v["value_arcsec"]) for k, v in truth.get("terms", {}).items()}


def recoverable_terms_arcsec(truth: Mapping[str, Any] | None) -> dict[str, float]:
    """``{term: value_arcsec}`` of a ``truth.json`` document's recoverable truth (the mount's
    terms plus what the fit makes of the uncorrected refraction, the heating and the
    repeatable irregularities: :mod:`antsim.simulate.equivalents`), the mount's terms
    (:func:`truth_terms_arcsec`) for a document without one."""
    if not truth or "recoverable" not in truth:
        return truth_terms_arcsec(truth)
    return {k: float(v["value_arcsec"]) for k, v in truth["recoverable"]["terms"].items()}


def recoverable_words(truth: Mapping[str, Any] | None) -> str:
    """One sentence saying what the truth a fit is compared with holds."""
    if truth and "recoverable" in truth:
        return f"The truth here is {truth['recoverable']['about']} (truth.json's recoverable)."
    return "The truth here is the mount's injected terms."


def thermal_truth_arcsec(truth: Mapping[str, Any] | None) -> dict[str, float]:
    """``{thermal term: value}`` from a ``truth.json`` document's ``thermal_terms`` (the
    simulated thermal effect's coefficients in the thermal terms' units), empty when absent."""
    if not truth:
        return {}
    return {k: float(v) for k, v in truth.get("thermal_terms", {}).items()}


def write_run_report(result: RunResult, fits: Mapping[str, FitResult | None],
                     out_dir: str | Path | None = None, in_use: Pointing | None = None
                     ) -> tuple[Path, list[FigureFile]]:
    """Figures (``DIR/figures/``) and ``DIR/report.html`` of a run; returns both. ``in_use``:
    how well the model in use pointed (:mod:`antsim.run.inuse`)."""
    out = Path(out_dir if out_dir is not None else result.out_dir)
    scenario = result.scenario
    truth = truth_terms_arcsec(result.truth)
    document = reference_for(scenario.name)
    reference = dict(document.table2) if document is not None and document.table2 else None
    figures = report_figures(result, fits, out / "figures")
    good = sum(1 for r in result.rows if r["polarization"] == "AVG" and r["good"])
    fit_a = fits.get("A")
    summary = (f"{scenario.description or scenario.name}. Campaign of "
               f"{scenario.duration_s / 3600:.1f} h from {scenario.epoch_utc} UTC, seed "
               f"{result.seed}: {result.n_scans} cross scans, {good} reduced without flags. "
               f"Pointing model in use: {result.model.name} ({len(result.model)} terms).")
    if fit_a is not None:
        summary += (f" Fit A ({fit_a.model.name}) used {fit_a.n_used} of {fit_a.n_input} "
                    f"scans: xel rms {fit_a.xel_rms_arcsec:.1f}\", el rms "
                    f"{fit_a.el_rms_arcsec:.1f}\", sky rms {fit_a.sky_rms_arcsec:.1f}\".")
    else:
        summary += " Too few observations for fit A."
    if in_use is not None:
        summary += f" The {in_use.line()[:1].lower()}{in_use.line()[1:]}."
    summary += (" Every angle on this page is in arcsec; the offsets are corrections to "
                "apply, indicated minus true.")
    sections = [Section("Summary", [Paragraph(summary), Paragraph(
        "Files in this directory: recordings.ecsv (one row per scan and polarization), "
        "truth.json (the injected truth), fit.json and fit_variants.json (the fits), fit.txt "
        "(these tables as text), model.dat (fit A as a TPOINT model, usable as antsim run "
        "--model), figures/ (the figures below as PNG files).")])]
    fit_blocks: list[Block] = [
        fit_summary_table(fits, reference, scenario.controller.night_sun_max_deg),
        coefficient_table(fits, document)]
    points = points_per_source(result.rows, fit_a)
    if points:
        fit_blocks.append(source_points_table(points, document))
    if reference:
        fit_blocks.append(Paragraph(
            "The report columns are the 1990 report's Tables 1-3 (Ghigo 1990) for the same "
            "selections of the real 24-hour run of 8-9 February 1990."))
    if document is not None and document.rms_arcsec is not None:
        fit_blocks.append(Paragraph(
            f"{document.citation}: rms deviation of a data point from the best fit "
            f"{document.rms_arcsec[0]:.1f}\" in azimuth (dA cos E) and "
            f"{document.rms_arcsec[1]:.1f}\" in elevation."))
    fit_t = fits.get("T")
    if fit_t is not None:
        fit_blocks += [thermal_table(fit_t, thermal_truth_arcsec(result.truth) or None),
                       Paragraph("Fit T: " + " ".join(fit_t.notes))]
    sections.append(Section("Fits A-F" + (" and T" if fit_t is not None else ""), fit_blocks))
    if fit_a is not None and truth:
        effects = [e.get("effect", "?") for e in (result.truth or {}).get("effects", [])]
        text = ("Pull = (fit - truth) / sigma. With independent Gaussian residuals pulls "
                "scatter with unit standard deviation. TPOINT's sigma assumes independent "
                "residuals; the honest sigma allows for residuals correlated in time "
                f"(a jackknife over {fit_a.honest_clusters_words}, widened for its few "
                "degrees of freedom), "
                "so its pulls are the ones to trust. "
                f"Cells above {PULL_WARN:g} are highlighted.")
        if effects:
            text += (" The truth also holds effects the fitted model has no terms for ("
                     + ", ".join(effects) + "): "
                     + ("those the recoverable truth does not count bias some coefficients."
                        if "recoverable" in (result.truth or {})
                        else "they bias some coefficients."))
        recoverable = recoverable_terms_arcsec(result.truth)
        caption = ("Coefficients against the recoverable truth" if "recoverable"
                   in (result.truth or {}) else "Coefficients against the injected truth")
        sections.append(Section("Coefficients against the truth", [
            Paragraph(recoverable_words(result.truth)),
            truth_pull_table(fit_a, recoverable, caption), Paragraph(text)]))
    if fit_a is not None:
        blocks: list[Block] = [Paragraph(
            f"Condition number {fit_a.condition_number:.3g}; Popn SD "
            f"{fit_a.popn_sd_arcsec:.1f}\"."
            + (" Unconstrained: " + ", ".join(fit_a.unconstrained) + "."
               if fit_a.unconstrained else ""))]
        if fit_a.warnings:
            blocks.append(Paragraph("\n\n".join(f"Warning: {w}" for w in fit_a.warnings)))
        blocks.append(_correlation_table(fit_a))
        sections.append(Section("Fit A: warnings and correlations", blocks))
    sections.append(Section("Figures", [Figure.of(f) for f in figures]))
    sections.append(Section("Scenario", [Preformatted(scenario.text or "(no scenario text)",
                                                      caption=str(Path(scenario.path).name))]))
    path = write_report(out / "report.html", f"antsim run: {scenario.name}, seed {result.seed}",
                        sections, subtitle=scenario.description)
    return path, figures


def report_figures(result: RunResult, fits: Mapping[str, FitResult | None],
                   figures_dir: str | Path) -> list[FigureFile]:
    """The figures of a run's report (:func:`antsim.figures.run.run_figures`) into
    ``figures_dir``, with the truth, the published rms, the gain curve and the model in use
    of the run ``result`` (its calibration set by :func:`antsim.run.outputs.run_products`)."""
    scenario = result.scenario
    truth = truth_terms_arcsec(result.truth)
    document = reference_for(scenario.name)
    reference = dict(document.table2) if document is not None and document.table2 else None
    return run_figures(result.rows, fits, figures_dir, truth_arcsec=truth or None,
                       name=scenario.name, start_label=f"UTC {scenario.epoch_utc}",
                       el_limit_deg=scenario.controller.scheduler.elevation_min_deg,
                       reference_rms=reference, gain_fit=_elevation_gain_fit(result),
                       model_in_use=result.model.name if len(result.model) else None)


def _elevation_gain_fit(result: RunResult):
    """The run's fitted elevation gain curve (controller.scans.gaincurve), if one was fitted."""
    calibration = getattr(result, "calibration", None)
    fit = getattr(calibration, "fit", None)
    return fit if hasattr(fit, "knots_deg") else None

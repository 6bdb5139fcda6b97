"""Files written after a campaign: the fits, their tables, the fitted model.

``fit.json`` (fit A, in the ``antsim fit --json`` schema), ``fit_variants.json`` (fits A-F),
``fit.txt`` (tables in the style of the 1990 report's Tables 2 and 3) and ``model.dat`` (fit
A as a TPOINT ``.mod`` file, usable as ``antsim run --model DIR/model.dat``). Where there are
calibrators (:func:`controller.scans.gaincurve.calibrate`), ``gaincurve.json``: the zenith opacity
(tipping scans or the scans' own off-source powers) and the fitted gain curve.
"""

from __future__ import annotations

import json
import math
import shutil
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from antsim.documents import Reference, reference_for
from antsim.outdir import write_file
from antsim.progress import Progress
from antsim.simulate.runner import RunResult
from controller.astro.sun import NIGHT_SUN_MAX_DEG
from controller.pointing.modelio import write_model_file
from controller.pointing.result import FitResult
from controller.pointing.signs import UNITS, sign_convention
from controller.pointing.terms import get_term
from controller.pointing.tpoint import TPointModel
from controller.pointing.variants import VARIANTS, fit_variants
from controller.scans.gaincurve import calibrate

from .inuse import Pointing, pointing_in_use
from .report import write_run_report
from .sources import points_per_source

__all__ = ["PRODUCTS", "RunProducts", "clear_products", "fit_tables", "model_caption",
           "run_fits", "run_products", "write_outputs"]


def run_fits(result: RunResult) -> dict[str, FitResult | None]:
    """Fits A-F of a run's recordings with the terms its controller fits."""
    c = result.scenario.controller
    terms, name = c.fit_spec()
    context = {"site": {"latitude_deg": c.site_latitude_deg,
                        "longitude_deg": c.site_longitude_deg, "height_m": c.site_height_m},
               "epoch_utc": c.epoch_utc, "sensor_lag_s": c.structure_lag_s}
    return fit_variants(result.rows, terms, name=name, night_sun_max_deg=c.night_sun_max_deg,
                        fixed=dict(c.fit_fixed), context=context)


def _fmt(value: float, spec: str) -> str:
    return format(value, spec) if value is not None and math.isfinite(value) else "-"


def fit_tables(fits: dict[str, FitResult | None], title: str,
               night_sun_max_deg: float = NIGHT_SUN_MAX_DEG,
               reference: Reference | None = None,
               points: Mapping[str, int] | None = None,
               in_use: Pointing | None = None) -> str:
    """Text tables in the style of the report's Table 2 (rms per fit) and Table 3 (terms),
    with the document's numbers beside ours when ``reference`` is given, and the points
    per source in fit A (Table 1) when ``points`` is; fit E's night is the Sun below
    ``night_sun_max_deg``. Units and sign head the tables, then ``in_use``: how well the
    model in use pointed."""
    ref_t2 = dict(reference.table2) if reference is not None else {}
    names = next((f.names for f in fits.values() if f is not None), ())
    lines = [title, f"Units: {UNITS} in every table. Sign of the coefficients: "
             f"{sign_convention(names)}.",
             *([in_use.line()[:1].upper() + in_use.line()[1:] + "."] if in_use else []),
             "", "Table 2. Residuals of the fits (arcsec)"
             + (f"; {reference.citation}, Table 2, beside them" if ref_t2 else ""), "",
             f"{'fit':<4}{'data':<48}{'N':>5}{'used':>6}{'xel rms':>9}{'el rms':>8}"
             f"{'sky rms':>9}" + (f"{'report N':>10}{'xel':>6}{'el':>6}" if ref_t2 else "")]
    for v in VARIANTS:
        fit = fits.get(v.name)
        ref = ""
        if v.name in ref_t2:
            ref = (f"{reference.points.get(v.name, 0):>10d}{ref_t2[v.name][0]:>6.0f}"
                   f"{ref_t2[v.name][1]:>6.0f}")
        if fit is None:
            if not v.thermal:  # fit T only where thermal terms can be driven
                lines.append(f"{v.name:<4}{v.describe(night_sun_max_deg):<48}"
                             f"{'(too few observations)':>30}")
            continue
        lines.append(f"{v.name:<4}{v.describe(night_sun_max_deg):<48}{fit.n_input:>5}"
                     f"{fit.n_used:>6}"
                     f"{fit.xel_rms_arcsec:>9.1f}{fit.el_rms_arcsec:>8.1f}"
                     f"{fit.sky_rms_arcsec:>9.1f}{ref}")
    if reference is not None and reference.rms_arcsec is not None:
        xel, el = reference.rms_arcsec
        lines.append(f"{'':<4}{reference.citation + ': rms per point':<69}"
                     f"{xel:>9.1f}{el:>8.1f}")
    present = [v.name for v in VARIANTS if fits.get(v.name) is not None]
    if present:
        lines += _coefficient_lines(fits, present, reference)
    if points:
        lines += _points_lines(points, reference)
    warnings = fits["A"].warnings if fits.get("A") is not None else ()
    lines += [""] + [f"fit A: {w}" for w in warnings]
    if fits.get("T") is not None:
        lines += _thermal_lines(fits["T"]) + [f"fit T: {n}" for n in fits["T"].notes]
    return "\n".join(lines).rstrip() + "\n"


def _coefficient_lines(fits, present: list[str], reference: Reference | None) -> list[str]:
    names = fits[present[0]].names
    terms = dict(reference.terms) if reference is not None else {}
    labels = dict(reference.labels) if reference is not None else {}
    fit_a = fits.get("A")
    fixed = fit_a.fixed if fit_a is not None else ()
    honest = fit_a.sigma_honest_arcsec if fit_a is not None else None
    jackknife = (f"jackknife over {fit_a.honest_clusters_words}" if honest is not None
                 else "jackknife")
    lines = ["", "Table 3. Coefficients (arcsec); fit A's sigma, TPOINT's and the honest one "
             f"({jackknife})" + (f"; {reference.citation} beside them, its arcmin times 60"
                                 if terms else ""), "",
             f"{'term':<8}" + "".join(f"{'fit ' + p:>10}" for p in present)
             + f"{'sigma A':>10}{'honest A':>10}"
             + (f"{reference.column:>10}{'s.e.':>7}" if terms else "")]
    for j, term in enumerate(names):
        row = f"{term:<8}"
        for p in present:
            row += f"{_fmt(fits[p].values_arcsec[j], '+.2f'):>10}"
        if term in fixed:
            row += f"{'fixed':>10}{'':>10}"
        else:
            sigma = fit_a.sigma_arcsec[j] if fit_a is not None else math.nan
            row += (f"{_fmt(sigma, '.2f'):>10}"
                    f"{_fmt(honest[j] if honest is not None else math.nan, '.2f'):>10}")
        if term in terms:
            value, se = terms[term]
            row += (f"{60.0 * value:>+10.1f}"
                    f"{_fmt(60.0 * se if se is not None else math.nan, '.1f'):>7}  "
                    f"{labels.get(term, ''):<10}")
        lines.append(row.rstrip())
    return lines


def _thermal_lines(fit: FitResult) -> list[str]:
    """Fit T's thermal terms: value and honest sigma (arcsec per kelvin, or per unit of a
    proxy)."""
    honest = fit.sigma_honest_arcsec
    lines = ["", "Thermal terms of fit T (arcsec per kelvin of the difference, or per unit of "
             "a proxy); honest sigma", ""]
    for j, name in enumerate(fit.names):
        term = get_term(name)
        if term.kind == "thermal":
            lines.append(f"{name:<8}{fit.values_arcsec[j]:>+10.2f}{_fmt(honest[j], '.2f'):>8}  "
                         f"{term.description}")
    return [*lines, ""]


def _points_lines(points: Mapping[str, int], reference: Reference | None) -> list[str]:
    report = dict(reference.source_points) if reference is not None else {}
    lines = ["", "Table 1. Points per source in fit A"
             + (f"; {reference.citation}, Table 1, beside them" if report else ""), "",
             f"{'source':<16}{'fit A':>6}" + (f"{reference.column:>8}" if report else "")]
    for name in list(report) + [n for n in points if n not in report]:
        lines.append(f"{name:<16}{points.get(name, 0):>6d}"
                     + (f"{report[name]:>8d}" if name in report else ""))
    lines.append(f"{'all':<16}{sum(points.values()):>6d}"
                 + (f"{sum(report.values()):>8d}" if report else ""))
    return lines


#: every file (and folder) ``antsim run`` may write into its output directory
PRODUCTS = ("recordings.ecsv", "truth.json", "fit.json", "fit_variants.json", "fit.txt",
            "model.dat", "gaincurve.json", "report.html", "figures")


def clear_products(out: Path, keep: tuple[str, ...] = ("recordings.ecsv", "truth.json")) -> None:
    """Remove an earlier run's products from ``out`` (all but ``keep``), so that a resumed run
    leaves only what it wrote itself: no stale ``model.dat`` beside recordings that can no
    longer be fitted."""
    for name in PRODUCTS:
        path = out / name
        if name in keep or not (path.exists() or path.is_symlink()):
            continue
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path)
        else:
            path.unlink()


@dataclass
class RunProducts:
    """What a run's files hold, computed once (:func:`run_products`): fits A-F (None where
    too few observations), how the model in use pointed (None without a good scan), the
    text of ``fit.txt`` and the command's summary (without the files written). The run's
    gain curve and opacity are set on the run itself (``RunResult.calibration``)."""

    fits: dict[str, FitResult | None]
    in_use: Pointing | None
    tables: str
    summary: str

    @property
    def fit_a(self) -> FitResult | None:
        return self.fits.get("A")


def run_products(result: RunResult, progress: Progress | None = None) -> RunProducts:
    """The fits, tables and summary of a run, and its calibration (set on ``result``);
    ``progress``: the command's, told the stage."""
    if progress is not None:
        progress.stage("fits A-F")
    fits = run_fits(result)
    fit_a = fits.get("A")
    result.calibration = calibrate(result.rows, result.scenario.controller, result.tippings)
    what = "star offsets" if result.scenario.controller.method == "optical" else "cross scans"
    title = (f"{result.scenario.name}, seed {result.seed}: {result.n_scans} {what}, "
             f"model in use {result.model.name}")
    reference = reference_for(result.scenario.name)
    in_use = pointing_in_use(result.rows, result.model)
    tables = fit_tables(fits, title, result.scenario.controller.night_sun_max_deg, reference,
                        points_per_source(result.rows, fit_a), in_use)
    good = sum(1 for r in result.rows if r["polarization"] == "AVG" and r["good"])
    summary = (f"{result.scenario.name}: {result.n_scans} {what} ({good} good) in "
               f"{result.scenario.duration_s / 3600:.1f} h, seed {result.seed}")
    if fit_a is not None:
        summary += (f"; fit A: {fit_a.n_used} points, xel rms {fit_a.xel_rms_arcsec:.1f}\", "
                    f"el rms {fit_a.el_rms_arcsec:.1f}\"")
    else:
        terms, _ = result.scenario.controller.fit_spec()
        summary += (f"; no fit A: {good} good {what} for {len(terms)} terms, too few "
                    "(fit.json and model.dat not written)")
    if in_use is not None and in_use.ratio is not None:
        summary += "\n" + in_use.line()
    return RunProducts(fits, in_use, tables, summary)


def model_caption(result: RunResult) -> str:
    """The caption of ``model.dat`` (and so the name of the model read back from it)."""
    return f"{result.scenario.name} seed {result.seed}: fit A"


def write_outputs(result: RunResult, report: bool = True,
                  progress: Progress | None = None,
                  products: RunProducts | None = None) -> str:
    """Write the products of a run into its output directory; return a short summary that
    names exactly the files written. With ``report`` also the figures (``figures/``) and
    ``report.html`` (:mod:`antsim.run.report`); ``progress``: the command's, told each
    stage; ``products``: :func:`run_products` of the run where already computed."""
    out = Path(result.out_dir)
    written = ["recordings.ecsv"] + (["truth.json"] if result.truth else [])
    if products is None:
        products = run_products(result, progress)
    fits, fit_a = products.fits, products.fit_a
    doc = {k: (v.to_json() if v is not None else None) for k, v in fits.items()}
    write_file(out / "fit_variants.json", json.dumps(doc, indent=2) + "\n")
    if fit_a is not None:
        write_file(out / "fit.json", json.dumps(fit_a.to_json(), indent=2) + "\n")
        write_model_file(TPointModel.from_fit(fit_a, caption=model_caption(result)),
                         out / "model.dat")
        written += ["fit.json"]
    written += ["fit_variants.json"]
    write_file(out / "fit.txt", products.tables)
    written += ["fit.txt"] + (["model.dat"] if fit_a is not None else [])
    if result.calibration is not None:
        write_file(out / "gaincurve.json",
                   json.dumps(result.calibration.to_json(), indent=2) + "\n")
        written += ["gaincurve.json"]
    if report:
        if progress is not None:
            progress.stage("figures and report")
        _, figures = write_run_report(result, fits, out, products.in_use)
        written += ["report.html", f"figures/ ({len(figures)} figures)"]
    return products.summary + f"\nwrote {out}/: {' '.join(written)}"

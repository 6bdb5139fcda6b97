"""``antsim.run_campaign``: a campaign simulated, reduced and fitted as ``antsim run`` does
it, and :class:`Campaign`, what it produced: the fits A-F, the truth, how the model in use
pointed, and the report's figures."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any

import astropy.units as u
import numpy as np
from astropy.table import Table as AstropyTable

from antsim.bundled import find
from antsim.figures.html import Table
from antsim.outdir import held_output_dir
from antsim.progress import Progress
from antsim.run.campaign import check_seed, model_in_use, refuse_earlier_run
from antsim.run.outputs import model_caption, run_products, write_outputs
from antsim.run.report import (
    recoverable_terms_arcsec,
    report_figures,
    truth_terms_arcsec,
)
from antsim.scenario import load_scenario
from antsim.simulate.runner import run_campaign as run_into
from antsim.simulate.runner import simulate
from controller.errors import InputError
from controller.pointing.variants import VARIANTS, columns, pointing_data, variant_mask

from .fit import Fit
from .show import ShownAsTable, arcsec, drawn, figure_of

if TYPE_CHECKING:
    from astropy.table import QTable
    from astropy.units import Quantity

    from antsim.run.inuse import Pointing
    from antsim.run.outputs import RunProducts
    from antsim.simulate.runner import RunResult

__all__ = ["Campaign", "recordings_file", "run_campaign"]

#: the report's figures by name (their files' stems in ``DIR/figures``), for the plot methods
REPORT_FIGURES = {
    "sky": "fig1_sky", "errors": "fig2_total_errors", "model_in_use": "fig_model_in_use",
    "residuals": "fig3_residuals", "amplitude": "fig4_amplitude",
    "residual_sky": "fig5_residual_quiver", "histograms": "fig6_residual_histograms",
    "residuals_time": "fig7_residuals_time", "against_truth": "fig8_coefficients",
    "sigmas": "fig9_term_sigmas", "rms": "fig10_fit_rms"}


@dataclass(repr=False)
class Campaign(ShownAsTable):
    """A campaign run (:func:`run_campaign`): the simulation's result (``run``, its rows
    as recorded), what its files hold (``products``: fits A-F, ``fit.txt``, the summary)
    and the directory written (``out``, None when nothing was written).

    Angles are :class:`astropy.units.Quantity` in arcsec; pointing errors are "indicated
    minus true". The documents are the files' own: :meth:`fit_json` is ``fit.json``,
    :meth:`fit_variants_json` ``fit_variants.json``, :attr:`truth` ``truth.json``."""

    run: RunResult
    products: RunProducts
    out: Path | None = None
    summary_text: str = ""
    _figures: dict[str, Any] | None = field(default=None, init=False)

    # ----------------------------------------------------------------- what was run
    @property
    def scenario(self) -> str:
        """The scenario's name."""
        return self.run.scenario.name

    @property
    def seed(self) -> int:
        return int(self.run.seed)

    @property
    def model_in_use(self) -> str:
        """The name of the pointing model the controller used."""
        return str(self.run.model.name)

    @property
    def duration(self) -> Quantity:
        """The campaign's length (hours)."""
        return self.run.scenario.duration_s / 3600.0 * u.h

    @property
    def n_scans(self) -> int:
        return int(self.run.n_scans)

    @property
    def n_good(self) -> int:
        """Scans reduced without a flag (the averaged polarization's)."""
        return sum(1 for r in self.run.rows if r["polarization"] == "AVG" and r["good"])

    @property
    def recordings_path(self) -> Path | None:
        """``recordings.ecsv`` where the campaign was written (None: not written)."""
        return None if self.out is None else self.out / "recordings.ecsv"

    def recordings(self) -> AstropyTable:
        """The rows recorded (one per scan and polarization), as an astropy Table whose
        column names carry their units (as ``recordings.ecsv``'s)."""
        rows = self.run.rows
        return AstropyTable(rows=[[r[k] for k in rows[0]] for r in rows],
                     names=list(rows[0])) if rows else Table()

    # ----------------------------------------------------------------- the fits
    @cached_property
    def fits(self) -> dict[str, Fit | None]:
        """Fits A-F (and T with structure thermometers) of the 1990 report's variants, as
        ``fit_variants.json`` holds them; None where too few observations."""
        cols = columns(self.run.rows)
        out: dict[str, Fit | None] = {}
        for variant in VARIANTS:
            fit = self.products.fits.get(variant.name)
            if variant.name not in self.products.fits:
                continue
            mask = variant_mask(cols, variant)
            out[variant.name] = None if fit is None else Fit(
                fit, pointing_data(cols, mask),
                source=f"{self.scenario} seed {self.seed}, fit {variant.name}",
                caption=model_caption(self.run) if variant.name == "A" else
                f"{self.scenario} seed {self.seed}: fit {variant.name}",
                sun_el_deg=np.asarray(cols["sun_el_deg"], dtype=float)[mask])
        return out

    @property
    def fit(self) -> Fit | None:
        """Fit A (every good scan, both polarizations averaged): the run's ``fit.json``
        and ``model.dat`` (None where too few observations)."""
        return self.fits.get("A")

    def fit_json(self) -> dict[str, Any] | None:
        """``fit.json``: fit A as ``antsim fit --json`` prints a fit."""
        fit = self.products.fit_a
        return None if fit is None else fit.to_json()

    def fit_variants_json(self) -> dict[str, Any]:
        """``fit_variants.json``: every fit, None where too few observations."""
        return {k: (v.to_json() if v is not None else None)
                for k, v in self.products.fits.items()}

    @property
    def tables(self) -> str:
        """``fit.txt``: the fits in the style of the 1990 report's Tables 1-3."""
        return self.products.tables

    @property
    def summary(self) -> str:
        """What ``antsim run`` prints (with the files written, when written)."""
        return self.summary_text or self.products.summary

    # ----------------------------------------------------------------- the truth
    @property
    def truth(self) -> dict[str, Any]:
        """``truth.json``: the injected pointing terms and effects."""
        return self.run.truth

    @property
    def truth_terms(self) -> dict[str, Quantity]:
        """The injected value of each term of the truth model (arcsec)."""
        return {k: arcsec(v) for k, v in truth_terms_arcsec(self.run.truth).items()}

    @property
    def recoverable_terms(self) -> dict[str, Quantity]:
        """The recoverable truth of each fitted term (arcsec): the mount's terms plus what
        the fit makes of the uncorrected refraction, the heating and the repeatable
        irregularities (``truth.json``'s ``recoverable``; the mount's terms without it)."""
        return {k: arcsec(v) for k, v in recoverable_terms_arcsec(self.run.truth).items()}

    def pulls(self) -> QTable:
        """Fit A against the recoverable truth (:attr:`recoverable_terms`, :meth:`Fit.pulls`),
        as the report's table: the mount's terms plus what the fit makes of the uncorrected
        refraction, the heating and the repeatable irregularities. A term without a truth
        has no pull."""
        if self.fit is None:
            raise ValueError(f"campaign {self.scenario} seed {self.seed} has no fit A "
                             "(too few observations)")
        return self.fit.pulls(self.recoverable_terms)

    # ----------------------------------------------------------------- the model in use
    @property
    def in_use(self) -> Pointing | None:
        """How the model in use pointed (:class:`antsim.run.inuse.Pointing`: its Sky RMS
        over the good scans and the fit it came from), None without a good scan."""
        return self.products.in_use

    @property
    def in_use_sky_rms(self) -> Quantity | None:
        """The Sky RMS of the pointing errors left by the model in use (arcsec)."""
        return None if self.in_use is None else arcsec(self.in_use.sky_rms_arcsec)

    # ----------------------------------------------------------------- the figures
    def figures(self) -> dict[str, Any]:
        """The report's figures (matplotlib Figures drawn by :mod:`antsim.figures.run`, as
        ``report.html`` shows them), by the name of their file in ``DIR/figures``
        ("fig1_sky", "fig2_total_errors", ...); drawn once, kept."""
        if self._figures is None:
            self._figures = drawn(lambda folder: report_figures(
                self.run, self.products.fits, folder))
        return self._figures

    def plot(self, name: str):
        """One figure of the report by its name: "sky" (Fig. 1), "errors" (Fig. 2: total
        pointing errors), "model_in_use" (with a model in use), "residuals" (Fig. 3: after
        fit A), "amplitude" (Fig. 4), "residual_sky", "histograms", "residuals_time",
        "against_truth" (fits A-F minus the truth), "sigmas", "rms"; or a file stem."""
        return figure_of(self.figures(), REPORT_FIGURES.get(name, name), "this campaign")

    def plot_sky(self):
        """Fig. 1: where the antenna looked."""
        return self.plot("sky")

    def plot_errors(self):
        """Fig. 2a-d: the total pointing errors against elevation and azimuth."""
        return self.plot("errors")

    def plot_residuals(self):
        """Fig. 3a-d: the residuals after fit A against elevation and azimuth."""
        return self.plot("residuals")

    def plot_against_truth(self):
        """The coefficients of fits A-F minus the injected truth, with honest sigmas."""
        return self.plot("against_truth")

    def plot_model_in_use(self):
        """The pointing errors with the model in use and without it."""
        return self.plot("model_in_use")

    def _table(self) -> Table:
        fit = self.products.fit_a
        rows: list[list[Any]] = [
            ["scenario", self.scenario], ["seed", self.seed],
            ["campaign (h)", f"{self.run.scenario.duration_s / 3600:.1f}"],
            ["scans (good)", f"{self.n_scans} ({self.n_good})"],
            ["model in use", self.model_in_use]]
        if self.in_use is not None:
            rows.append(["Sky RMS with the model in use (\")",
                         f"{self.in_use.sky_rms_arcsec:.1f}"])
        if fit is not None:
            rows += [["fit A: observations used", f"{fit.n_used} of {fit.n_input}"],
                     ["fit A: xel / el / Sky RMS (\")",
                      f"{fit.xel_rms_arcsec:.1f} / {fit.el_rms_arcsec:.1f} / "
                      f"{fit.sky_rms_arcsec:.1f}"]]
        rows.append(["written to", str(self.out) if self.out is not None else "(nothing)"])
        return Table(["", ""], rows, caption="antsim campaign")


def run_campaign(scenario: str | os.PathLike, *, seed: int | None = None,
                 model: str | os.PathLike | Fit | Any | None = None,
                 out: str | os.PathLike | None = None, report: bool = True,
                 progress: bool | None = False) -> Campaign:
    """Simulate a campaign, reduce every scan and fit the 1990 report's variants A-F, as
    ``antsim run`` does.

    ``scenario``: a name (``antsim scenarios`` lists them, e.g. ``"ghigo1990"``) or a
    scenario file (TOML). ``seed``: the random seed (default: the scenario's). ``model``:
    the pointing model the controller uses: a named model (``"none"``, ``"ghigo10"``, ...),
    a ``model.dat``/``.mod`` file or a ``fit.json``, a :class:`Fit` (its model as its
    ``.mod`` file holds it: the closed loop, to the byte the command's with that file) or
    a :class:`~controller.pointing.model.PointingModel`; default the scenario's.
    ``out``: a directory to write what ``antsim run --out`` writes (recordings, truth, fits,
    ``model.dat``, with ``report`` the figures and ``report.html``); without it nothing is
    written. ``progress``: a progress bar on stderr (None: on a terminal only).

    Same scenario and seed, same numbers: the fits equal the ``fit.json`` and
    ``fit_variants.json`` the command writes. Bad input raises
    :class:`controller.errors.InputError` with the line ``antsim run`` prints."""
    check_seed(seed)
    loaded = load_scenario(find(os.fspath(scenario)))
    if isinstance(model, Fit):
        model = model.pointing_model()
    elif isinstance(model, os.PathLike):
        model = os.fspath(model)
    use = model_in_use(model, loaded)
    if out is None:
        with Progress("run", progress) as shown:
            hours = round(loaded.duration_s / 3600.0, 2)
            shown.stage("campaign", total=hours, unit="h")
            run = simulate(loaded, seed, use, progress=lambda t_s: shown.set(
                round(min(t_s, loaded.duration_s) / 3600.0, 2)))
            products = run_products(run, shown)
        return Campaign(run, products)
    with held_output_dir(os.fspath(out), "--out", "antsim.run_campaign") as directory:
        refuse_earlier_run(directory, resume=False)
        with Progress("run", progress) as shown:
            run = run_into(loaded, directory, seed=seed, model=use, show_progress=shown)
            products = run_products(run, shown)
            summary = write_outputs(run, report=report, progress=shown, products=products)
    return Campaign(run, products, out=directory, summary_text=summary)


def recordings_file(data: Any, function: str) -> str:
    """The file a function is given: a path, or a campaign written with ``out=``."""
    if isinstance(data, Campaign):
        if data.out is None:
            raise InputError(function, "data", f"campaign {data.scenario} seed {data.seed}",
                             "was run without out=, so it has no recordings file",
                             "run it with out=DIR, or give a file")
        return str(data.out / "recordings.ecsv")
    if isinstance(data, str | os.PathLike):
        return os.fspath(data)
    raise InputError(function, "data", type(data).__name__,
                     "must be a file (a path) or a campaign run with out=")

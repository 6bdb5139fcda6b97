"""A pointing model fitted (:class:`Fit`): its numbers as Quantities, its tables, its model
and its figures; what :func:`antsim.api.fit_model` returns, and a campaign's fits."""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from astropy.table import QTable

from antsim.figures.charts import (
    histogram_figure,
    pointing_errors_figure,
    residual_quiver_figure,
)
from antsim.figures.html import Table
from antsim.run.report import truth_pull_table
from controller.pointing.modelio import write_model_file
from controller.pointing.tpoint import TPointModel, format_mod, parse_mod
from controller.pointing.vocabulary import in_tpoint_terms

from .show import ShownAsTable, arcsec, as_arcsec, drawn, figure_of, formatted

if TYPE_CHECKING:
    from astropy.units import Quantity

    from controller.pointing.data import PointingData
    from controller.pointing.model import PointingModel
    from controller.pointing.result import FitResult

__all__ = ["Fit"]


@dataclass(frozen=True, repr=False)
class Fit(ShownAsTable):
    """A pointing model fitted: ``result`` (the fitter's
    :class:`~controller.pointing.result.FitResult`, plain floats in arcsec), the pointing
    ``data`` it fitted, what was fitted (``source``) and the caption of its model file.

    Angles are :class:`astropy.units.Quantity` in arcsec; errors are "indicated minus true"
    (the 1990 report's sign; TPOINT's corrections are their negative). ``to_json()`` is the
    document ``antsim fit --json`` prints and a run's ``fit.json`` holds."""

    result: FitResult
    data: PointingData
    source: str
    caption: str
    notes: tuple[str, ...] = ()
    #: the Sun's elevation at each observation (deg), where known: the figures colour day,
    #: twilight and night by it
    sun_el_deg: Any = None

    # ----------------------------------------------------------------- the numbers
    @property
    def names(self) -> tuple[str, ...]:
        """The fitted terms, in the fit's order."""
        return tuple(self.result.names)

    @property
    def values(self) -> Quantity:
        """The coefficients (arcsec), in the order of :attr:`names`."""
        return arcsec(self.result.values_arcsec)

    @property
    def sigma(self) -> Quantity:
        """TPOINT's sigma of each coefficient (scaled by the Sky RMS; arcsec)."""
        return arcsec(self.result.sigma_arcsec)

    @property
    def sigma_honest(self) -> Quantity | None:
        """The honest sigma of each coefficient (a cluster jackknife, :attr:`honest_words`;
        arcsec), None where the fit has none."""
        honest = self.result.sigma_honest_arcsec
        return None if honest is None else arcsec(honest)

    @property
    def honest_words(self) -> str:
        """What the honest sigma's clusters are ("observations within 3600 s time blocks")."""
        return self.result.honest_clusters_words

    @property
    def sky_rms(self) -> Quantity:
        """TPOINT's Sky RMS of the residuals (arcsec)."""
        return arcsec(self.result.sky_rms_arcsec)

    @property
    def xel_rms(self) -> Quantity:
        """The rms of the cross-elevation residuals (arcsec)."""
        return arcsec(self.result.xel_rms_arcsec)

    @property
    def el_rms(self) -> Quantity:
        """The rms of the elevation residuals (arcsec)."""
        return arcsec(self.result.el_rms_arcsec)

    @property
    def n_used(self) -> int:
        """Observations the fit used (after the robust stages' rejections)."""
        return int(self.result.n_used)

    @property
    def n_input(self) -> int:
        """Observations given to the fit."""
        return int(self.result.n_input)

    def coefficient(self, name: str) -> Quantity:
        """One coefficient by its term's name (arcsec)."""
        if name not in self.names:
            raise KeyError(f"{name} is not a term of this fit: {' '.join(self.names)}")
        return self.values[self.names.index(name)]

    def to_json(self) -> dict[str, Any]:
        """The fit as ``antsim fit --json`` prints it (a run's ``fit.json``)."""
        return self.result.to_json()

    def summary(self) -> str:
        """The fit as ``antsim fit`` prints it: TPOINT's statistics and the coefficients."""
        return self.result.summary()

    def coefficients(self) -> QTable:
        """A table of the coefficients: term, value, TPOINT's sigma, honest sigma (arcsec)."""
        honest = self.sigma_honest
        table = QTable({"term": list(self.names), "value": self.values, "sigma": self.sigma,
                        "sigma_honest": honest if honest is not None
                        else self.sigma * float("nan")})
        return formatted(table, ".2f")

    def pulls(self, truth: Mapping[str, Any]) -> QTable:
        """The coefficients against a truth (``{term: angle}``, Quantities or arcsec; e.g. a
        campaign's :attr:`~antsim.api.Campaign.recoverable_terms`), as the run's report tables
        them: truth, fit, fit minus truth, TPOINT's sigma and its pull, the honest sigma and
        its pull (pull = (fit - truth) / sigma). A term without a truth has no pull."""
        given = {name: as_arcsec(v, "truth", name) for name, v in truth.items()}
        rows = truth_pull_table(self.result, given).rows
        column = list(zip(*rows, strict=True)) if rows else [()] * 8

        def nan(values) -> list[float]:
            return [float("nan") if v is None else float(v) for v in values]

        table = QTable({"term": list(column[0]), "truth": arcsec(nan(column[1])),
                        "fit": arcsec(nan(column[2])),
                        "fit_minus_truth": arcsec(nan(column[3])),
                        "sigma": arcsec(nan(column[4])), "pull": nan(column[5]),
                        "sigma_honest": arcsec(nan(column[6])), "pull_honest": nan(column[7])})
        return formatted(table, ".2f")

    # ----------------------------------------------------------------- the model
    def pointing_model(self) -> PointingModel:
        """The fitted model as its TPOINT ``.mod`` file holds it (the file's precision and
        caption): what ``antsim run --model FILE`` reads back from :meth:`write_model`'s
        file, so a campaign pointed with it is the command's to the byte."""
        model = TPointModel.from_fit(self.result, caption=self.caption)
        return parse_mod(format_mod(in_tpoint_terms(model)), source=self.caption)

    def write_model(self, path: str | os.PathLike) -> Path:
        """Write the model as a TPOINT ``.mod`` file (TPOINT's term names and signs)."""
        return write_model_file(TPointModel.from_fit(self.result, caption=self.caption),
                                Path(path))

    # ----------------------------------------------------------------- the figures
    def figures(self) -> dict[str, Any]:
        """The fit's figures (matplotlib Figures, drawn by :mod:`antsim.figures.charts`):
        "residuals" (against elevation and azimuth, rejected points marked), "sky" (arrows
        on the sky) and "histograms"."""
        fit, data = self.result, self.data
        used = np.asarray(fit.used, bool)
        series = {"used": (fit.residual_xel_arcsec[used], fit.residual_el_arcsec[used])}
        if (~used).any():
            series["rejected"] = (fit.residual_xel_arcsec[~used], fit.residual_el_arcsec[~used])

        def draw(folder: Path):
            return [
                pointing_errors_figure(
                    np.degrees(data.az_rad), np.degrees(data.el_rad), fit.residual_xel_arcsec,
                    fit.residual_el_arcsec, folder / "residuals.png", rejected=~used,
                    sun_el_deg=self.sun_el_deg, what="residual",
                    title=f"Residuals of {self.source} against elevation and azimuth"),
                residual_quiver_figure(data, fit, folder / "sky.png",
                                       title=f"Residuals of {self.source} on the sky"),
                histogram_figure(series, folder / "histograms.png",
                                 title=f"Histograms of the residuals of {self.source}")]

        return drawn(draw)

    def plot_residuals(self):
        """The residuals against elevation and azimuth (a matplotlib Figure)."""
        return figure_of(self.figures(), "residuals", "a fit")

    def plot_sky(self):
        """The residuals as arrows on the sky (a matplotlib Figure)."""
        return figure_of(self.figures(), "sky", "a fit")

    def _table(self) -> Table:
        fit = self.result
        honest = fit.sigma_honest_arcsec
        rows = [[name, float(fit.values_arcsec[j]), float(fit.sigma_arcsec[j]),
                 float(honest[j]) if honest is not None else None]
                for j, name in enumerate(self.names)]
        caption = (f"{self.source}: {self.n_used} of {self.n_input} observations used, Sky "
                   f"RMS {self.result.sky_rms_arcsec:.2f}\" (arcsec; honest sigma: jackknife "
                   f"over {self.honest_words})")
        return Table(["term", "value (\")", "sigma (\")", "honest sigma (\")"], rows,
                     caption=caption, number_format=".2f")

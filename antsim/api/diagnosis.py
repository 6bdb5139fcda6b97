"""``antsim.diagnose_model``: what a pointing model leaves out of a file's residuals, found
as ``antsim diagnose`` finds it, and :class:`Diagnosis`, the diagnose library's result
wrapped: its document, its words and its figures."""

from __future__ import annotations

import os
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from antsim.diagnose.modelit import plots, resimulation_words
from antsim.diagnose.request import check_options, diagnose_file, read_scenario, refuse_links
from antsim.figures.html import Table
from antsim.outdir import held_output_dir
from antsim.progress import Progress
from antsim.simulate.streaming import release_prestarted
from controller.errors import Note

from .campaign import recordings_file
from .show import ShownAsTable, arcsec, drawn, figure_of

if TYPE_CHECKING:
    from astropy.units import Quantity

    import antsim.diagnose
    from controller.pointing.model import PointingModel

__all__ = ["Diagnosis", "diagnose_model"]


@dataclass(repr=False)
class Diagnosis(ShownAsTable):
    """A diagnosis (:func:`diagnose_model`): the diagnose library's own result
    (``diagnosis``, :class:`antsim.diagnose.Diagnosis`), what was written (``written``:
    the ``outputs`` part of ``diagnose.json``; None without ``out``) and where (``out``).

    :meth:`to_json` is the document ``antsim diagnose --json`` prints (and
    ``diagnose.json`` holds); the properties read it, so they say what the command says.
    Angles are Quantities in arcsec."""

    diagnosis: antsim.diagnose.Diagnosis
    written: dict[str, Any] | None = None
    out: Path | None = None
    _figures: dict[str, Any] | None = field(default=None, init=False)

    def to_json(self) -> dict[str, Any]:
        """``antsim diagnose --json``: findings best first, the baseline, the located
        mismatch, refusals and the summary (with ``outputs`` when files were written)."""
        doc = self.diagnosis.to_json()
        if self.written is not None:
            doc["outputs"] = self.written
        return doc

    def text(self) -> str:
        """The report in words, as ``antsim diagnose`` prints it."""
        text = self.diagnosis.text()
        if self.written and "resimulation" in self.written:
            text += "\n" + resimulation_words(self.written["resimulation"])
        return text

    @property
    def mismatch(self) -> bool:
        """Whether anything was found that the model leaves out."""
        return bool(self.diagnosis.mismatch)

    @property
    def findings(self) -> list[dict[str, Any]]:
        """The findings, best first, as the JSON gives them (effect, terms, explanation,
        where, params, significance, Sky RMS before and after in arcsec)."""
        return self.to_json()["findings"]

    @property
    def effects(self) -> list[str]:
        """The effects found, best first."""
        return [f["effect"] for f in self.findings]

    @property
    def sky_rms_before(self) -> Quantity:
        """The Sky RMS of the baseline model's residuals (arcsec), as the JSON gives it."""
        return arcsec(self.to_json()["summary"]["sky_rms_before_arcsec"])

    @property
    def sky_rms_after(self) -> Quantity:
        """The Sky RMS with the findings modelled (arcsec), as the JSON gives it."""
        return arcsec(self.to_json()["summary"]["sky_rms_after_arcsec"])

    def updated_model(self) -> PointingModel:
        """The baseline terms refitted with the findings' terms (``model_updated.dat``)."""
        return self.diagnosis.updated_model()

    def figures(self) -> dict[str, Any]:
        """The residual figures ``--out`` writes (matplotlib Figures drawn by
        :mod:`antsim.figures.diagnose`: before and after the findings, or before only), by
        file name ("diagnose_residuals", "diagnose_histograms", "diagnose_quiver")."""
        if self._figures is None:
            self._figures = drawn(lambda folder: plots(self.diagnosis, folder))
        return self._figures

    def plot_residuals(self):
        """Residuals before and after the findings against elevation and azimuth."""
        return figure_of(self.figures(), "diagnose_residuals", "this diagnosis")

    def plot_sky(self):
        """Residuals before and after the findings on the sky."""
        return figure_of(self.figures(), "diagnose_quiver", "this diagnosis")

    def _table(self) -> Table:
        doc = self.to_json()
        rows = [[i, f["effect"], " ".join(f["terms"]), f["significance"],
                 f["sky_rms_before_arcsec"], f["sky_rms_after_arcsec"], f["where"]]
                for i, f in enumerate(doc["findings"], 1)]
        s = doc["summary"]
        caption = (f"{self.diagnosis.obs.path}: baseline {' '.join(doc['baseline']['terms'])}; "
                   + (f"{len(rows)} finding(s), best first" if rows else
                      self.diagnosis.nothing_found_words())
                   + f"; Sky RMS {s['sky_rms_before_arcsec']:.2f}\" -> "
                   f"{s['sky_rms_after_arcsec']:.2f}\"")
        return Table(["#", "effect", "terms", "significance (sigma)", "Sky RMS before (\")",
                      "Sky RMS after (\")", "where"], rows, caption=caption,
                     column_formats=(None, None, None, ".1f", ".2f", ".2f", None))


def diagnose_model(data: str | os.PathLike | Any, *, scenario: str | os.PathLike | None = None,
                   model: str | None = None, mount: str | None = None,
                   csv: Sequence[str] = (), sims: int = 8,
                   jobs: int = min(2, os.cpu_count() or 1),
                   cache: str | os.PathLike | None = None, use_cache: bool = True,
                   out: str | os.PathLike | None = None, resimulate: int | None = None,
                   progress: bool | None = False) -> Diagnosis:
    """Find what a pointing model leaves out of a file's residuals, as ``antsim diagnose``
    does (docs/diagnose.md).

    ``data``: recordings, a TPOINT data file or a CSV of measurements, or a
    :class:`~antsim.api.Campaign` run with ``out=``. ``scenario``: the scenario that should
    explain them (a name or a TOML file): its simulations predict the noise; without it
    the noise is estimated from the data. ``model``: the baseline terms (a named model, a
    model file, or "T1,T2,..."; default the scenario's fit model, else the recordings'
    model in use). ``sims``: simulations that predict the noise; ``jobs``: processes for
    them; ``cache``/``use_cache``: the baseline simulations' cache (docs/caches.md).
    ``out``: a directory to write what ``--out`` writes (``diagnose.json``, the updated
    model and scenario, figures, ``report.html``; re-simulating ``resimulate`` times,
    default 4); without it nothing is written but the cache. ``progress``: a progress bar
    on stderr (None: on a terminal only).

    The file's notes are issued as :class:`controller.errors.Note` warnings. Bad input
    raises :class:`controller.errors.InputError` with the line ``antsim diagnose`` prints."""
    path = recordings_file(data, "antsim.diagnose_model")
    check_options(jobs, sims, resimulate, model)
    spec = None if scenario is None else os.fspath(scenario)
    cache_dir = None if cache is None else os.fspath(cache)

    def note(line: str) -> None:
        warnings.warn(line, Note, stacklevel=3)

    def ask(directory: Path | None) -> Diagnosis:
        try:
            loaded = None if spec is None else read_scenario(spec, path, jobs)
            with Progress("diagnose", progress) as shown:
                asked = diagnose_file(path, loaded, scenario_spec=spec, model=model,
                                      mount=mount, csv_options=csv, sims=sims, jobs=jobs,
                                      cache_dir=cache_dir, use_cache=use_cache, out=directory,
                                      resimulate=resimulate, progress=shown, note=note)
        finally:
            release_prestarted()  # a quiet campaign started and not needed ends here
        return Diagnosis(asked.diagnosis, asked.written, directory)

    if out is None:
        return ask(None)
    with held_output_dir(os.fspath(out), "--out", "antsim.diagnose_model") as directory:
        refuse_links(directory)
        return ask(directory)

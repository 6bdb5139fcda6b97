"""``antsim.answer_plan``: a plan's what-if questions answered as ``antsim plan`` answers
them, and :class:`PlanAnswers`: the variants' predicted and Monte Carlo sigmas, the
answers, and the comparison figures."""

from __future__ import annotations

import os
from contextlib import nullcontext
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from astropy.table import QTable

from antsim.bundled import find
from antsim.figures.plan import plan_figures
from antsim.outdir import held_output_dir
from antsim.plan.outputs import check_options, write_outputs
from antsim.plan.planfile import load_plan
from antsim.plan.report import variants_table
from antsim.plan.study import run_plan
from antsim.progress import Progress

from .show import ShownAsTable, arcsec, drawn, figure_of, formatted

if TYPE_CHECKING:
    from antsim.figures.html import Table
    from antsim.plan.study import PlanResult

__all__ = ["PlanAnswers", "answer_plan"]


@dataclass(repr=False)
class PlanAnswers(ShownAsTable):
    """A plan answered (:func:`answer_plan`): the plan's result (``result``,
    :class:`antsim.plan.study.PlanResult`) and where it was written (``out``, None when
    nothing was). :meth:`to_json` is ``plan.json`` (``antsim plan --json``); :meth:`text`
    is ``plan.txt``. Angles are Quantities in arcsec."""

    result: PlanResult
    out: Path | None = None
    _document: dict[str, Any] | None = field(default=None, init=False)
    _figures: dict[str, Any] | None = field(default=None, init=False)

    def to_json(self) -> dict[str, Any]:
        """``plan.json``: every variant's terms (predicted and Monte Carlo sigma, bias,
        truth) and the answers to the plan's questions."""
        if self._document is None:
            self._document = self.result.to_json()
        return self._document

    def text(self) -> str:
        """``plan.txt``: the tables and answers in words (without the timing)."""
        return self.result.text(timing=False)

    @property
    def variants(self) -> list[str]:
        """The variants' names, in the plan's order."""
        return [p["name"] for p in self.to_json()["plans"]]

    @property
    def answers(self) -> dict[str, list[dict[str, Any]]]:
        """The answers to the plan's questions (how long, which sources, coverage)."""
        return self.to_json()["answers"]

    def terms(self, variant: str | int = 0) -> QTable:
        """One variant's terms (by name or index): truth, sigma predicted (Fisher) and
        Monte Carlo, bias Monte Carlo and predicted (arcsec)."""
        plans = self.to_json()["plans"]
        names = [p["name"] for p in plans]
        if isinstance(variant, str):
            if variant not in names:
                raise KeyError(f"no variant {variant!r}; the plan's are {', '.join(names)}")
            variant = names.index(variant)
        terms = plans[variant]["terms"]

        def column(key: str):
            return arcsec([float("nan") if t[key] is None else t[key] for t in terms.values()])

        table = QTable({"term": list(terms), "truth": column("truth_arcsec"),
                        "sigma_predicted": column("sigma_fisher_arcsec"),
                        "sigma_monte_carlo": column("sigma_mc_arcsec"),
                        "bias_monte_carlo": column("bias_arcsec"),
                        "bias_predicted": column("bias_predicted_arcsec")})
        return formatted(table, ".2f")

    def figures(self) -> dict[str, Any]:
        """The comparison figures ``--out`` writes (matplotlib Figures drawn by
        :mod:`antsim.figures.plan`), by file name ("sigma_predicted", "sigma_monte_carlo",
        "sigma_mc_over_predicted", "bias", "duration_1", "sources_1", ...)."""
        if self._figures is None:
            self._figures = drawn(lambda folder: plan_figures(self.to_json(), folder))
        return self._figures

    def plot(self, name: str):
        """One figure by its file name (see :meth:`figures`)."""
        return figure_of(self.figures(), name, "this plan")

    def plot_sigmas(self):
        """The predicted sigma of each term, per variant."""
        return self.plot("sigma_predicted")

    def _table(self) -> Table:
        return variants_table(self.to_json())


def answer_plan(plan: str | os.PathLike, *, members: int | None = None,
                workers: int | None = None, scheduler: str | None = None,
                answers: bool = True, out: str | os.PathLike | None = None,
                progress: bool | None = False) -> PlanAnswers:
    """Answer a plan's what-if questions, as ``antsim plan`` does: for each variant the
    predicted (Fisher) sigma of every fitted term and the Monte Carlo sigma and bias of
    simulated campaigns, then the plan's questions (how long, which sources, coverage).

    ``plan``: a name (``antsim scenarios`` lists them, e.g. ``"ghigo1990_whatif"``) or a
    plan file (TOML). ``members``: Monte Carlo members per variant (default the plan's);
    ``workers``: local processes (default the machine's cores; 0: this process);
    ``scheduler``: a Dask scheduler's address instead; ``answers``: False skips the
    questions (the quick look). ``out``: a directory to write what ``--out`` writes
    (``plan.json``, ``plan.txt``, figures, ``report.html``); without it nothing is written.
    ``progress``: a progress bar on stderr (None: on a terminal only). The numbers do not
    depend on ``workers`` or ``scheduler``.

    Bad input raises :class:`controller.errors.InputError` with the line ``antsim plan``
    prints."""
    check_options(members, workers, scheduler)
    held = (held_output_dir(os.fspath(out), "--out", "antsim.answer_plan") if out is not None
            else nullcontext())
    with held as directory, Progress("plan", progress) as shown:
        shown.stage("reading the plan")
        loaded = load_plan(find(os.fspath(plan), "plan"))
        result = run_plan(loaded, workers=workers, scheduler=scheduler, members=members,
                          progress=shown, answers=answers)
        answered = PlanAnswers(result, directory)
        if directory is not None:
            shown.stage("figures")
            write_outputs(result, directory, answered.to_json())
    return answered

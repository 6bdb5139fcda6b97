"""What ``antsim plan`` asks of a plan before it runs (the counts of its options), and the
files it writes of the answers: ``plan.json`` (:meth:`antsim.plan.study.PlanResult.to_json`),
``plan.txt`` (the tables without the timing), the comparison figures and ``report.html``.
The command line and the Python API (:func:`antsim.api.answer_plan`) share them.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

from antsim.figures.plan import plan_figures
from antsim.options import check_processes
from antsim.outdir import write_file
from controller.errors import InputError

from .planfile import MAX_MEMBERS
from .report import write_plan_report

if TYPE_CHECKING:
    from antsim.figures.style import FigureFile

    from .study import PlanResult

__all__ = ["check_options", "write_outputs"]


def check_options(members: int | None, workers: int | None, scheduler: str | None) -> None:
    """``--members`` (None: the plan's), ``--workers`` (None: the machine's cores) and
    ``--scheduler``, each within its limits, else one InputError line."""
    if members is not None and not 2 <= members <= MAX_MEMBERS:
        raise InputError("command line", "--members", members,
                         f"must be within 2..{MAX_MEMBERS}")
    if workers is not None:
        check_processes(workers, "--workers", minimum=0)
    if scheduler is not None and workers is not None:
        raise InputError("command line", "--workers", workers,
                         "give --workers or --scheduler, not both",
                         "the Dask cluster sets its own workers")


def write_outputs(result: PlanResult, out: Path,
                  doc: dict[str, Any] | None = None) -> list[FigureFile]:
    """Write ``plan.json``, ``plan.txt``, the figures and ``report.html`` of ``result``
    (``doc``: its :meth:`~antsim.plan.study.PlanResult.to_json` where already made) into
    ``out``; returns the figures."""
    doc = result.to_json() if doc is None else doc
    write_file(out / "plan.json", json.dumps(doc, indent=2) + "\n")
    plan_text = result.text(timing=False)
    write_file(out / "plan.txt", plan_text)
    figures = plan_figures(doc, out)
    write_plan_report(doc, plan_text, figures, out)
    return figures

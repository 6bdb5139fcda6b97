"""``DIR/report.html`` of ``antsim plan --out DIR``: one self-contained page like ``antsim
run``'s report (:mod:`antsim.figures.html`: the same style, figures embedded the same way).

One source for every number: the page is built from the document written as ``plan.json``
(:meth:`antsim.plan.study.PlanResult.to_json`), printed at the precision of ``plan.txt``; the
answers are :func:`antsim.plan.answers.answers_text` of that document, and the whole
``plan.txt`` closes the page.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from antsim.figures.html import (
    Block,
    Figure,
    Paragraph,
    Preformatted,
    Section,
    Table,
    format_number,
    write_report,
)

from .answers import answers_text

if TYPE_CHECKING:
    from antsim.figures.style import FigureFile

__all__ = ["TERMS_HEADER", "VARIANTS_HEADER", "write_plan_report"]

#: the variants table's columns (tests read the page by them)
VARIANTS_HEADER = ("variant", "campaign (h)", "scans", "Monte Carlo members",
                   "Sky RMS predicted (\")", "Sky RMS Monte Carlo (\")")
#: each variant's terms table's columns
TERMS_HEADER = ("term", "truth (\")", "sigma predicted (\")", "sigma Monte Carlo (\")",
                "bias Monte Carlo (\")", "bias predicted (\")")


def _f(x: float | None, spec: str) -> str | None:
    return None if x is None else format_number(x, spec)


def _num(x: float | None) -> float | None:
    return None if x is None else float(x)


#: the numbers' formats of each table's columns (plan.txt's precision)
VARIANTS_FORMATS = (None, ".1f", None, None, ".1f", ".1f")
TERMS_FORMATS = (None, "+.1f", ".2f", ".2f", "+.1f", "+.1f")


def variants_table(doc: Mapping[str, Any]) -> Table:
    """The variants, a row each; numbers as numbers (right-aligned, no negative zero)."""
    rows = [[p["name"], _num(p["duration_h"]), p["n_scans"], p["n_monte_carlo"],
             _num(p["sky_rms_fisher_arcsec"]), _num(p["sky_rms_mc_arcsec"])]
            for p in doc["plans"]]
    return Table(VARIANTS_HEADER, rows, caption="The plan's variants",
                 column_formats=VARIANTS_FORMATS)


def terms_table(variant: Mapping[str, Any]) -> Table:
    """The sigma and bias of each term of one variant, as ``plan.txt`` prints them."""
    rows = [[name, _num(t["truth_arcsec"]), _num(t["sigma_fisher_arcsec"]),
             _num(t["sigma_mc_arcsec"]), _num(t["bias_arcsec"]),
             _num(t["bias_predicted_arcsec"])]
            for name, t in variant["terms"].items()]
    return Table(TERMS_HEADER, rows, caption=f"{variant['name']}: the fitted terms (arcsec)",
                 column_formats=TERMS_FORMATS)


def write_plan_report(doc: Mapping[str, Any], text: str, figures: Sequence[FigureFile],
                      out_dir: str | Path) -> Path:
    """Write ``out_dir/report.html`` from the plan document ``doc`` (as in ``plan.json``),
    its ``text`` (``plan.txt``) and its figures."""
    out = Path(out_dir)
    summary = (f"Plan {doc['plan']}: {len(doc['plans'])} variants of scenario "
               f"{doc['scenario']} (seed {doc['seed']}). "
               + (f"{doc['description']} " if doc.get("description") else "")
               + "Predicted: from the design and the noise model (Fisher); Monte Carlo: the "
               "scatter and mean of the fits of simulated campaigns. All angles in "
               f"{doc['units']}; sign of the terms: {doc['sign_convention']}.")
    sections = [Section("Summary", [
        Paragraph(summary),
        Paragraph("Files in this directory: plan.json and plan.txt (this page's numbers), "
                  f"the figures ({', '.join(f.path.name for f in figures)})."),
        variants_table(doc)])]
    for p in doc["plans"]:
        blocks: list[Block] = [terms_table(p)]
        if p.get("description"):
            blocks.insert(0, Paragraph(p["description"]))
        if p["cannot_separate"]:
            blocks.append(Paragraph("Cannot reliably be separated: " + ", ".join(
                f"{c['terms'][0]}-{c['terms'][1]} (r = {_f(c['r_predicted'], '+.3f')})"
                for c in p["cannot_separate"]) + "."))
        sections.append(Section(f"Variant: {p['name']}", blocks))
    answers = answers_text(doc.get("answers", {}))
    if answers:
        sections.append(Section("Answers", [Paragraph("\n\n".join(answers))]))
    sections.append(Section("Figures", [Figure.of(f) for f in figures]))
    sections.append(Section("The plan in words", [Preformatted(text, caption="plan.txt")]))
    return write_report(out / "report.html", f"antsim plan: {doc['plan']}", sections,
                        subtitle=doc.get("description", ""))

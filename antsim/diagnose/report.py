"""``DIR/report.html`` of ``antsim diagnose --out DIR``: one self-contained page like
``antsim run``'s report (:mod:`antsim.figures.html`: the same style, figures embedded the same
way).

One source for every number: the page is built from the document written as
``diagnose.json`` (:meth:`antsim.diagnose.core.Diagnosis.to_json` plus its outputs), printed
at the precision of ``diagnose.txt``; the updated model is ``model_updated.dat`` as written,
and the whole ``diagnose.txt`` closes the page.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from antsim.figures.html import Block, Figure, Paragraph, Preformatted, Section, Table, write_report

if TYPE_CHECKING:
    from antsim.figures.style import FigureFile

__all__ = ["FINDINGS_HEADER", "RMS_HEADER", "write_diagnose_report"]

#: the findings table's columns (tests read the page by them)
FINDINGS_HEADER = ("#", "effect", "terms", "significance (sigma)", "Sky RMS before (\")",
                   "Sky RMS after (\")", "where")
#: the Sky RMS table's columns
RMS_HEADER = ("", "before (\")", "after (\")")


def _rms(x: float | None) -> str | None:
    """A Sky RMS as diagnose.txt prints it."""
    return None if x is None else f"{x:.2f}"


def findings_table(doc: Mapping[str, Any]) -> Table:
    rows = [[i, f["effect"], " ".join(f["terms"]), f"{f['significance']:.1f}",
             _rms(f["sky_rms_before_arcsec"]), _rms(f["sky_rms_after_arcsec"]), f["where"]]
            for i, f in enumerate(doc["findings"], 1)]
    return Table(FINDINGS_HEADER, rows, caption="Findings, best first (arcsec)")


def rms_table(doc: Mapping[str, Any], axes: str) -> Table:
    """In-sample and held-out Sky RMS and per-axis rms, before and after the findings."""
    s = doc["summary"]
    a, b = axes.split("/")
    rows = [["Sky RMS in-sample", _rms(s["sky_rms_before_arcsec"]),
             _rms(s["sky_rms_after_arcsec"])],
            [f"Sky RMS held out ({s['held_out']})", _rms(s["cv_sky_rms_before_arcsec"]),
             _rms(s["cv_sky_rms_after_arcsec"])]]
    for k, name in enumerate((a, b)):
        rows.append([f"{name} rms in-sample", f"{s['axis_rms_before_arcsec'][k]:.1f}",
                     f"{s['axis_rms_after_arcsec'][k]:.1f}"])
        rows.append([f"{name} rms held out", f"{s['cv_axis_rms_before_arcsec'][k]:.1f}",
                     f"{s['cv_axis_rms_after_arcsec'][k]:.1f}"])
    return Table(RMS_HEADER, rows, caption="Residuals before and after the findings "
                 f"({s['n_used']} scans used)")


def write_diagnose_report(doc: Mapping[str, Any], text: str, figures: Sequence[FigureFile],
                          out_dir: str | Path, *, recordings: str, axes: str = "xel/el",
                          nothing_found: str = "") -> Path:
    """Write ``out_dir/report.html`` from the diagnosis document ``doc`` (as in
    ``diagnose.json``), its ``text`` (``diagnose.txt``) and its figures; ``axes``: the two
    offsets' names ("xel/el" or "RA/Dec"); ``nothing_found``: the words for no finding."""
    out = Path(out_dir)
    base = doc["baseline"]
    n = len(doc["findings"])
    summary = (f"Recordings {recordings}: baseline {' '.join(base['terms'])} "
               f"({base['origin']}); noise: {base['noise']}. Located: "
               f"{doc['located']['words']}. ")
    summary += (f"{n} finding{'s' if n != 1 else ''}, best first; stopped: {doc['stop']}."
                if n else f"{nothing_found[:1].upper()}{nothing_found[1:]}.")
    summary += (" Every angle on this page is in arcsec; residuals are indicated minus "
                "true, cross-elevation = dA cos E.")
    outputs = doc.get("outputs", {})
    files = ["diagnose.json and diagnose.txt (this page's numbers)",
             "model_updated.dat (TPOINT model, usable as antsim run --model) and "
             "model_updated.json"]
    if "scenario" in outputs:
        files.append(f"{outputs['scenario']} (the scenario with the findings as effects)")
    files.append(f"the figures ({', '.join(outputs.get('plots', []))})")
    sections = [Section("Summary", [Paragraph(summary),
                                    Paragraph("Files in this directory: " + "; ".join(files)
                                              + ".")])]
    blocks: list[Block] = []
    if n:
        blocks.append(findings_table(doc))
        blocks += [Paragraph(f"{i}. {f['effect']}: {f['explanation']}")
                   for i, f in enumerate(doc["findings"], 1)]
    else:
        blocks.append(Paragraph(nothing_found))
    blocks.append(rms_table(doc, axes))
    sections.append(Section("Findings", blocks))
    model_blocks: list[Block] = [Preformatted(
        (out / "model_updated.dat").read_text(encoding="utf-8"), caption="model_updated.dat")]
    for key in ("not_in_model", "not_in_scenario"):
        if key in outputs:
            model_blocks.append(Paragraph(f"Note: {outputs[key]}."))
    sections.append(Section("Updated pointing model", model_blocks))
    sections.append(Section("Figures", [Figure.of(f) for f in figures]))
    sections.append(Section("The report in words", [Preformatted(text,
                                                                 caption="diagnose.txt")]))
    title = f"antsim diagnose: {Path(recordings).name}"
    return write_report(out / "report.html", title, sections,
                        subtitle="What the pointing model misses")

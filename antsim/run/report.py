"""Self-contained HTML reports: one file that opens offline and requests nothing.

:func:`write_report` is generic (``antsim run``, ``diagnose``, ``plan`` and the teaching
walk-through use it): a title and a list of :class:`Section` s, each holding blocks:
:class:`Paragraph`, :class:`Table`, :class:`Figure` (a PNG on disk, embedded as a base64
``data:`` URI) and :class:`Preformatted`. The page has inline CSS only, no script, and a
Content-Security-Policy that forbids every network request (``default-src 'none'; img-src
data:``), so a browser could not fetch anything even if a figure or a string asked it to.
All text is HTML-escaped. A software-versions section ends every report. No timestamps: the
same inputs give the same bytes.

:func:`write_run_report` builds the report of ``antsim run``: the fits A-F in the style of
the 1990 report's Table 2, the coefficients (Table 3), the coefficients against the injected
truth with pulls, fit A's warnings and correlations, the figures of :mod:`antsim.figures.run`,
the scenario text and the software versions.
"""

from __future__ import annotations

import base64
import html
import math
import platform
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from antsim._version import __version__
from controller.pointing.fitting import FitResult
from controller.pointing.variants import VARIANTS

if TYPE_CHECKING:
    from antsim.figures.style import FigureFile

    from .runner import RunResult

__all__ = [
    "CONTENT_SECURITY_POLICY",
    "Figure",
    "Paragraph",
    "Preformatted",
    "Section",
    "Table",
    "coefficient_table",
    "fit_summary_table",
    "render_report",
    "software_versions",
    "truth_pull_table",
    "truth_terms_arcsec",
    "write_report",
    "write_run_report",
]

#: forbids every request but inline styles and data: images (no script at all)
CONTENT_SECURITY_POLICY = "default-src 'none'; img-src data:; style-src 'unsafe-inline'"
#: |pull| above which a table cell is highlighted
PULL_WARN = 3.0


# ---------------------------------------------------------------------------------------------
# blocks
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Paragraph:
    """Plain text; blank lines separate paragraphs."""

    text: str


@dataclass(frozen=True)
class Preformatted:
    """Monospaced text kept as it is (tables from ``fit.txt``, a scenario file, a command)."""

    text: str
    caption: str = ""


@dataclass(frozen=True)
class Table:
    """A table: ``header`` and ``rows`` of cells. Strings are shown as given; numbers with
    ``number_format``; None and non-finite numbers as a dash. ``highlight`` holds (row,
    column) indices of cells to emphasise."""

    header: Sequence[str]
    rows: Sequence[Sequence[Any]]
    caption: str = ""
    number_format: str = ".1f"
    highlight: frozenset[tuple[int, int]] = field(default_factory=frozenset)


@dataclass(frozen=True)
class Figure:
    """A PNG file on disk, embedded into the page; ``title`` and ``caption`` under it."""

    path: Path
    title: str = ""
    caption: str = ""

    @classmethod
    def of(cls, figure: FigureFile) -> Figure:
        """The block of a :class:`antsim.figures.style.FigureFile`."""
        return cls(Path(figure.path), figure.title, figure.caption)


Block = Paragraph | Preformatted | Table | Figure


@dataclass(frozen=True)
class Section:
    """A heading and its blocks."""

    heading: str
    blocks: Sequence[Block] = ()


# ---------------------------------------------------------------------------------------------
# rendering
# ---------------------------------------------------------------------------------------------
_CSS = """
body { font-family: "DejaVu Sans", Helvetica, Arial, sans-serif; margin: 0 auto;
       max-width: 1080px; padding: 1em 1.5em 3em; color: #1a1a1a; line-height: 1.45; }
h1 { font-size: 1.6em; border-bottom: 2px solid #1f4e9c; padding-bottom: 0.2em; }
h2 { font-size: 1.25em; margin-top: 1.8em; color: #1f4e9c; }
p.subtitle { color: #555; margin-top: -0.5em; }
nav ol { columns: 2; font-size: 0.92em; }
table { border-collapse: collapse; margin: 0.6em 0 1.2em; font-size: 0.9em; }
caption { caption-side: top; text-align: left; font-weight: bold; padding-bottom: 0.3em; }
th, td { border: 1px solid #c8c8c8; padding: 0.2em 0.55em; }
th { background: #eef2f8; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
td.warn { background: #fde0dd; font-weight: bold; }
figure { margin: 1.2em 0 1.8em; }
figure img { max-width: 100%; height: auto; border: 1px solid #ddd; }
figcaption { font-size: 0.92em; color: #333; margin-top: 0.3em; }
figcaption b { color: #1a1a1a; }
pre { background: #f6f6f6; border: 1px solid #ddd; padding: 0.6em; overflow-x: auto;
      font-size: 0.82em; line-height: 1.3; }
p.pre-caption { font-weight: bold; margin-bottom: 0.2em; }
"""


def _esc(text: Any) -> str:
    return html.escape(str(text), quote=True)


def _cell(value: Any, number_format: str) -> tuple[str, bool]:
    """(escaped text, is numeric) of one table cell."""
    if value is None:
        return "\N{EN DASH}", True
    if isinstance(value, bool):
        return _esc(value), False
    if isinstance(value, int):
        return _esc(value), True
    if isinstance(value, float):
        if not math.isfinite(value):
            return "\N{EN DASH}", True
        text = format(value, number_format)
        if text.lstrip("+-").strip("0.") == "" and text[:1] == "-":  # no "-0.00"
            text = format(0.0, number_format)
        return _esc(text), True
    return _esc(value), False


def _render_table(table: Table) -> str:
    out = ["<table>"]
    if table.caption:
        out.append(f"<caption>{_esc(table.caption)}</caption>")
    out.append("<thead><tr>" + "".join(f"<th>{_esc(h)}</th>" for h in table.header)
               + "</tr></thead><tbody>")
    for i, row in enumerate(table.rows):
        if len(row) != len(table.header):
            raise ValueError(f"table {table.caption!r}: row {i} has {len(row)} cells, the "
                             f"header {len(table.header)}")
        cells = []
        for j, value in enumerate(row):
            text, numeric = _cell(value, table.number_format)
            classes = (["num"] if numeric else []) + (["warn"] if (i, j) in table.highlight
                                                      else [])
            cls = f' class="{" ".join(classes)}"' if classes else ""
            cells.append(f"<td{cls}>{text}</td>")
        out.append("<tr>" + "".join(cells) + "</tr>")
    out.append("</tbody></table>")
    return "\n".join(out)


def _render_figure(figure: Figure) -> str:
    path = Path(figure.path)
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise FileNotFoundError(f"report figure {path} does not exist") from None
    if not data.startswith(b"\x89PNG\r\n\x1a\n"):
        raise ValueError(f"report figure {path} is not a PNG file")
    uri = "data:image/png;base64," + base64.b64encode(data).decode("ascii")
    alt = figure.title or path.stem
    caption = ""
    if figure.title or figure.caption:
        caption = ("<figcaption>" + (f"<b>{_esc(figure.title)}.</b> " if figure.title else "")
                   + _esc(figure.caption) + "</figcaption>")
    return (f'<figure id="fig-{_esc(path.stem)}"><img src="{uri}" alt="{_esc(alt)}" '
            f'data-file="{_esc(path.name)}">{caption}</figure>')


def _render_block(block: Block) -> str:
    if isinstance(block, Paragraph):
        parts = [p.strip() for p in block.text.split("\n\n") if p.strip()]
        return "\n".join(f"<p>{_esc(p)}</p>" for p in parts)
    if isinstance(block, Preformatted):
        cap = f'<p class="pre-caption">{_esc(block.caption)}</p>' if block.caption else ""
        return f"{cap}<pre>{_esc(block.text)}</pre>"
    if isinstance(block, Table):
        return _render_table(block)
    if isinstance(block, Figure):
        return _render_figure(block)
    raise TypeError(f"unknown report block {type(block).__name__}: use Paragraph, "
                    "Preformatted, Table or Figure")


def software_versions() -> dict[str, str]:
    """Versions of antsim, the libraries it computes with, and Python."""
    from importlib import metadata

    versions = {"antsim": __version__}
    for package in ("numpy", "scipy", "astropy", "simpy", "matplotlib"):
        try:
            versions[package] = metadata.version(package)
        except metadata.PackageNotFoundError:
            versions[package] = "not installed"
    versions["python"] = platform.python_version()
    return versions


def render_report(title: str, sections: Sequence[Section], *, subtitle: str = "",
                  versions: Mapping[str, str] | None = None) -> str:
    """The HTML text of a report (see the module docstring); ``versions`` defaults to
    :func:`software_versions`."""
    versions = software_versions() if versions is None else versions
    all_sections = [*sections, Section("Software versions", [Table(
        ["package", "version"], [[k, v] for k, v in versions.items()])])]
    body = [f"<h1>{_esc(title)}</h1>"]
    if subtitle:
        body.append(f'<p class="subtitle">{_esc(subtitle)}</p>')
    body.append("<nav><ol>" + "".join(
        f'<li><a href="#s{i + 1}">{_esc(s.heading)}</a></li>'
        for i, s in enumerate(all_sections)) + "</ol></nav>")
    for i, section in enumerate(all_sections):
        body.append(f'<section id="s{i + 1}"><h2>{_esc(section.heading)}</h2>')
        body.extend(_render_block(b) for b in section.blocks)
        body.append("</section>")
    return ("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
            f'<meta http-equiv="Content-Security-Policy" content="{CONTENT_SECURITY_POLICY}">\n'
            '<meta name="viewport" content="width=device-width, initial-scale=1">\n'
            f"<title>{_esc(title)}</title>\n<style>{_CSS}</style>\n</head>\n<body>\n"
            + "\n".join(body) + "\n</body>\n</html>\n")


def write_report(path: str | Path, title: str, sections: Sequence[Section], *,
                 subtitle: str = "", versions: Mapping[str, str] | None = None) -> Path:
    """Write :func:`render_report` to ``path`` (UTF-8) and return the path."""
    path = Path(path)
    text = render_report(title, sections, subtitle=subtitle, versions=versions)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


# ---------------------------------------------------------------------------------------------
# tables of fits
# ---------------------------------------------------------------------------------------------
def fit_summary_table(fits: Mapping[str, FitResult | None],
                      reference_rms: Mapping[str, tuple[float, float]] | None = None) -> Table:
    """Table 2 style: per fit A-F, the data, N, used, xel/el/sky rms (arcsec), and the
    published xel/el rms if ``reference_rms`` is given."""
    header = ["fit", "data", "N", "used", "xel rms (\")", "el rms (\")", "sky rms (\")"]
    if reference_rms:
        header += ["report xel rms (\")", "report el rms (\")"]
    rows = []
    for v in VARIANTS:
        fit = fits.get(v.name)
        ref = list(reference_rms.get(v.name, (None, None))) if reference_rms else []
        if fit is None:
            rows.append([v.name, v.description, None, None, None, None, None, *ref])
        else:
            rows.append([v.name, v.description, fit.n_input, fit.n_used,
                         float(fit.xel_rms_arcsec), float(fit.el_rms_arcsec),
                         float(fit.sky_rms_arcsec), *ref])
    return Table(header, rows, caption="Residuals of the fits (the 1990 report's Table 2)")


def coefficient_table(fits: Mapping[str, FitResult | None]) -> Table:
    """Table 3 style: coefficients (arcmin) of each fit present, and fit A's TPOINT sigma."""
    present = [v.name for v in VARIANTS if fits.get(v.name) is not None]
    if not present:
        return Table(["term"], [], caption="Coefficients: no fit had enough observations")
    names = fits[present[0]].names
    fit_a = fits.get("A")
    rows = []
    for j, term in enumerate(names):
        row: list[Any] = [term]
        for p in present:
            fit = fits[p]
            row.append(float(fit.values_arcsec[fit.names.index(term)]) / 60.0
                       if term in fit.names else None)
        row.append(float(fit_a.sigma_arcsec[j]) / 60.0 if fit_a is not None else None)
        rows.append(row)
    return Table(["term", *(f"fit {p} (')" for p in present), "sigma A (')"], rows,
                 caption="Coefficients (arcmin; the 1990 report's Table 3)",
                 number_format="+.3f")


def truth_pull_table(fit: FitResult, truth_arcsec: Mapping[str, float]) -> Table:
    """Fitted coefficients against the injected truth (arcsec) with pulls
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
                 rows, caption="Coefficients against the injected truth", number_format=".2f",
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


def write_run_report(result: RunResult, fits: Mapping[str, FitResult | None],
                     out_dir: str | Path | None = None) -> tuple[Path, list[FigureFile]]:
    """Figures (``DIR/figures/``) and ``DIR/report.html`` of a run; returns both."""
    from antsim.figures.run import REPORT_TABLE2_ARCSEC, run_figures

    out = Path(out_dir if out_dir is not None else result.out_dir)
    scenario = result.scenario
    truth = truth_terms_arcsec(result.truth)
    reference = REPORT_TABLE2_ARCSEC if scenario.name == "ghigo1990" else None
    figures = run_figures(result.rows, fits, out / "figures", truth_arcsec=truth or None,
                          name=scenario.name, start_label=f"UTC {scenario.epoch_utc}",
                          el_limit_deg=scenario.controller.scheduler.elevation_min_deg,
                          reference_rms=reference, gain_fit=_elevation_gain_fit(result))
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
    sections = [Section("Summary", [Paragraph(summary), Paragraph(
        "Files in this directory: recordings.ecsv (one row per scan and polarization), "
        "truth.json (the injected truth), fit.json and fit_variants.json (the fits), fit.txt "
        "(these tables as text), model.dat (fit A as a TPOINT model, usable as antsim run "
        "--model), figures/ (the figures below as PNG files).")])]
    fit_blocks: list[Block] = [fit_summary_table(fits, reference), coefficient_table(fits)]
    if reference:
        fit_blocks.append(Paragraph(
            "The report columns are the 1990 report's Table 2 (Ghigo 1990) for the same "
            "selections of the real 24-hour run of 8-9 February 1990."))
    sections.append(Section("Fits A-F", fit_blocks))
    if fit_a is not None and truth:
        effects = [e.get("effect", "?") for e in (result.truth or {}).get("effects", [])]
        text = ("Pull = (fit - truth) / sigma. With independent Gaussian residuals pulls "
                "scatter with unit standard deviation. TPOINT's sigma assumes independent "
                "residuals; the honest sigma allows for residuals correlated in time "
                "(a jackknife over one-hour blocks, widened for its few degrees of freedom), "
                "so its pulls are the ones to trust. "
                f"Cells above {PULL_WARN:g} are highlighted.")
        if effects:
            text += (" The truth also holds effects the fitted model has no terms for ("
                     + ", ".join(effects) + "): they bias some coefficients.")
        sections.append(Section("Coefficients against the truth",
                                [truth_pull_table(fit_a, truth), Paragraph(text)]))
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


def _elevation_gain_fit(result: RunResult):
    """The run's fitted elevation gain curve (controller.gaincurve), if one was fitted."""
    calibration = getattr(result, "calibration", None)
    fit = getattr(calibration, "fit", None)
    return fit if hasattr(fit, "knots_deg") else None

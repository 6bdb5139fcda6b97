"""Self-contained HTML pages: one file that opens offline and requests nothing.

:func:`write_report` is generic (``antsim run``'s report and the teaching walk-through use
it): a title and a list of :class:`Section` s, each holding blocks: :class:`Paragraph`,
:class:`Table`, :class:`Figure` (a PNG on disk, embedded as a base64 ``data:`` URI) and
:class:`Preformatted`. The page has inline CSS only, no script, and a
Content-Security-Policy that forbids every network request (``default-src 'none'; img-src
data:``), so a browser could not fetch anything even if a figure or a string asked it to.
All text is HTML-escaped. A software-versions section ends every report. No timestamps: the
same inputs give the same bytes.
"""

from __future__ import annotations

import base64
import html
import math
import platform
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path
from typing import TYPE_CHECKING, Any

from antsim._version import __version__
from antsim.outdir import write_file

if TYPE_CHECKING:
    from antsim.figures.style import FigureFile

__all__ = [
    "CONTENT_SECURITY_POLICY",
    "Figure",
    "Paragraph",
    "Preformatted",
    "Section",
    "Table",
    "format_number",
    "render_report",
    "software_versions",
    "table_html",
    "write_report",
]

#: forbids every request but inline styles and data: images (no script at all)
CONTENT_SECURITY_POLICY = "default-src 'none'; img-src data:; style-src 'unsafe-inline'"


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
    """A table: ``header`` and ``rows`` of cells. Strings are shown as given (left-aligned);
    numbers right-aligned with ``number_format`` (or their column's ``column_formats``),
    never as a negative zero (:func:`format_number`); None and non-finite numbers as a dash.
    ``highlight`` holds (row, column) indices of cells to emphasise."""

    header: Sequence[str]
    rows: Sequence[Sequence[Any]]
    caption: str = ""
    number_format: str = ".1f"
    highlight: frozenset[tuple[int, int]] = field(default_factory=frozenset)
    #: a format per column for its numbers (None or missing: ``number_format``)
    column_formats: Sequence[str | None] = ()


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
div.table { overflow-x: auto; max-width: 100%; margin: 0.6em 0 1.2em; }
table { border-collapse: collapse; font-size: 0.9em; }
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


def format_number(value: float, spec: str) -> str:
    """``format(value, spec)`` without a negative zero: a value that rounds to zero is
    printed as zero is ("-0.04" at ".1f" is "0.0", at "+.1f" "+0.0")."""
    text = format(value, spec)
    digits = text.strip()
    if digits[:1] == "-" and digits.lstrip("+-").strip("0.") == "":
        text = format(0.0, spec)
    return text


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
        return _esc(format_number(value, number_format)), True
    return _esc(value), False


def _render_table(table: Table) -> str:
    """The table in a box that scrolls sideways when the page is narrower than the table (a
    coefficient table of six fits is ~900 px wide): the page itself never does."""
    out = ['<div class="table"><table>']
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
            spec = (table.column_formats[j] if j < len(table.column_formats) else None)
            text, numeric = _cell(value, spec or table.number_format)
            classes = (["num"] if numeric else []) + (["warn"] if (i, j) in table.highlight
                                                      else [])
            cls = f' class="{" ".join(classes)}"' if classes else ""
            cells.append(f"<td{cls}>{text}</td>")
        out.append("<tr>" + "".join(cells) + "</tr>")
    out.append("</tbody></table></div>")
    return "\n".join(out)


def table_html(table: Table) -> str:
    """The HTML of one table as a report shows it (a notebook shows results with it)."""
    return _render_table(table)


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
    return write_file(path, text)

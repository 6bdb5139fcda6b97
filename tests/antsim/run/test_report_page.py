"""report.html of ``antsim run`` (antsim.run.report): every figure written, sane, not blank and
embedded byte for byte; the tables match fit.json/truth.json; nothing is requested from the
network; identical bytes run to run; ``--no-report``; the generic writer escapes and refuses
bad blocks; and the page opened in a real headless browser (Debian's chromium; skipped when
it is absent) renders without a console message and decodes every image.
"""

from __future__ import annotations

import base64
import json
import os
import re
import shutil
import subprocess
import warnings
from html.parser import HTMLParser
from pathlib import Path

import pytest

from antsim.cli import main
from antsim.figures.html import (
    CONTENT_SECURITY_POLICY,
    Figure,
    Paragraph,
    Preformatted,
    Section,
    Table,
    render_report,
    software_versions,
    write_report,
)
from tests.antsim.figures.test_figures import assert_sane_png, png_stats

REPO = Path(__file__).resolve().parents[3]
GHIGO = REPO / "scenarios" / "ghigo1990.toml"
QUIET = REPO / "tests" / "data" / "scenarios" / "quiet.toml"
IMG = re.compile(r'<img src="data:image/png;base64,([A-Za-z0-9+/=]+)"[^>]*data-file="([^"]+)"')


@pytest.fixture(scope="module")
def ghigo_run(tmp_path_factory) -> Path:
    """``antsim run scenarios/ghigo1990.toml --out DIR`` (the 24-hour run), once."""
    out = tmp_path_factory.mktemp("run") / "ghigo1990"
    assert main(["run", str(GHIGO), "--out", str(out), "--no-progress"]) == 0
    return out


def _embedded(html: str) -> dict[str, bytes]:
    return {name: base64.b64decode(data) for data, name in IMG.findall(html)}


class _PageReader(HTMLParser):
    """The tables (by caption: header and rows of cell texts) and figure captions (by file)
    of a report page."""

    def __init__(self):
        super().__init__()
        self.tables: dict[str, list[list[str]]] = {}
        self.captions: dict[str, str] = {}
        self._text: list[str] | None = None
        self._rows: list[list[str]] = []
        self._caption = ""
        self._figure = ""

    def handle_starttag(self, tag, attrs):
        if tag == "table":
            self._rows, self._caption = [], ""
        elif tag == "tr":
            self._rows.append([])
        elif tag in ("td", "th", "caption", "figcaption"):
            self._text = []
        elif tag == "img":
            self._figure = dict(attrs).get("data-file", "")

    def handle_data(self, data):
        if self._text is not None:
            self._text.append(data)

    def handle_endtag(self, tag):
        text = "".join(self._text or [])
        if tag in ("td", "th"):
            self._rows[-1].append(text)
        elif tag == "caption":
            self._caption = text
        elif tag == "figcaption":
            self.captions[self._figure] = text
        elif tag == "table":
            self.tables[self._caption] = self._rows
        if tag in ("td", "th", "caption", "figcaption"):
            self._text = None


def read_page(path: Path) -> _PageReader:
    """A report page's tables ``{caption: [header, *rows]}`` and figure captions
    ``{file name: title and caption}``, as the browser shows their text."""
    reader = _PageReader()
    reader.feed(path.read_text(encoding="utf-8"))
    return reader


def test_report_embeds_every_figure_of_the_run(ghigo_run):
    html = (ghigo_run / "report.html").read_text(encoding="utf-8")
    files = sorted((ghigo_run / "figures").glob("*.png"))
    assert len(files) >= 8
    embedded = _embedded(html)
    assert set(embedded) == {f.name for f in files}
    assert html.count("<img ") == len(files)
    for f in files:
        assert_sane_png(f)
        assert embedded[f.name] == f.read_bytes(), f"{f.name} embedded differs from the file"


def test_report_requests_nothing_from_the_network(ghigo_run):
    html = (ghigo_run / "report.html").read_text(encoding="utf-8")
    assert "http://" not in html and "https://" not in html
    assert "<script" not in html and "<link" not in html and "url(" not in html
    assert "@import" not in html
    for attr, value in re.findall(r'\b(src|href|action|poster|srcset)="([^"]*)"', html):
        assert (attr == "src" and value.startswith("data:image/png;base64,")) or \
            (attr == "href" and value.startswith("#")), f'{attr}="{value[:60]}"'
    assert f'content="{CONTENT_SECURITY_POLICY}"' in html


def _row(html: str, caption: str, first_cell: str) -> list[str]:
    """The cells of the row starting with ``first_cell`` in the table with ``caption``."""
    table = html.split(f"<caption>{caption}</caption>", 1)[1].split("</table>", 1)[0]
    for row in re.findall(r"<tr>(.*?)</tr>", table):
        cells = re.findall(r"<td[^>]*>(.*?)</td>", row)
        if cells and cells[0] == first_cell:
            return cells
    raise AssertionError(f"no row {first_cell!r} in table {caption!r}")


def test_report_tables_match_the_fits_and_the_truth(ghigo_run):
    html = (ghigo_run / "report.html").read_text(encoding="utf-8")
    variants = json.loads((ghigo_run / "fit_variants.json").read_text())
    for name, fit in variants.items():
        cells = _row(html, "Residuals of the fits (the 1990 report&#x27;s Table 2)", name)
        if fit is None:
            continue
        assert cells[2:7] == [str(fit["n_input"]), str(fit["n_used"]),
                              f"{fit['xel_rms_arcsec']:.1f}", f"{fit['el_rms_arcsec']:.1f}",
                              f"{fit['sky_rms_arcsec']:.1f}"]
    assert _row(html, "Residuals of the fits (the 1990 report&#x27;s Table 2)", "A")[7:] == \
        ["23.0", "38.0"]  # the report's own Table 2 beside ours
    fit = json.loads((ghigo_run / "fit.json").read_text())
    truth = json.loads((ghigo_run / "truth.json").read_text())
    for term, entry in fit["terms"].items():
        value, sigma = entry["value_arcsec"], entry["sigma_arcsec"]
        honest = entry["sigma_honest_arcsec"]
        # the recoverable truth: the mount's terms plus the fit's shares of the effects
        true = truth["recoverable"]["terms"][term]["value_arcsec"]
        cells = _row(html, "Coefficients against the recoverable truth", term)
        expected = [f"{true:.2f}", f"{value:.2f}", f"{value - true:.2f}", f"{sigma:.2f}",
                    f"{(value - true) / sigma:.2f}", f"{honest:.2f}",
                    f"{(value - true) / honest:.2f}"]
        expected = ["0.00" if e in ("-0.00",) else e for e in expected]
        assert cells[1:] == expected, term


def test_report_lists_the_software_versions_and_the_scenario(ghigo_run):
    html = (ghigo_run / "report.html").read_text(encoding="utf-8")
    versions = software_versions()
    assert set(versions) >= {"antsim", "numpy", "scipy", "astropy", "simpy", "matplotlib",
                             "python"}
    for package, version in versions.items():
        assert f"<td>{package}</td><td>{version}</td>" in html
    assert "W6 = 12.24" in html  # the scenario text is there


def test_writing_the_outputs_warns_nothing(tmp_path):
    """The fits, files, figures and report are written in the command's own process, with
    no warning on the way (matplotlib's, numpy's, ...: they would reach the user's stderr).
    Ported from the test of the forked output process, removed with it."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert main(["run", str(QUIET), "--out", str(tmp_path / "quiet"), "--no-progress"]) == 0
    assert [str(w.message) for w in caught] == []
    assert (tmp_path / "quiet" / "report.html").exists()


def test_same_run_twice_gives_identical_figures_and_report(ghigo_run, tmp_path):
    again = tmp_path / "again"
    assert main(["run", str(GHIGO), "--out", str(again), "--no-progress"]) == 0
    first = {p.name: p.read_bytes() for p in (ghigo_run / "figures").glob("*.png")}
    second = {p.name: p.read_bytes() for p in (again / "figures").glob("*.png")}
    assert first.keys() == second.keys()
    for name in first:
        assert first[name] == second[name], f"{name} differs between two identical runs"
    assert (ghigo_run / "report.html").read_bytes() == (again / "report.html").read_bytes()


def test_no_report_option_and_a_degenerate_run(tmp_path, capsys):
    """--no-report writes neither figures nor report; a noise-free one-hour run (residuals
    exactly 0) still gets a complete report."""
    bare, full = tmp_path / "bare", tmp_path / "full"
    assert main(["run", str(QUIET), "--out", str(bare), "--no-report", "--no-progress"]) == 0
    assert (bare / "fit.json").exists()
    assert not (bare / "report.html").exists() and not (bare / "figures").exists()
    assert "report.html" not in capsys.readouterr().out
    assert main(["run", str(QUIET), "--out", str(full), "--no-progress"]) == 0
    assert "report.html" in capsys.readouterr().out
    html = (full / "report.html").read_text(encoding="utf-8")
    assert len(_embedded(html)) == len(list((full / "figures").glob("*.png"))) >= 8


# ---------------------------------------------------------------------------------------------
# the generic writer
# ---------------------------------------------------------------------------------------------
def test_write_report_escapes_text_and_embeds_figures(tmp_path):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure as MplFigure

    fig = MplFigure(figsize=(2, 2), dpi=50)
    FigureCanvasAgg(fig)
    fig.add_subplot().plot([0, 1], [1, 0])
    png = tmp_path / "probe.png"
    fig.savefig(png)
    path = write_report(
        tmp_path / "r.html", "A <title> & more",
        [Section("One", [Paragraph("<script>alert(1)</script>\n\nsecond paragraph"),
                         Table(["a", "b"], [["x<y", 1.23456], [None, float("nan")]],
                               caption="T", number_format=".2f"),
                         Figure(png, "the title", "the caption"),
                         Preformatted("  keep   spaces <b>", caption="pre")])],
        versions={"antsim": "test"})
    html = path.read_text(encoding="utf-8")
    assert "<script>" not in html and "&lt;script&gt;alert(1)&lt;/script&gt;" in html
    assert "A &lt;title&gt; &amp; more" in html
    assert "<p>second paragraph</p>" in html
    assert "x&lt;y" in html and ">1.23<" in html and html.count("\N{EN DASH}") >= 2
    assert _embedded(html) == {"probe.png": png.read_bytes()}
    assert "<pre>  keep   spaces &lt;b&gt;</pre>" in html
    assert "<td>antsim</td><td>test</td>" in html


def test_write_report_refuses_bad_blocks(tmp_path):
    with pytest.raises(FileNotFoundError, match="does not exist"):
        render_report("t", [Section("s", [Figure(tmp_path / "missing.png")])])
    (tmp_path / "fake.png").write_text("not a png")
    with pytest.raises(ValueError, match="is not a PNG"):
        render_report("t", [Section("s", [Figure(tmp_path / "fake.png")])])
    with pytest.raises(ValueError, match="row 0 has 1 cells, the header 2"):
        render_report("t", [Section("s", [Table(["a", "b"], [["only one"]])])])
    with pytest.raises(TypeError, match="unknown report block"):
        render_report("t", [Section("s", ["a bare string"])])  # type: ignore[list-item]


# ---------------------------------------------------------------------------------------------
# a real browser
# ---------------------------------------------------------------------------------------------
def _find_chromium() -> str | None:
    """Debian's chromium; ANTSIM_CHROMIUM names another binary, or "none" to skip."""
    chosen = os.environ.get("ANTSIM_CHROMIUM", "")
    if chosen:
        return None if chosen.lower() == "none" else chosen
    return shutil.which("chromium") or ("/usr/bin/chromium"
                                        if Path("/usr/bin/chromium").exists() else None)


CHROMIUM = _find_chromium()
needs_chromium = pytest.mark.skipif(CHROMIUM is None, reason="chromium is not installed "
                                    "(apt-get install chromium)")


def run_chromium(page: Path, tmp_path: Path, *args: str) -> subprocess.CompletedProcess:
    """Headless chromium on ``page`` with no network services, logging the console."""
    cmd = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
           "--no-first-run", "--disable-background-networking", "--disable-component-update",
           "--disable-sync", "--disable-extensions", f"--user-data-dir={tmp_path / 'profile'}",
           "--enable-logging=stderr", "--v=0", *args, page.resolve().as_uri()]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=120, check=False)


def console_lines(stderr: str) -> list[str]:
    """Console messages of the page (chromium logs them as ``...:CONSOLE...``), and any
    uncaught exception."""
    return [line for line in stderr.splitlines() if ":CONSOLE" in line or "Uncaught" in line]


@needs_chromium
def test_console_detector_catches_a_broken_page(tmp_path):
    """The browser check can fail: a page with a script error and a blocked network image."""
    page = tmp_path / "broken.html"
    page.write_text(
        '<!DOCTYPE html><html><head><meta charset="utf-8"><meta http-equiv='
        f'"Content-Security-Policy" content="{CONTENT_SECURITY_POLICY}; script-src '
        "'unsafe-inline'\"></head><body><img src=\"http://example.invalid/x.png\">"
        "<script>undefinedFunction();</script></body></html>", encoding="utf-8")
    proc = run_chromium(page, tmp_path, "--dump-dom")
    lines = console_lines(proc.stderr)
    assert any("Uncaught" in line for line in lines)
    assert any("Content Security Policy" in line for line in lines)


def assert_renders_in_a_browser(page: Path, tmp_path: Path, n_images: int) -> None:
    """``page`` in headless chromium: no console message, a screenshot that is not blank, and
    every one of its ``n_images`` embedded images decoded."""
    shot = tmp_path / "report.png"
    proc = run_chromium(page, tmp_path, f"--screenshot={shot}", "--window-size=1280,2000")
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert console_lines(proc.stderr) == []
    assert shot.exists() and shot.stat().st_size > 10_000
    std, ink = png_stats(shot)
    assert std > 0.03 and ink > 0.01, f"screenshot looks blank (std {std:.3f}, ink {ink:.3f})"
    # every embedded image decodes in the browser: a copy of the page with a probe script
    # (the report itself has none, and its policy forbids scripts)
    html = page.read_text(encoding="utf-8")
    probe = ("<script>window.addEventListener('load', function () {"
             "var n = 0; for (var i = 0; i < document.images.length; i++) {"
             "var im = document.images[i]; if (im.complete && im.naturalWidth > 0) n++; }"
             "document.body.setAttribute('data-probe', document.images.length + ' ' + n);"
             "});</script>")
    probed = tmp_path / "probe.html"
    probed.write_text(html.replace("default-src 'none';",
                                   "default-src 'none'; script-src 'unsafe-inline';", 1)
                      .replace("</body>", probe + "</body>", 1), encoding="utf-8")
    proc = run_chromium(probed, tmp_path, "--dump-dom", "--virtual-time-budget=5000")
    assert f'data-probe="{n_images} {n_images}"' in proc.stdout
    assert console_lines(proc.stderr) == []


@needs_chromium
def test_report_in_a_headless_browser(ghigo_run, tmp_path):
    assert_renders_in_a_browser(ghigo_run / "report.html", tmp_path,
                                len(list((ghigo_run / "figures").glob("*.png"))))

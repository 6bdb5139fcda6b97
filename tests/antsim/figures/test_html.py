"""antsim/figures/html.py: a page stays readable on a narrow screen (a table wider than the
window scrolls in its own box, the page does not); numbers in tables are right-aligned and
never a negative zero."""

from __future__ import annotations

import re

import pytest

from antsim.figures.html import Section, Table, _render_table, format_number, render_report
from tests.antsim.run.test_report_page import needs_chromium, run_chromium

#: a coefficient table as a run's report has it: a term and 12 columns of numbers
WIDE = Table(["term", *(f"fit {k} (\")" for k in "ABCDEFGHIJKL")],
             [[f"W{i}", *(-123.456 * (i + k) for k in range(12))] for i in range(1, 11)],
             caption="Coefficients (arcsec)", number_format="+.2f")


def test_every_table_is_in_a_box_that_scrolls_sideways():
    page = render_report("t", [Section("s", [WIDE, Table(["a"], [[1]])])])
    tables = page.count("<table>")
    assert tables == 3  # the two and the software versions
    assert page.count('<div class="table"><table>') == page.count("</table></div>") == tables
    css = re.search(r"div\.table \{([^}]*)\}", page).group(1)
    assert "overflow-x: auto" in css and "max-width: 100%" in css


@needs_chromium
def test_a_wide_table_does_not_widen_the_page_at_800_px(tmp_path):
    """In a browser 800 px wide the page is no wider than the window (the table's box
    scrolls) while the table itself is wider: the box is what keeps the page."""
    page = render_report("t", [Section("s", [WIDE])])
    probe = ("<script>window.addEventListener('load', function () {"
             "var t = document.querySelector('table');"
             "document.body.setAttribute('data-probe', document.documentElement.scrollWidth"
             " + ' ' + window.innerWidth + ' ' + t.scrollWidth);});</script>")
    probed = tmp_path / "narrow.html"
    probed.write_text(page.replace("default-src 'none';",
                                   "default-src 'none'; script-src 'unsafe-inline';", 1)
                      .replace("</body>", probe + "</body>", 1), encoding="utf-8")
    proc = run_chromium(probed, tmp_path, "--dump-dom", "--window-size=800,600",
                        "--virtual-time-budget=5000")
    page_w, window_w, table_w = map(int, re.search(r'data-probe="(\d+) (\d+) (\d+)"',
                                                   proc.stdout).groups())
    assert table_w > window_w  # the test shows something: the table does not fit
    assert page_w <= window_w


@pytest.mark.parametrize(("value", "spec", "text"), [
    (-0.04, ".1f", "0.0"), (-0.04, "+.1f", "+0.0"), (-0.004, "+9.2f", "    +0.00"),
    (-0.06, "+.1f", "-0.1"), (0.04, "+.1f", "+0.0"), (-12.5, ".2f", "-12.50"),
    (-0.0, "g", "0")])
def test_a_number_that_rounds_to_zero_is_printed_as_zero(value, spec, text):
    assert format_number(value, spec) == text


def test_table_numbers_take_their_columns_format_and_are_right_aligned():
    html = _render_table(Table(("name", "bias", "sigma"), [["W5", -0.04, 2.9213]],
                               column_formats=(None, "+.1f", ".2f")))
    assert '<td>W5</td><td class="num">+0.0</td><td class="num">2.92</td>' in html

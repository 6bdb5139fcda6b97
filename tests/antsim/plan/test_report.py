"""antsim/plan/report.py: the plan's page shows its numbers as numbers."""

from __future__ import annotations

import json
import re
from html import escape

from antsim.plan.report import TERMS_HEADER, VARIANTS_HEADER, write_plan_report
from tests.antsim.run.test_report_page import (
    _embedded,
    assert_renders_in_a_browser,
    needs_chromium,
    read_page,
)


def _doc() -> dict:
    term = {"truth_arcsec": 48.0, "sigma_fisher_arcsec": 2.92, "sigma_mc_arcsec": 3.12,
            "bias_arcsec": 0.21, "bias_predicted_arcsec": -0.04}
    return {"plan": "p", "description": "", "scenario": "s", "seed": 1, "units": "arcsec",
            "sign_convention": "indicated minus true", "answers": {},
            "plans": [{"name": "night only", "description": "", "duration_h": 24.0,
                       "n_scans": 136, "n_monte_carlo": 200, "sky_rms_fisher_arcsec": 31.1,
                       "sky_rms_mc_arcsec": 31.14, "terms": {"W5": term},
                       "cannot_separate": []}]}


def test_numbers_are_right_aligned_and_no_zero_is_negative(tmp_path):
    """Every number cell of both tables is a number cell (right-aligned), at plan.txt's
    precision; a predicted bias of -0.04" reads +0.0, not -0.0."""
    page = write_plan_report(_doc(), "plan.txt\n", [], tmp_path).read_text()
    rows = re.findall(r"<tr>(.*?)</tr>", page, re.S)
    cells = [re.findall(r"<td([^>]*)>([^<]*)</td>", row) for row in rows]
    cells = [c for c in cells if c][:2]  # the variants' and the terms' (then versions)
    assert [text for _, text in cells[0]] == ["night only", "24.0", "136", "200", "31.1",
                                              "31.1"]
    assert [text for _, text in cells[1]] == ["W5", "+48.0", "2.92", "3.12", "+0.2", "+0.0"]
    for row in cells:
        assert row[0][0] == ""  # the name, text
        assert all(attrs == ' class="num"' for attrs, _ in row[1:])
    assert len(cells[0]) == len(VARIANTS_HEADER) and len(cells[1]) == len(TERMS_HEADER)
    assert "-0.0" not in page


def test_plan_page_numbers_are_the_json_numbers(plan_out):
    """report.html: the variants' and terms' numbers are plan.json's at plan.txt's precision
    (one source), plan.txt is on the page whole, every figure embedded byte for byte."""
    from antsim.figures.html import format_number
    from antsim.plan.report import TERMS_HEADER, VARIANTS_HEADER

    _, out = plan_out
    doc = json.loads((out / "plan.json").read_text())
    page = read_page(out / "report.html")

    def f(x, spec):
        return "\N{EN DASH}" if x is None else format_number(x, spec)

    assert page.tables["The plan's variants"] == [list(VARIANTS_HEADER)] + [
        [p["name"], f(p["duration_h"], ".1f"), str(p["n_scans"]), str(p["n_monte_carlo"]),
         f(p["sky_rms_fisher_arcsec"], ".1f"), f(p["sky_rms_mc_arcsec"], ".1f")]
        for p in doc["plans"]]
    text = (out / "plan.txt").read_text()
    for p in doc["plans"]:
        rows = page.tables[f"{p['name']}: the fitted terms (arcsec)"]
        assert rows == [list(TERMS_HEADER)] + [
            [n, f(t["truth_arcsec"], "+.1f"), f(t["sigma_fisher_arcsec"], ".2f"),
             f(t["sigma_mc_arcsec"], ".2f"), f(t["bias_arcsec"], "+.1f"),
             f(t["bias_predicted_arcsec"], "+.1f")] for n, t in p["terms"].items()]
        for n, t in p["terms"].items():  # the same figures as plan.txt's table
            assert re.search(rf"^  {n} .*{f(t['sigma_fisher_arcsec'], '.2f')}", text, re.M)
        assert f"predicted {f(p['sky_rms_fisher_arcsec'], '.1f')}\"" in text
    html = (out / "report.html").read_text()
    assert escape(text.rstrip("\n")) in html
    embedded = _embedded(html)
    pngs = sorted(x.name for x in out.glob("*.png"))
    assert sorted(embedded) == pngs and len(pngs) >= 4
    assert all(embedded[n] == (out / n).read_bytes() for n in pngs)


@needs_chromium
def test_plan_page_in_a_headless_browser(plan_out, tmp_path):
    _, out = plan_out
    assert_renders_in_a_browser(out / "report.html", tmp_path, len(list(out.glob("*.png"))))

"""antsim/plan/report.py: the plan's page shows its numbers as numbers."""

from __future__ import annotations

import re

from antsim.plan.report import TERMS_HEADER, VARIANTS_HEADER, write_plan_report


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

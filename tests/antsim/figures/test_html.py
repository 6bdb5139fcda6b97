"""antsim/figures/html.py: numbers in tables, right-aligned and never a negative zero."""

from __future__ import annotations

import pytest

from antsim.figures.html import Table, _render_table, format_number


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

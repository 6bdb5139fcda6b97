"""Times UTC can hold: ERFA's known years, leap seconds, the campaign's end."""

from __future__ import annotations

import pytest

from antsim.schema.utc import FIRST_UTC_YEAR, end_problem, last_known_year, utc_known, utc_time
from antsim.tomlcheck import Table
from controller.errors import InputError


def problem(text: str) -> str:
    with pytest.raises(InputError) as err:
        utc_time(Table({}, "f.toml", "campaign"), "start_utc", text)
    return err.value.problem


def test_a_time_reads_as_astropy_writes_it():
    assert utc_time(Table({}, "f", ""), "t", "1990-02-08T17:00:00") == "1990-02-08T17:00:00.000"
    assert utc_time(Table({}, "f", ""), "t", "1990-02-08 17:00") == "1990-02-08T17:00:00.000"


def test_the_known_years_are_erfa_s():
    assert utc_known(FIRST_UTC_YEAR) and not utc_known(FIRST_UTC_YEAR - 1)
    last = last_known_year()
    assert last >= 2025 and utc_known(last) and not utc_known(last + 1)


@pytest.mark.parametrize("text, says", [
    ("1990-02-30T17:00:00", "not an ISO UTC time"),
    ("3000-01-01T00:00:00", "year outside 1900..2200"),
    ("1959-12-31T23:00:00", "UTC is known from 1960"),
    ("2150-01-01T00:00:00", "UTC is known from 1960"),
    ("1990-12-31T23:59:60", "is a leap second"),
    ("1990-12-31T23:59:60.5", "is a leap second"),
    ("1990-02-08T23:59:60", "has a 60th second on a day without a leap second"),
])
def test_times_utc_cannot_hold(text, says):
    assert says in problem(text)


def test_a_campaign_ending_beyond_the_known_years():
    last = last_known_year()
    assert end_problem(f"{last}-12-30T00:00:00", 86400.0) == ""
    assert end_problem(f"{last}-12-30T00:00:00", 3 * 86400.0).startswith(
        f"the campaign ends on {last + 1}-01-02: UTC is known from 1960 to {last} only")

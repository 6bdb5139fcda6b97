"""A campaign's times as UTC can hold them: an ISO time ERFA knows the leap seconds of.

UTC exists from 1960 (before, there were no atomic clocks to steer it by), and its leap
seconds are announced months ahead: ERFA (through astropy) tabulates them up to a few years
after its release and calls a later year "dubious". A campaign there would run on guessed
time (and ERFA would warn at every conversion), so a start or an end outside the known years
is refused by name, as is a leap second as the start (23:59:60: the simulation's clock counts
seconds from the start and cannot begin inside one) and a 60th second on a day without one.
"""

from __future__ import annotations

import warnings
from datetime import datetime, timedelta
from functools import lru_cache

import erfa
from astropy.time import Time

from ..tomlcheck import Table

__all__ = ["FIRST_UTC_YEAR", "last_known_year", "utc_known", "utc_time"]

#: UTC's first year (its definition begins on 1960 January 1)
FIRST_UTC_YEAR = 1960
#: the years a scenario's time may name at all (a coarse bound, before the leap seconds')
YEARS = (1900, 2200)


@lru_cache(maxsize=256)
def utc_known(year: int, month: int = 1, day: int = 1) -> bool:
    """Whether ERFA knows UTC's offset from atomic time on this day."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", erfa.ErfaWarning)
        try:
            erfa.dat(year, month, day, 0.5)
        except erfa.ErfaWarning:
            return False
    return True


@lru_cache(maxsize=1)
def last_known_year() -> int:
    """The last year ERFA knows the leap seconds of (its release year plus a few)."""
    year = 2020
    while utc_known(year + 1):
        year += 1
    return year


def unknown_text() -> str:
    return (f"UTC is known from {FIRST_UTC_YEAR} to {last_known_year()} only (ERFA's leap "
            "seconds); a campaign outside runs on guessed time")


@lru_cache(maxsize=256)
def _parsed(text: str) -> tuple[str, tuple[int, int, int], float, bool] | None:
    """(ISO time, (year, month, day), second, ERFA found a 60th second past the day's end)
    of ``text``, or None where astropy reads no UTC time (a scenario is read many times in
    a plan and in the tests: one parse per text)."""
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", erfa.ErfaWarning)
            epoch = Time(text, scale="utc")
            iso, when = epoch.isot, epoch.ymdhms
    except (ValueError, TypeError):
        return None
    past_day = any("after end of day" in str(w.message) for w in caught)
    return (iso, (int(when["year"]), int(when["month"]), int(when["day"])),
            float(when["second"]), past_day)


def utc_time(table: Table, name: str, text: str) -> str:
    """``text`` (the value of key ``name``) as astropy's ISO UTC time, or one InputError line:
    not a time, a year outside 1900..2200, a year whose UTC ERFA does not know, a leap second,
    a 60th second on a day without one."""
    parsed = _parsed(text)
    if parsed is None:
        raise table.error(name, text, "not an ISO UTC time", "write e.g. 1990-02-08T17:00:00")
    iso, day, second, past_day = parsed
    if not YEARS[0] <= day[0] <= YEARS[1]:
        raise table.error(name, text, f"year outside {YEARS[0]}..{YEARS[1]}")
    if not utc_known(*day):
        raise table.error(name, text, unknown_text())
    if second >= 60.0:
        raise table.error(name, text, "is a leap second: the campaign's clock cannot start "
                          "inside one", "start a second later, at the next minute")
    if past_day:
        raise table.error(name, text, "has a 60th second on a day without a leap second",
                          "write the next minute")
    return iso


def end_problem(epoch_iso: str, duration_s: float) -> str:
    """Why a campaign from ``epoch_iso`` lasting ``duration_s`` ends where UTC is not known
    ("" when it does not). The end's day is counted in plain days: a leap second moves it by
    a second, not a day that matters here."""
    end = datetime.fromisoformat(epoch_iso[:19]) + timedelta(seconds=duration_s)
    if utc_known(end.year, end.month, end.day):
        return ""
    return f"the campaign ends on {end:%Y-%m-%d}: {unknown_text()}"

"""Checking tables read from files (ECSV recordings, CSV pointing data): units, values, rows.

The readers describe each column they know by a :class:`ColumnRule` (unit held inside,
allowed range, whether NaN may stand for "no value"); these helpers convert a column from the
unit a file declares into that unit, or refuse it, and find the first value out of range,
the first repeated row, always as one :class:`~controller.errors.InputError` line naming
``file:line``, the column and the value.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import astropy.units as u
import numpy as np

from controller.errors import InputError

__all__ = ["ColumnRule", "check_range", "first_repeat", "unit_factor"]


@dataclass(frozen=True)
class ColumnRule:
    """What a numeric column must hold: values in ``unit`` (None: a pure number) within
    ``lo``..``hi`` (None: unbounded); ``finite``: NaN (no value) refused as well; infinity is
    always refused."""

    name: str
    unit: str | None = None
    lo: float | None = None
    hi: float | None = None
    finite: bool = False


def unit_factor(given: str | None, rule: ColumnRule, where: str, named: bool = False,
                hint: str = ""):
    """A function converting values in unit ``given`` (a file's unit string; None or "" when
    the file names none) into ``rule.unit``; InputError when they are not convertible. A
    column without a unit is in ``rule.unit`` when its name says so (``named``: ``az_deg``);
    otherwise it must declare one: a bare number could be any unit."""
    want = u.dimensionless_unscaled if rule.unit is None else u.Unit(rule.unit)
    if not given:
        if rule.unit is None or named:
            return lambda v: v
        raise InputError(where, f"{rule.name}.unit", "<none>", f"needs a unit ({rule.unit})",
                         hint or f"declare it in the header, e.g. unit: {rule.unit}")
    try:
        unit = u.Unit(given, parse_strict="raise")
    except ValueError:
        raise InputError(where, f"{rule.name}.unit", given, "is not a unit astropy knows",
                         f"expected {rule.unit or 'no unit'} or one convertible to it") from None
    if unit == want:
        return lambda v: v
    equivalencies = u.temperature()
    try:
        unit.to(want, equivalencies=equivalencies)
    except u.UnitConversionError:
        raise InputError(where, f"{rule.name}.unit", given,
                         f"cannot be converted to {rule.unit or 'a pure number'}") from None
    return lambda v: (np.asarray(v, dtype=float) * unit).to_value(want,
                                                                   equivalencies=equivalencies)


def check_range(values: np.ndarray, rule: ColumnRule, path: str, lines: Sequence[int],
                rows: np.ndarray | None = None, shown=None) -> None:
    """InputError for the first row (of ``rows``, a boolean mask; all by default) whose value
    is infinite, NaN where ``rule.finite``, or outside ``rule.lo``..``rule.hi``. ``lines``:
    each row's line in the file. ``shown``: the values as written, for the message (default
    ``values``)."""
    values = np.asarray(values, dtype=float)
    bad = np.isinf(values)
    if rule.finite:
        bad |= np.isnan(values)
    with np.errstate(invalid="ignore"):
        if rule.lo is not None:
            bad |= values < rule.lo
        if rule.hi is not None:
            bad |= values > rule.hi
    if rows is not None:
        bad &= rows
    if not bad.any():
        return
    i = int(np.flatnonzero(bad)[0])
    value = float((values if shown is None else np.asarray(shown, dtype=float))[i])
    unit = f" {rule.unit}" if rule.unit else ""
    if np.isnan(values[i]):
        problem = "has no value (NaN) where one is needed"
    elif np.isinf(values[i]):
        problem = "is infinite"
    else:
        lo = "-inf" if rule.lo is None else f"{rule.lo:g}"
        hi = "+inf" if rule.hi is None else f"{rule.hi:g}"
        problem = f"is outside {lo}..{hi}{unit}"
        if value != values[i]:  # converted from the file's unit
            problem = f"is {values[i]:.6g}{unit}, outside {lo}..{hi}{unit}"
    raise InputError(f"{path}:{lines[i]}", rule.name, value, problem)


def first_repeat(keys: Sequence[np.ndarray]) -> tuple[int, int] | None:
    """The first row whose key (the tuple of ``keys`` arrays) an earlier row already has, as
    (earlier row, row); None when every key is unique."""
    n = len(keys[0]) if keys else 0
    if n < 2:
        return None
    codes = np.stack([np.unique(np.asarray(k), return_inverse=True)[1].reshape(-1)
                      for k in keys], axis=1)
    _, first, inverse = np.unique(codes, axis=0, return_index=True, return_inverse=True)
    repeated = np.flatnonzero(first[inverse.reshape(-1)] != np.arange(n))
    if repeated.size == 0:
        return None
    row = int(repeated[0])
    return int(first[inverse.reshape(-1)[row]]), row

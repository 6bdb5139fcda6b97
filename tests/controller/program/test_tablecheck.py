"""Checking tables read from files (controller.program.tablecheck): units converted or
refused, the first bad value and the first repeated row named as one line."""

from __future__ import annotations

import numpy as np
import pytest

from controller.errors import InputError
from controller.program.tablecheck import ColumnRule, check_range, first_repeat, unit_factor

AZ = ColumnRule("az", unit="deg", lo=0.0, hi=360.0, finite=True)
TEMPERATURE = ColumnRule("temperature", unit="deg_C", lo=-60.0, hi=60.0)


def test_a_declared_unit_is_converted_into_the_rules():
    assert unit_factor("rad", AZ, "f.ecsv")(np.pi) == pytest.approx(180.0)
    assert unit_factor("deg", AZ, "f.ecsv")(12.5) == 12.5
    # temperatures convert with an offset, not a factor
    assert unit_factor("K", TEMPERATURE, "f.ecsv")(273.15) == pytest.approx(0.0, abs=1e-9)


def test_a_column_without_a_unit_needs_one_unless_its_name_says_it():
    assert unit_factor(None, AZ, "f.csv", named=True)(3.0) == 3.0
    assert unit_factor("", ColumnRule("weight"), "f.csv")(3.0) == 3.0
    with pytest.raises(InputError) as err:
        unit_factor(None, AZ, "f.csv")
    assert str(err.value) == ("f.csv: az.unit = '<none>': needs a unit (deg); declare it in the "
                              "header, e.g. unit: deg")


@pytest.mark.parametrize("given, problem", [("furlong_per_fortnight", "is not a unit astropy"),
                                            ("m", "cannot be converted to deg")])
def test_a_unit_that_is_unknown_or_not_convertible_is_refused(given, problem):
    with pytest.raises(InputError, match=f"^f.ecsv: az.unit = '{given}': {problem}"):
        unit_factor(given, AZ, "f.ecsv")


@pytest.mark.parametrize("values, line, problem", [
    ([10.0, 400.0, -5.0], 12, "az = 400.0: is outside 0..360 deg"),
    ([10.0, 20.0, np.nan], 13, "az = nan: has no value (NaN) where one is needed"),
    ([np.inf, 20.0, 30.0], 11, "az = inf: is infinite"),
])
def test_the_first_bad_value_is_named_with_its_line(values, line, problem):
    with pytest.raises(InputError) as err:
        check_range(np.array(values), AZ, "f.ecsv", [11, 12, 13])
    assert str(err.value) == f"f.ecsv:{line}: {problem}"


def test_nan_may_mean_no_value_and_rows_outside_the_mask_are_not_checked():
    check_range(np.array([np.nan, 0.0]), TEMPERATURE, "f.csv", [2, 3])
    check_range(np.array([10.0, 400.0]), AZ, "f.csv", [2, 3], rows=np.array([True, False]))


def test_a_converted_value_is_shown_as_written_and_as_converted():
    # the message quotes the file's number (here radians) and what it is in the rule's unit
    with pytest.raises(InputError) as err:
        check_range(np.array([400.0]), AZ, "f.csv", [5], shown=np.array([6.98]))
    assert str(err.value) == "f.csv:5: az = 6.98: is 400 deg, outside 0..360 deg"


def test_the_first_repeated_row_is_found_with_the_row_it_repeats():
    names = np.array(["a", "b", "a", "b"])
    times = np.array([1.0, 1.0, 2.0, 1.0])
    assert first_repeat([names, times]) == (1, 3)
    assert first_repeat([names]) == (0, 2)
    assert first_repeat([names[:2], times[:2]]) is None
    assert first_repeat([np.array([1.0])]) is None

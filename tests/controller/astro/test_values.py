"""Validated numbers shared by the astro modules (controller.astro.values)."""

from __future__ import annotations

from dataclasses import dataclass

import astropy.units as u
import numpy as np
import pytest

from controller.astro.values import finite_fields, require_finite, scalar, seconds_value


@pytest.mark.parametrize("value, problem", [("abc", "is not a number"), (None, "is not a number"),
                                            (float("nan"), "is not finite"),
                                            (float("-inf"), "is not finite")])
def test_a_value_that_is_no_finite_number_is_refused_by_name(value, problem):
    with pytest.raises(ValueError, match=f"^height = .*{problem}"):
        require_finite(value, "height")


def test_finite_fields_stores_floats_on_a_frozen_dataclass_and_names_the_bad_one():
    @dataclass(frozen=True)
    class Place:
        lat: object
        lon: object

        def __post_init__(self):
            finite_fields(self, "site", "lat", "lon")

    place = Place(np.float32(38.5), "-79.5")
    assert (place.lat, place.lon) == (38.5, -79.5)
    assert type(place.lat) is float and type(place.lon) is float
    with pytest.raises(ValueError, match=r"^site lon = inf"):
        Place(1, float("inf"))


def test_seconds_from_a_number_or_a_time_quantity_only():
    assert seconds_value(90, "step") == 90.0
    assert seconds_value(1.5 * u.min, "step") == pytest.approx(90.0)
    with pytest.raises(ValueError, match="is not a time"):
        seconds_value(3 * u.m, "step")
    with pytest.raises(ValueError, match="is not finite"):
        seconds_value(float("nan") * u.s, "step")


def test_scalar_unwraps_zero_dimensional_arrays_only():
    assert isinstance(scalar(np.array(2.5)), np.floating)
    array = np.array([2.5])
    assert scalar(array) is array

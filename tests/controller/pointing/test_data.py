"""Pointing data (controller.pointing.data): what a set of observations refuses."""

from __future__ import annotations

import numpy as np
import pytest

from controller.pointing.data import PointingData


@pytest.mark.parametrize(("kwargs", "match"), [
    (dict(az_rad=[0.1, np.nan], el_rad=[0.5, 0.6], xel_arcsec=[1, 2], el_arcsec=[1, 2]), "NaN"),
    (dict(az_rad=[0.1, 0.2], el_rad=[0.5], xel_arcsec=[1, 2], el_arcsec=[1, 2]), "differ"),
    (dict(az_rad=[0.1], el_rad=[45.0], xel_arcsec=[1], el_arcsec=[1]), "radians"),
    (dict(az_rad=[[0.1]], el_rad=[[0.5]], xel_arcsec=[[1]], el_arcsec=[[1]]), "one-dim"),
    (dict(az_rad=["a"], el_rad=[0.5], xel_arcsec=[1], el_arcsec=[1]), "numbers"),
    (dict(az_rad=[0.1], el_rad=[0.5], xel_arcsec=[1], el_arcsec=[1], weight_xel=[1.0]),
     "both"),
    (dict(az_rad=[0.1], el_rad=[0.5], xel_arcsec=[1], el_arcsec=[1], weight_xel=[0.0],
          weight_el=[1.0]), "positive"),
])
def test_invalid_pointing_data_raise_value_error(kwargs, match):
    with pytest.raises(ValueError, match=match):
        PointingData(**kwargs)

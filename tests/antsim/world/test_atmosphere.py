"""The atmosphere (antsim.world.atmosphere): its emission seen through the airmass."""

from __future__ import annotations

import numpy as np
import pytest

from antsim.world.atmosphere import Atmosphere, AtmosphereConfig


def test_sky_emission_rises_with_airmass():
    atm = Atmosphere(AtmosphereConfig(zenith_opacity=0.01, temperature_k=265.0))
    el = np.radians([90.0, 30.0, 10.0])
    emission = atm.emission_k(el)
    # T_atm (1 - exp(-tau0 / sin E)): 2.64 K at the zenith, 5.25 K at 30 deg, 14.8 K at 10
    assert emission == pytest.approx(265.0 * (1 - np.exp(-0.01 / np.sin(el))), rel=1e-12)
    assert np.all(np.diff(emission) > 0)

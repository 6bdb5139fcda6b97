"""Geometric pointing errors as pointing-model terms (antsim.world.effects.geometric): the
encoders read true + the model's offset, in the sign convention of TPOINT's terms."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from antsim.world.effects import PointingState
from antsim.world.effects.geometric import GeometricEffect, TermsEffect
from controller.pointing.model import PointingModel
from controller.pointing.terms import TermError

ARCSEC = math.pi / 648000.0


def _state(az_deg: float, el_deg: float) -> PointingState:
    return PointingState(t_s=0.0, az_rad=math.radians(az_deg), el_rad=math.radians(el_deg))


@pytest.mark.parametrize("az_deg, el_deg", [(10.0, 20.0), (200.0, 75.0)])
def test_index_errors_are_indicated_minus_true_as_tpoint_writes_them(az_deg, el_deg):
    """TPOINT: dA = -IA, dE = +IE (docs/layout.md: errors are indicated minus true,
    corrections their negative)."""
    effect = TermsEffect({"IA": 30.0}, IE=-12.0)
    d_az, d_el = effect.pointing_error(_state(az_deg, el_deg))
    assert d_az == pytest.approx(30.0 * ARCSEC, rel=1e-12)
    assert d_el == pytest.approx(12.0 * ARCSEC, rel=1e-12)
    assert effect.terms == ("IA", "IE")


def test_a_term_grows_as_its_formula_says():
    """NPAE: azimuth error ~ tan(el); a model's offset at the true position is the error."""
    effect = GeometricEffect(PointingModel(["NPAE"], [10.0]))
    low = effect.pointing_error(_state(90.0, 30.0))[0]
    high = effect.pointing_error(_state(90.0, 60.0))[0]
    assert high / low == pytest.approx(math.tan(math.radians(60)) / math.tan(math.radians(30)))
    assert effect.p == {"model": "custom", "terms_arcsec": {"NPAE": 10.0}}


def test_the_block_error_is_the_pointing_error_on_arrays():
    effect = TermsEffect({"CA": 20.0, "TF": 5.0})
    az = np.radians([10.0, 100.0, 250.0])
    el = np.radians([15.0, 45.0, 80.0])
    state = PointingState(t_s=0.0, az_rad=az, el_rad=el)
    block = effect.block_error(state)
    for i in range(3):
        one = effect.pointing_error(_state(math.degrees(az[i]), math.degrees(el[i])))
        assert (block[0][i], block[1][i]) == pytest.approx(one, rel=1e-12)


def test_names_that_are_no_alt_az_terms_are_refused_on_an_alt_az_mount():
    altaz_world = SimpleNamespace(frame=SimpleNamespace(is_altaz=True))
    effect = TermsEffect({"NOT_A_TERM": 1.0})
    with pytest.raises(TermError, match="NOT_A_TERM are not all alt-az pointing terms"):
        effect.start(altaz_world, rng=None)

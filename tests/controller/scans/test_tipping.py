"""Tipping scans (controller.scans.tipping): the opacity fit on synthetic powers."""

from __future__ import annotations

import numpy as np
import pytest

from controller.scans.tipping import airmass, fit_opacity


def test_opacity_fit_finds_the_right_basin():
    # the cost of P = T0 + T_atm (1 - exp(-tau A)) has a shallow second minimum where the
    # atmosphere saturates; the grid search must find the physical one
    rng = np.random.default_rng(9)
    el = np.radians([88, 60, 40, 30, 23, 18, 14, 11.5])
    a = airmass(el)
    for tau in (0.002, 0.01, 0.05, 0.3):
        p = 45.0 + 265.0 * (1 - np.exp(-tau * a)) + 0.01 * rng.standard_normal(a.size)
        fit = fit_opacity(a, p, 265.0)
        assert fit.tau == pytest.approx(tau, rel=0.03, abs=2e-4)
        assert fit.t0_k == pytest.approx(45.0, abs=0.1)
    # a wrong assumed T_atm scales tau by about the same factor
    p = 45.0 + 265.0 * (1 - np.exp(-0.01 * a))
    assert fit_opacity(a, p, 260.0).tau == pytest.approx(0.01 * 265 / 260, rel=0.005)
    with pytest.raises(ValueError, match="at least three"):
        fit_opacity([1.0, 1.0, 1.0], [1.0, 2.0, 3.0], 265.0)

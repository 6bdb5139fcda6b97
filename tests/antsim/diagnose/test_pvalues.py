"""antsim.diagnose.pvalues against scipy.stats: the same special functions, to a few ulps."""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest
from scipy import stats

from antsim.diagnose import pvalues


def _same(a: float, b: float) -> bool:
    """Equal, or both NaN, or within four ulps: the same scipy.special functions as
    scipy.stats calls, equal to the bit with scipy 1.17; scipy 1.11's stats takes the log of
    the tail by another route, one ulp away (chi2.logsf(200, 3))."""
    return ((math.isnan(a) and math.isnan(b)) or a == b
            or math.isclose(a, b, rel_tol=4 * sys.float_info.epsilon, abs_tol=0.0))


def test_tail_probabilities_are_scipy_stats():
    xs = [-1.0, 0.0, 1e-12, 0.3, 1.0, 2.5, 7.0, 30.0, 200.0, 2000.0, math.inf, math.nan]
    for dof in (1, 2, 3, 7.5, 40, 300):
        for x in xs:
            assert _same(pvalues.chi2_sf(x, dof), float(stats.chi2.sf(x, dof))), (x, dof)
            logsf = float(stats.chi2.logsf(x, dof))
            if not float(stats.chi2.sf(x, dof)) > 1e-40:  # the far tail, where select.py
                assert _same(pvalues.chi2_logsf(x, dof), logsf), (x, dof)  # uses it
            else:  # near the body scipy uses log1p(-cdf): equal to 1e-9
                assert pvalues.chi2_logsf(x, dof) == pytest.approx(logsf, abs=1e-9), (x, dof)
            for dfd in (1, 5, 250):
                assert _same(pvalues.f_sf(x, dof, dfd), float(stats.f.sf(x, dof, dfd))), \
                    (x, dof, dfd)
    for q in [0.0, 1e-300, 1e-20, 0.005, 0.3, 0.5, 0.97, 1.0, *np.geomspace(1e-15, 0.5, 9)]:
        assert _same(pvalues.norm_isf(q), float(stats.norm.isf(q))), q
        for dof in (1, 4, 30):
            assert _same(pvalues.chi2_isf(q, dof), float(stats.chi2.isf(q, dof))), (q, dof)

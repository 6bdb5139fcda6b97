"""A reduced version of ``benchmarks/recovery.py``: are the honest error bars honest?

Twelve seeds of the 1990 campaign without its thermal effect (the heating shifts some W's the
same way in every seed, a bias no single-campaign error bar can cover: see the benchmark and
docs/results.md). The pulls (fitted - true) / sigma of all ten W's in all twelve seeds are pooled.
"""

from __future__ import annotations

from dataclasses import replace
from multiprocessing import get_context
from pathlib import Path

import numpy as np
import pytest

from antsim.run.outputs import run_fits
from antsim.scenario import load_scenario
from antsim.simulate.runner import simulate

GHIGO = Path(__file__).resolve().parents[2] / "scenarios" / "ghigo1990.toml"
SEEDS = range(1, 13)


def _fit_seed(args):
    scenario, seed = args
    fit = run_fits(simulate(scenario, seed=seed))["A"]
    return fit.values_arcsec, fit.sigma_arcsec, fit.sigma_honest_arcsec


@pytest.fixture(scope="module")
def pulls():
    base = load_scenario(GHIGO)
    scenario = replace(base, effects=tuple(e for e in base.effects if e.name != "thermal"))
    with get_context("spawn").Pool(2) as pool:
        results = pool.map(_fit_seed, [(scenario, s) for s in SEEDS])
    values, tpoint, honest = (np.array(x) for x in zip(*results, strict=True))
    error = values - scenario.truth_model.values_arcsec
    return error / tpoint, error / honest


def test_honest_sigma_matches_the_scatter_over_seeds(pulls):
    """120 pooled pulls (12 seeds x 10 terms; the terms of one seed are correlated, so the
    effective number is nearer 60): a sample spread then has a relative standard error of
    about 1/sqrt(120) = 9%, and 0.75..1.25 is a ~3-sigma band around 1. Measured: 0.79, with
    100% within 3 sigma, since the thermal recalibration of the jitter (0.83 before; 0.87 with
    one block grid instead of four; 0.98 and 97.5% before the jackknife replayed the fit's
    rejection and the azimuth steps followed the sky elevation; the 200-seed benchmark:
    per-term spreads 0.91-1.00, docs/results/recovery.txt)."""
    _, honest = pulls
    spread = float(np.sqrt(np.mean(honest**2)))
    assert 0.75 < spread < 1.25, spread
    assert np.mean(np.abs(honest) <= 3.0) >= 0.95


def test_tpoint_sigma_is_conservative(pulls):
    """TPOINT's sigma (Sky RMS times the unscaled error) overstates the scatter, because the
    Sky RMS is sqrt(2) times the per-axis scatter: its pooled spread stays well below 1
    (measured 0.67 pooled since the thermal recalibration, 0.72 before; the benchmark:
    0.62-0.89 per term). The test would fail if the two sigmas were the same."""
    tpoint, honest = pulls
    assert float(np.sqrt(np.mean(tpoint**2))) < 0.85
    assert float(np.sqrt(np.mean(tpoint**2))) < 0.9 * float(np.sqrt(np.mean(honest**2)))

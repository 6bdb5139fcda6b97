"""The outcome of a fit (controller.pointing.result.FitResult): its JSON document, its table
and summary, and the honest error bars computed once, on first use."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from controller.pointing.jackknife import JackknifeResult
from controller.pointing.model import PointingModel
from controller.pointing.result import FitResult

NAN = float("nan")


def _result(**changes) -> FitResult:
    """A fit of IA, IE, CA in which CA was not constrained (its sigma NaN)."""
    fields = dict(
        model=PointingModel(["IA", "IE", "CA"], [12.5, -3.25, 0.0], name="three"),
        sigma_arcsec=np.array([0.5, 0.25, NAN]), n_input=10, n_used=9, n_rejected=1,
        used=np.array([True] * 9 + [False]), residual_xel_arcsec=np.zeros(10),
        residual_el_arcsec=np.zeros(10), sky_rms_arcsec=1.5, xel_rms_arcsec=1.0,
        el_rms_arcsec=1.1, popn_sd_arcsec=1.6, condition_number=3.0,
        correlation=np.array([[1.0, 0.1, NAN], [0.1, 1.0, NAN], [NAN, NAN, NAN]]),
        unconstrained=("CA",), warnings=("CA is not constrained by the data",))
    fields.update(changes)
    return FitResult(**fields)


def test_the_json_document_has_plain_types_and_null_for_nan():
    doc = _result().to_json()
    json.dumps(doc, allow_nan=False)  # no NaN reaches the file
    assert doc["terms"]["IA"] == {"value_arcsec": 12.5, "sigma_arcsec": 0.5,
                                  "sigma_honest_arcsec": None}
    assert doc["terms"]["CA"]["sigma_arcsec"] is None
    assert doc["correlations"]["matrix"][0] == [1.0, 0.1, None]
    assert (doc["n_input"], doc["n_used"], doc["n_rejected"]) == (10, 9, 1)
    assert doc["unconstrained"] == ["CA"] and "fixed" not in doc and "notes" not in doc
    assert doc["honest_sigma"]["clusters"] == 0


def test_the_table_says_which_terms_were_not_fitted_or_held_fixed():
    lines = _result().table().splitlines()
    assert lines[1].split() == ["IA", "+12.5000", "0.5000"]
    assert lines[3].split() == ["CA", "+0.0000", "not", "fitted"]
    held = _result(fixed=("CA",)).table().splitlines()
    assert held[3].split() == ["CA", "+0.0000", "fixed"]


def test_the_honest_error_bars_are_computed_once_and_read_only():
    calls = []

    def jackknife():
        calls.append(1)
        return JackknifeResult(sigma=np.array([0.6, 0.3, NAN]), dof=np.array([6.0, 6.0, NAN]),
                               clusters=8, phases=2)

    result = _result(honest_source=jackknife, honest_block_s=600.0)
    assert calls == []  # nothing computed until asked
    honest = result.sigma_honest_arcsec
    assert honest[0] == pytest.approx(0.6 * math.sqrt(6.0 / 4.0))
    assert result.honest_clusters == 8 and result.honest_phases == 2
    with pytest.raises(ValueError):
        honest[0] = 1.0
    summary = result.summary()
    assert calls == [1]
    assert "honest sigma: cluster jackknife (CV3)" in summary
    assert "observations within 600 s time blocks" in summary
    assert "averaged over 2 block grids" in summary
    assert summary.splitlines()[-1] == "warning: CA is not constrained by the data"
    assert result.to_json()["terms"]["IE"]["sigma_honest_arcsec"] == pytest.approx(
        0.3 * math.sqrt(1.5))


def test_without_times_the_jackknife_leaves_out_single_observations():
    result = _result(honest_source=lambda: JackknifeResult(
        sigma=np.array([0.6, 0.3, NAN]), dof=np.array([2.0, 9.0, NAN]), clusters=3))
    assert "single observations (the data have no times)" in result.honest_method()
    # dof 2 leaves sqrt(dof / (dof - 2)) infinite: the summary says the sigma is blank
    assert "honest sigma blank for IA: 3 clusters are too few" in result.summary()

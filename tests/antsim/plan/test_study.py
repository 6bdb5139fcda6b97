"""Running a plan (antsim.plan.study): members in full after a cold start, the same results
on any engine (a pool of 1 or 2 workers, Dask, this process), and a variant that fits thermal
terms from the antenna's sensors."""

from __future__ import annotations

import json

import numpy as np
import pytest

from antsim.plan.planfile import load_plan
from antsim.plan.study import run_plan
from controller.errors import InputError
from tests.antsim.plan.conftest import assert_docs_close


def test_cold_start_runs_members_in_full(write_plan, tmp_path):
    # a model in use 12' wrong in elevation (W1, the elevation encoder offset): every first
    # scan misses, even in the noise-free run, and the controller searches. (With no model
    # at all the 1990 antenna's 12.24' azimuth offset is only W6 cos E on the sky: the
    # noise-free run of these hours finds its sources on the flank of the beam.)
    model = tmp_path / "wrong.json"
    model.write_text('{"model": "wrong", "w_terms": "Ghigo 1990 (NRAO EDIR 288) section II", '
                     '"terms": {"W1": {"value_arcsec": -720.0}}}', encoding="utf-8")
    plan = load_plan(write_plan(members=2, block=2,
                                variant=f'model = "{model.as_posix()}"\nduration_h = 1.5\n'
                                'sources = ["3C84", "Cygnus A", "Cassiopeia A"]'))
    result = run_plan(plan, workers=0, answers=False, progress=False)
    doc = result.to_json()["plans"][0]
    assert doc["n_full_simulation"] == 2 and doc["n_shared_schedule"] == 0
    assert not doc["shared_schedule"] and "searched" in doc["why_not_shared"][0]


def test_same_results_with_1_and_2_workers_and_dask(plan_out):
    """Member i has seed (plan seed, i) and block i // block_members whatever runs it: the
    same JSON from a pool of 1 and of 2 workers, a Dask LocalCluster of 2, and this process."""
    path, out = plan_out
    doc1 = json.loads((out / "plan.json").read_text())
    plan = load_plan(path)
    doc2 = run_plan(plan, workers=2, answers=False, progress=False).to_json()
    doc0 = run_plan(plan, workers=0, answers=False, progress=False).to_json()  # this process
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        doc3 = run_plan(plan, scheduler=cluster.scheduler_address, answers=False,
                        progress=False).to_json()
    assert doc1 == doc2 == doc3  # workers all of one BLAS thread: one code path, same bytes
    # this process's BLAS may split a product over threads (numpy 1.26's OpenBLAS does on
    # two cores), summing in another order: equal to rounding, 1e-12 (measured 2e-15)
    assert_docs_close(doc0, doc1, rtol=1e-12)
    p = doc1["plans"][0]
    assert p["name"] == "as run" and p["n_monte_carlo"] == 6
    for term in ("W1", "W4", "W10"):
        entry = p["terms"][term]
        assert {"sigma_fisher_arcsec", "sigma_mc_arcsec", "bias_arcsec"} <= set(entry)
        assert entry["sigma_fisher_arcsec"] > 0 and entry["sigma_mc_arcsec"] > 0
    assert {"sky_rms_fisher_arcsec", "sky_rms_mc_arcsec", "duration_h", "n_scans"} <= set(p)
    assert (out / "sigma_predicted.png").stat().st_size > 1000


def test_a_plan_with_sensors_fits_thermal_terms(write_plan, repo_root, write_scenario,
                                                 short_ghigo_text):
    """A variant on the antenna with sensors that fits the yoke's bow and the pedestal's
    tilt (3 hours of the 1990 afternoon; the mount's irregularities off and the refraction
    corrected, so that the heating's is the bias): the prediction reads the deterministic
    run's sensors, the members are fitted with them; the heating's bias of W2 (the pedestal
    leaning north, away from the Sun, its pole north of the zenith: +63" without them)
    shrinks with them, as do all of
    W1..W4's (scenarios/plans/ghigo1990_sensors_whatif.toml asks it of 20 days). A
    source-list question cannot be asked of such a variant."""
    from tests.conftest import NOISE_ONLY, SHORT_EDITS, edit_text

    text = (repo_root / "scenarios" / "ghigo1990_sensors.toml").read_text(encoding="utf-8")
    heated = (*SHORT_EDITS, *(e for e in NOISE_ONLY if e[0].startswith(("az_", "el_enc",
                                                                         "track_", "refr"))))
    sensors = write_scenario(edit_text(text, heated), name="sensors.toml")
    thermal = (f'scenario = "{sensors.as_posix()}"\n'
               'fit_model = "W1,W2,W3,W4,W5,W6,W7,W8,W9,W10,TEYFB,TTILT"\n')
    more = f'[[variants]]\nname = "plain"\nscenario = "{sensors.as_posix()}"\n'
    plan = load_plan(write_plan(members=2, block=2, variant=thermal, more=more))
    result = run_plan(plan, workers=0, progress=False)
    with_terms, plain = result.variants
    assert list(with_terms.terms[-2:]) == ["TEYFB", "TTILT"]
    pred = with_terms.prediction
    assert np.all(np.isfinite(pred.sigma_arcsec))
    assert plain.prediction.bias_arcsec[1] > 20.0
    assert abs(pred.bias_arcsec[1]) < 0.5 * abs(plain.prediction.bias_arcsec[1])
    assert np.max(np.abs(pred.bias_arcsec[:4])) < np.max(np.abs(plain.prediction.bias_arcsec[:4]))
    bad = write_plan(members=2, block=2, variant=thermal,
                     more='[[answers.sources]]\nbased_on = "as run"\n', name="bad.toml")
    with pytest.raises(InputError, match="fits thermal terms"):
        load_plan(bad)

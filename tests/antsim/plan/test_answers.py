"""antsim/plan/answers.py: the answers from chains on the members' executor, equal to the
slow way of computing them, and the answering stage's fraction done.

The 1990 scenario cut to 3 hours (tests/conftest.py), its first two hours a variant: a
duration question in hours over its three hours (the long run) and a source-list question.
"""

from __future__ import annotations

import uuid
from dataclasses import replace

import numpy as np
import pytest

from antsim.plan.answers import duration_points, duration_scenario, sources_shortlist
from antsim.plan.fisher import predict, task_noise, truth_vector
from antsim.plan.planfile import load_plan
from antsim.plan.study import run_plan
from antsim.progress import Progress
from antsim.simulate.ensemble import Job, task_record
from antsim.simulate.vectorized import (
    quiet_scenario,
)
from tests.antsim.plan.conftest import assert_docs_close

PLAN = """name = "answers"
scenario = "{scenario}"
seed = 7
members = 2
block_members = 2

[[variants]]
name = "two hours"
duration_h = 2.0
sources = ["3C84", "W31", "Cygnus A", "Cassiopeia A"]

[[answers.duration]]
based_on = "two hours"
terms = ["W1", "W4"]
target_arcsec = 40.0
unit = "hour"
max_days = 0.125

[[answers.sources]]
based_on = "two hours"
min_sources = 3
candidates = 2
"""


@pytest.fixture(scope="module")
def plan(tmp_path_factory, short_ghigo_text):
    base = tmp_path_factory.mktemp("answers")
    scenario = base / "short.toml"
    scenario.write_text(short_ghigo_text, encoding="utf-8")
    path = base / "plan.toml"
    path.write_text(PLAN.format(scenario=scenario.as_posix()), encoding="utf-8")
    return load_plan(path)


class _Recorded(Progress):
    """A progress that shows nothing and keeps every stage's (text, total, last count)."""

    def __init__(self):
        super().__init__("plan", False)
        self.stages: list[list] = []

    def stage(self, text, total=None, unit=""):
        super().stage(text, total, unit)
        self.stages.append([text, total, 0])

    def set(self, n):
        super().set(n)
        self.stages[-1][2] = n


@pytest.fixture(scope="module")
def answered(plan):
    progress = _Recorded()
    result = run_plan(plan, workers=0, progress=progress)
    return result, progress


def _deterministic(scenario, seed):
    """The slow way: a deterministic run and its noise model, one after the other."""
    quiet = quiet_scenario(scenario)
    shared = task_record(quiet)
    terms, fit_name = scenario.controller.fit_spec()
    job = Job(f"slow:{uuid.uuid4().hex}", scenario, quiet, shared, tuple(terms), fit_name, seed)
    noise, _ = task_noise(job, 128)
    return shared, noise, tuple(terms)


def test_duration_curve_equals_a_prediction_of_each_prefix_alone(plan, answered):
    """Each point of the curve (the rejections of all prefixes simulated at once, in parts,
    each draw's LAD started from the prefix before) equals :func:`predict` of that prefix
    alone (every LAD an LP of every row): to 1e-9, the LPs' rounding (1e-13) and the sums'
    order far below it; and the sampling errors stated beside each number."""
    result, _ = answered
    (answer,) = result.answers["duration"]
    q = plan.durations[0]
    long = duration_scenario(q, plan)
    shared, noise, terms = _deterministic(long, plan.seed)
    points = duration_points(q, long, shared, noise)
    assert [c["count"] for c in answer["curve"]] == [count for count, _ in points]
    assert len(points) >= 2
    truth = truth_vector(long, terms)
    for point, (_, end) in zip(answer["curve"], points, strict=True):
        pred = predict(shared, terms, noise, n_scans=end, truth=truth)
        for name in q.terms:
            j = list(pred.names).index(name)
            assert point["sigma_arcsec"][name] == pytest.approx(pred.sigma_arcsec[j], rel=1e-9)
            assert point["bias_predicted_arcsec"][name] == pytest.approx(
                pred.bias_arcsec[j], rel=1e-9, abs=1e-9)
            assert point["sigma_error_arcsec"][name] == pytest.approx(
                pred.sigma_error_arcsec[j], rel=1e-9)
            assert 0.0 < point["sigma_error_arcsec"][name] < point["sigma_arcsec"][name]


def test_source_lists_equal_a_prediction_of_each_candidate(plan, answered):
    result, _ = answered
    (answer,) = result.answers["sources"]
    short = sources_shortlist(plan.sources[0], result.variants[0])
    feasible = [c for c in answer["checked"] if c["feasible"]]
    assert feasible and answer["best"] in feasible
    for item, checked in zip(short["candidates"], answer["checked"], strict=True):
        assert list(item["sources"]) == checked["sources"]
        if item["scenario"] is None:
            continue
        shared, noise, terms = _deterministic(item["scenario"], plan.seed)
        pred = predict(shared, terms, noise)
        np.testing.assert_allclose([checked["sigma_arcsec"][n] for n in terms],
                                   pred.sigma_arcsec, rtol=1e-9)


def test_the_answering_stage_counts_its_steps_to_the_end(answered):
    """After the members, a stage "answering 2 questions" whose count reaches its total
    (every task of the answers: the long run's schedule, noise model, thermal draws and 8
    parts of the rejections' draws; per candidate list a schedule, a noise model, its
    thermal draws and its rejections' draws)."""
    result, progress = answered
    (stage,) = [s for s in progress.stages if s[0].startswith("answering")]
    text, total, done = stage
    n_candidates = sum(c["feasible"] for c in result.answers["sources"][0]["checked"])
    assert text == "answering 2 questions"
    assert total == 1 + 2 + 8 + 4 * n_candidates
    assert done == total
    assert any(s[0].startswith("1 variant: ") for s in progress.stages)


@pytest.mark.parametrize("engine", ["pool", "dask"])
def test_answers_are_the_same_on_two_workers_and_on_dask(plan, answered, engine):
    """The answers' tasks run where the members' do, on a pool of 2 or a Dask cluster of 2,
    beside the members; the rejections' draws are cut into the same 8 parts whatever the
    workers: the same answers as in this process (to rounding: this process's BLAS may sum
    in another order, 1e-12)."""
    result, _ = answered
    if engine == "pool":
        other = run_plan(plan, workers=2, progress=False)
    else:
        distributed = pytest.importorskip("distributed")
        with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                      dashboard_address=None) as cluster:
            other = run_plan(plan, scheduler=cluster.scheduler_address, progress=False)
    assert_docs_close(other.to_json()["answers"], result.to_json()["answers"], rtol=1e-12)


def test_questions_of_one_long_run_simulate_it_once(plan, monkeypatch):
    """Two duration questions of the same variant and length (two targets): one schedule
    of three hours answers both."""
    from antsim.plan import answers

    second = replace(plan.durations[0], targets_arcsec=(30.0, 30.0),
                     key="answers.duration[1]")
    both = replace(plan, durations=(plan.durations[0], second), sources=())
    recorded = []
    real = answers.task_record
    monkeypatch.setattr(answers, "task_record", lambda q: recorded.append(q.duration_s)
                        or real(q))
    result = run_plan(both, workers=0, progress=False)
    assert recorded == [0.125 * 86400.0]
    one, two = result.answers["duration"]
    assert one["curve"] == two["curve"] and one["target_arcsec"] != two["target_arcsec"]


def test_answers_duration_sources_and_separation(write_plan):
    more = ('[[answers.duration]]\nbased_on = "as run"\nterms = ["W1"]\n'
            'target_arcsec = 60.0\nunit = "hour"\nmax_days = 0.125\n'
            '[[answers.duration]]\nbased_on = "as run"\nterms = ["W1"]\n'
            'target_arcsec = 0.5\nunit = "hour"\nmax_days = 0.125\n'
            '[[answers.sources]]\nbased_on = "as run"\nmin_sources = 3\ncandidates = 1\n')
    variant = 'duration_h = 2.0\nsources = ["3C84", "W31", "Cygnus A", "Cassiopeia A"]'
    plan = load_plan(write_plan(members=2, block=2, variant=variant, more=more))
    result = run_plan(plan, workers=0, progress=False)
    reached, missed = result.answers["duration"]
    assert reached["reached"] and reached["answer"]["sigma_arcsec"]["W1"] <= 60.0
    # more hours, smaller sigma than the first hour's, though not hour by hour: the
    # afternoon's rising wind makes its gusts, and a later hour's scans, noisier (measured
    # 44.7", 14.4", 15.4" after 1, 2 and 3 hours)
    sig = [c["sigma_arcsec"]["W1"] for c in reached["curve"]]
    assert all(later < 0.5 * sig[0] for later in sig[1:])
    earlier = [c for c in reached["curve"] if c["count"] < reached["answer"]["count"]]
    assert all(c["sigma_arcsec"]["W1"] > 60.0 for c in earlier)
    assert not missed["reached"] and missed["extrapolated"]["count"] > 3
    src = result.answers["sources"][0]
    best = src["best"]
    assert best is not None and len(best["sources"]) >= 3
    assert all(best["score"] >= c["score"] for c in src["checked"] if c["feasible"])
    separation = result.answers["separation"][0]
    v = result.variants[0]
    sd = v.prediction.sigma_arcsec
    corr = v.prediction.covariance / np.outer(sd, sd)
    names = list(v.terms)
    expected = {(names[i], names[j]) for i in range(len(names)) for j in range(i + 1, len(names))
                if abs(corr[i, j]) > 0.95}
    assert {tuple(p["terms"]) for p in separation["pairs"]} == expected
    assert "duration:" in result.text() and "sources:" in result.text()

"""``antsim plan``: plan files, the shared-schedule ensemble, predictions against Monte Carlo,
answers, and the same results on any engine.

Everything runs on the 1990 scenario cut to 3 hours (``SHORT_EDITS``, about 30 scans) so that
the whole module stays well under a minute.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import replace
from html import escape

import numpy as np
import pytest

from antsim.cli import main as cli_main
from antsim.plan.planfile import load_plan
from antsim.plan.study import run_plan
from antsim.scenario import load_scenario
from antsim.simulate.runner import simulate
from antsim.simulate.vectorized import (
    MemberEngine,
    _MemberDraws,
    member_seed,
    quiet_scenario,
    record_schedule,
)
from antsim.world.effects import PointingState
from antsim.world.effects.thermal import OUProcess
from controller.errors import InputError
from tests.antsim.run.test_report_page import (
    _embedded,
    assert_renders_in_a_browser,
    needs_chromium,
    read_page,
)

PLAN = """name = "short"
scenario = "{scenario}"
seed = 7
members = {members}
block_members = {block}
{extra}
[[variants]]
name = "as run"
{variant}
"""


@pytest.fixture
def short_path(write_scenario, short_ghigo_text):
    return write_scenario(short_ghigo_text, name="short.toml")


@pytest.fixture
def write_plan(tmp_path, short_path):
    def write(members: int = 4, block: int = 2, variant: str = "", extra: str = "",
              more: str = "", name: str = "plan.toml"):
        text = PLAN.format(scenario=short_path.as_posix(), members=members, block=block,
                           variant=variant, extra=extra) + more
        path = tmp_path / name
        path.write_text(text, encoding="utf-8")
        return path

    return write


@pytest.fixture(scope="module")
def short_engine(tmp_path_factory, short_ghigo_text):
    """The shared schedule and member engine of the 3-hour scenario."""
    import simpy

    from antsim.world.world import World

    path = tmp_path_factory.mktemp("short") / "short.toml"
    path.write_text(short_ghigo_text, encoding="utf-8")
    scenario = load_scenario(path)
    quiet = quiet_scenario(scenario)
    shared, _ = record_schedule(quiet)
    terms, name = scenario.controller.fit_spec()
    engine = MemberEngine(scenario, shared, World(quiet, simpy.Environment(), 0), terms, name)
    return scenario, engine


# ---------------------------------------------------------------------------------------------
# plan files
# ---------------------------------------------------------------------------------------------
BAD_VARIANTS = [
    ('windw = "night"', "variants[0].windw", "unknown key"),
    ('window = "dusk"', "variants[0].window", "must be one of all, day, night"),
    ('sources = ["3C84", "Sirius"]', "variants[0].sources", "not a source of the scenario"),
    ("step_arcmin = 20.0", "variants[0].step_arcmin", "outside the main beam"),
    ("duration_h = -3.0", "variants[0].duration_h", "must be > 0"),
    ("elevation_min_deg = 40.0\nelevation_max_deg = 30.0", "variants[0].elevation_max_deg",
     "must exceed elevation_min_deg"),
    ('estimator = "gauss"', "variants[0].estimator", "must be one of clark, lsq"),
    ("members = 1", "variants[0].members", "must be >= 2"),
]


@pytest.mark.parametrize(("variant", "key", "problem"), BAD_VARIANTS)
def test_bad_plan_values_are_one_line_errors(write_plan, variant, key, problem):
    path = write_plan(variant=variant)
    with pytest.raises(InputError) as info:
        load_plan(path)
    line = str(info.value)
    assert "\n" not in line
    assert line.startswith(f"{path}: {key} = ")
    assert problem in line


def test_bad_questions_and_scenario_reference(write_plan, tmp_path):
    path = write_plan(more='[[answers.duration]]\nbased_on = "as run"\nterms = ["IA"]\n'
                           'target_arcsec = 5.0\n')
    with pytest.raises(InputError, match=r"answers\.duration\[0\]\.terms = 'IA': is not fitted"):
        load_plan(path)
    path = write_plan(more='[[answers.sources]]\nbased_on = "by night"\n')
    with pytest.raises(InputError, match=r"answers\.sources\[0\]\.based_on = 'by night': not "
                                         "a variant"):
        load_plan(path)
    path = tmp_path / "lost.toml"
    path.write_text('name = "x"\nscenario = "nowhere.toml"\n[[variants]]\nname = "a"\n',
                    encoding="utf-8")
    with pytest.raises(InputError, match=r"scenario = 'nowhere.toml': no such scenario file"):
        load_plan(path)


def test_cli_bad_input_exits_2_with_one_line(write_plan, capsys):
    path = write_plan(variant='window = "dusk"')
    assert cli_main(["plan", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "variants[0].window = 'dusk'" in err
    assert cli_main(["plan", str(write_plan()), "--members", "1"]) == 2
    assert "--members = 1" in capsys.readouterr().err


def test_variants_change_what_they_say(write_plan):
    path = write_plan(variant='window = "day"\nduration_h = 3.0\nstep_arcmin = 6.0\n'
                              'integration_s = 10.0\nestimator = "lsq"\nmodel = "truth"\n'
                              'elevation_min_deg = 10.5\nfit_model = "tpoint6"')
    plan = load_plan(path)
    s = plan.scenarios[0]
    c = s.controller
    assert (c.scheduler.window, s.duration_s, c.duration_s) == ("day", 10800.0, 10800.0)
    assert (c.scan.step_arcmin, c.scan.integration_s, c.scan.estimator) == (6.0, 10.0, "lsq")
    assert c.scheduler.elevation_min_deg == 10.5
    assert c.model.as_dict() == s.truth_model.as_dict()
    assert c.fit_spec() == (("IA", "IE", "NPAE", "CA", "AN", "AW"), "tpoint6")
    # a source that never enters the window is refused, naming the variant's key
    path = write_plan(variant="duration_h = 2.0\nelevation_min_deg = 15.0", name="p2.toml")
    with pytest.raises(InputError, match=r"variants\[0\]\.sources = 'Taurus A': never between"):
        load_plan(path)


# ---------------------------------------------------------------------------------------------
# the shared schedule
# ---------------------------------------------------------------------------------------------
def test_member_seeds_are_fixed_and_distinct():
    seeds = [member_seed(7, i) for i in range(1000)]
    assert len(set(seeds)) == 1000
    assert seeds[:3] == [member_seed(7, 0), member_seed(7, 1), member_seed(7, 2)]
    assert member_seed(8, 0) != seeds[0]


def assert_docs_close(a, b, rtol: float, path: str = "") -> None:
    """Two JSON documents alike: the same keys, strings and integers; floats within rtol."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys(), path
        for key in a:
            assert_docs_close(a[key], b[key], rtol, f"{path}.{key}")
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            assert_docs_close(x, y, rtol, f"{path}[{i}]")
    elif isinstance(a, float) and isinstance(b, float):
        assert a == b or (math.isnan(a) and math.isnan(b)) or math.isclose(
            a, b, rel_tol=rtol, abs_tol=0.0), f"{path}: {a} != {b}"
    else:
        assert a == b, f"{path}: {a!r} != {b!r}"


def test_ou_process_with_a_member_axis_is_each_members_process():
    """OUProcess(rms of shape (members, k)) drawing from each member's own generator equals
    the members' own processes (the edit of antsim.world.effects.thermal that the ensembles rely
    on), however the draws are cut into integrations and buffered ahead."""
    rms = np.array([3e-4, 2e-3])
    times = [np.arange(15) + 0.5 + 21.0 * i for i in range(6)] + [np.arange(80) + 200.5]
    seeds = [11, 12, 13]
    own = []
    for s in seeds:
        p = OUProcess(np.random.default_rng(s), rms, 60.0)
        own.append(np.concatenate([p.sample(t) for t in times]))
    draws = _MemberDraws([np.random.default_rng(s) for s in seeds])
    draws.CHUNK = 50  # refills inside an integration too
    batched = OUProcess(draws, np.tile(rms, (3, 1)), 60.0)
    out = np.concatenate([batched.sample(t) for t in times])
    # one member's kernel product and three members' are matrix products of other shapes,
    # which BLAS may sum in another order (OpenBLAS's Haswell kernels do: 4e-19 on values of
    # 1e-3, 2.6e-14 relative): equal to a few hundred ulps, 1e-12 relative, and 1e-15 (1e-12
    # of the smaller rms) where the process passes near zero
    np.testing.assert_allclose(out, np.stack(own, axis=1), rtol=1e-12, atol=1e-15)
    # K integrations at once (the member blocks): draws (K, n, members, k), each member's
    # own in its own order
    blocks = OUProcess(_MemberDraws([np.random.default_rng(s) for s in seeds]),
                       np.tile(rms, (3, 1)), 60.0)
    out = np.concatenate([*blocks.sample(np.stack(times[:6])), blocks.sample(times[6])])
    # the blocks' batched matrix product sums in another order: equal to a few ulps
    np.testing.assert_allclose(out, np.stack(own, axis=1), rtol=1e-12, atol=0.0)
    with pytest.raises(RuntimeError, match="for 2 members asked of 3"):
        draws.standard_normal((4, 2, 2))


def test_member_blocks_equal_members_one_integration_at_a_time(short_engine, monkeypatch):
    """Members compute their integrations in blocks (World.sample_blocks with a member
    axis): the jitter, gain and radiometer draws of each member come in the order one
    integration at a time would draw them, and the OU processes and the dish gradients
    carry across block boundaries. Blocks of one integration each give the same powers.
    Tolerance: only the fixed point's start differs (it converges to 5e-11 rad from either),
    which moves a power by < 1e-7 K; a draw out of order would move it by ~0.01-1 K."""
    from antsim.simulate import vectorized

    _, engine = short_engine
    seeds = [member_seed(7, m) for m in range(3)]
    power, std = engine.simulate(seeds)
    assert power.shape == (engine.shared.n_integrations, 3, 2)
    monkeypatch.setattr(vectorized._MemberRun, "MAX_BLOCK", 1)
    one_power, one_std = engine.simulate(seeds)
    np.testing.assert_allclose(power, one_power, rtol=0.0, atol=1e-7)
    np.testing.assert_allclose(std, one_std, rtol=0.0, atol=1e-7)
    assert not np.allclose(power[:, 0], power[:, 1], atol=1e-3)  # members differ


def test_thermal_block_errors_with_a_member_axis_are_each_members(short_engine):
    """The stacked thermal effect of three members (cloud modulation and lateral forcing
    drawn per member, sunlit dish and pedestal on), asked for K integrations at once with
    a direction per member, answers each member's own block errors; asked again with new
    directions (the fixed point's next step) its dish restarts from before the block, and
    the next block continues from the last."""
    _, engine = short_engine
    seeds = [member_seed(7, m) for m in range(3)]
    stacked = engine._effects(seeds, quiet=False, slow_only=True)[0][1]
    own = [engine._effects([s], quiet=False, slow_only=True)[0][1] for s in seeds]
    assert stacked.name == "thermal" and np.ndim(stacked.el_arcsec) == 2
    assert stacked.p["dish_gradient_k"] > 0 and stacked.p["pedestal_gradient_k"] > 0
    rng = np.random.default_rng(3)
    for start_s in (5000.0, 5300.0):  # two blocks in sunlight, in order
        assert np.interp(start_s, stacked.t_grid, stacked._insolation[0]) > 0.1
        t = start_s + 21.0 * np.arange(6)[:, None]  # (K, 1)
        asked = []
        for _ in range(2):  # the fixed point asks twice with the same times
            az = rng.uniform(0.5, 4.0, (6, 3))
            el = rng.uniform(0.3, 1.2, (6, 3))
            got = stacked.block_error(PointingState(t_s=t, az_rad=az, el_rad=el))
            asked.append((az, el, got))
            for m, effect in enumerate(own):
                want = effect.block_error(PointingState(t_s=t[:, 0], az_rad=az[:, m],
                                                        el_rad=el[:, m]))
                for g, w in zip(got, want, strict=True):
                    np.testing.assert_allclose(g[:, m], w, rtol=1e-12, atol=1e-18)
        # asked once more with the first directions: the first answer again
        az, el, first = asked[0]
        again = stacked.block_error(PointingState(t_s=t, az_rad=az, el_rad=el))
        np.testing.assert_array_equal(again[1], first[1])
        for m, effect in enumerate(own):  # every member's own state alike
            effect.block_error(PointingState(t_s=t[:, 0], az_rad=az[:, m], el_rad=el[:, m]))


def test_effects_without_a_member_axis_make_the_schedule_unshareable(short_engine, monkeypatch):
    """An effect that answers one member but not a block of members (its block errors do
    not broadcast to (integrations, members)) is named as the reason the schedule cannot
    be shared (the members are then simulated in full, as for a cold start below)."""
    from antsim.scenario import EffectSpec
    from antsim.world.effects import EFFECTS, Effect

    class OneMemberOnly(Effect):
        name = "one_member_only"

        def pointing_error(self, state):
            return 0.0, 1e-6 * np.asarray(state.el_rad)

        def block_error(self, state):  # loses the member axis
            return 0.0, 1e-6 * np.asarray(state.el_rad)[:, 0]

    monkeypatch.setitem(EFFECTS, "one_member_only", OneMemberOnly)
    scenario, engine = short_engine
    odd = replace(scenario, effects=(*scenario.effects, EffectSpec("one_member_only", {})))
    eng = MemberEngine(odd, engine.shared, engine.reference, engine.terms, engine.fit_name)
    assert any("one_member_only does not accept a member axis (ValueError)" in why
               for why in eng.unshareable), eng.unshareable
    fine = MemberEngine(scenario, engine.shared, engine.reference, engine.terms,
                        engine.fit_name)
    assert fine.unshareable == []


def test_streamed_members_equal_the_members_on_the_finished_schedule(short_engine):
    """The quiet run in a second process, the members integrated here as its integrations
    arrive: the same schedule as the quiet run in this process, and the powers of
    MemberEngine.simulate on it, bit for bit."""
    from antsim.simulate.streaming import ScheduleStream, stream_members

    scenario, engine = short_engine
    seeds = [member_seed(7, m) for m in range(3)]
    with ScheduleStream(quiet_scenario(scenario), 0) as stream:
        shared, (power, std) = stream_members(stream, scenario, seeds)
    ref = engine.shared
    assert shared.n_integrations == ref.n_integrations > 100
    for k in (0, ref.n_integrations // 2, ref.n_integrations - 1):
        np.testing.assert_array_equal(shared.t[k], ref.t[k])
        np.testing.assert_array_equal(shared.enc_el[k], ref.enc_el[k])
        assert shared.state[k] == ref.state[k]
    np.testing.assert_array_equal(shared.scan_int, ref.scan_int)
    for name, values in ref.columns.items():
        np.testing.assert_array_equal(shared.columns[name], values, err_msg=name)
    ref_power, ref_std = engine.simulate(seeds)
    np.testing.assert_array_equal(power, ref_power)
    np.testing.assert_array_equal(std, ref_std)


def test_a_failing_quiet_run_process_is_an_error_not_a_hang(short_engine):
    """A quiet run that fails reports its failure, and a killed process sends nothing:
    either way the parent raises instead of waiting forever."""
    from antsim.simulate.streaming import ScheduleStream

    scenario, _ = short_engine
    with ScheduleStream(None, 0) as stream, \
            pytest.raises(RuntimeError, match="quiet run's process failed: AttributeError"):
        stream.schedule()
    with ScheduleStream(quiet_scenario(scenario), 0) as stream:
        stream._process.terminate()  # killed: no schedule will ever come
        stream._process.join()
        with pytest.raises(RuntimeError, match="ended without its schedule"):
            list(stream.items())


def test_members_that_cannot_follow_the_quiet_run_are_an_error(short_engine, monkeypatch):
    """Whatever stops the members mid-stream becomes the RuntimeError on which the baseline
    falls back to running both in this process (tests/antsim/diagnose/test_diagnose.py)."""
    from antsim.simulate import vectorized
    from antsim.simulate.streaming import ScheduleStream, stream_members

    def broken(self, *args):
        raise ValueError("test")

    monkeypatch.setattr(vectorized._MemberRun, "integrate", broken)
    scenario, _ = short_engine
    with ScheduleStream(quiet_scenario(scenario), 0) as stream, \
            pytest.raises(RuntimeError, match=r"could not follow the quiet run \(ValueError"):
        stream_members(stream, scenario, [1])


def test_vectorized_members_reproduce_their_full_simulation(short_engine):
    """A member on the shared schedule measures what its full simulation measures; the
    only difference is the weather's wander, which moves the refraction correction and the
    true refraction together (arcseconds) and the timing (milliseconds)."""
    scenario, engine = short_engine
    seeds = [member_seed(7, m) for m in range(3)]
    power, std = engine.simulate(seeds)
    reduced = engine.reduce(power, std)
    for m, seed in enumerate(seeds):
        run = simulate(scenario, seed=seed)
        assert run.program.searches == 0
        avg = [r for r in run.rows if r["polarization"] == "AVG"]
        off = np.asarray(reduced.offset_arcmin)[m, :, :, -1] * 60.0
        full = np.array([[r["xel_arcmin"], r["el_arcmin"]] for r in avg]) * 60.0
        assert off.shape == full.shape
        assert np.max(np.abs(off - full)) < 0.5  # arcsec, against ~30" of noise per scan
        xr = [r for r in run.rows if r["polarization"] == "XR"]
        p = engine.scan_powers(power, std)[0][m, :, 0, 0]  # XR azimuth scan powers
        p_full = np.array([[r[f"p_az_{k}"] for k in ("m4", "m1", "0", "p1", "p4")]
                           for r in xr])
        # the recordings keep the raw powers; the reduction sees them less the sky emission
        # the controller predicts from its a-priori atmosphere (ghigo1990's controller.sky)
        sky = engine.shared.scan_sky_k[:, 0, 0]
        assert sky.min() > 2.5 and sky.max() < 15.0  # K: 260 K x tau 0.010 x airmass 1-5.8
        assert np.max(np.abs(p + sky - p_full)) < 0.01  # K, against ~10 K of source


def test_members_that_would_search_are_simulated_in_full(write_plan, short_engine):
    """snr_min = 1000: the quiet run detects every scan (its noise is ~1e-9 K), every noisy
    member misses its first scan and searches, so none can share the schedule."""
    scenario, engine = short_engine
    strict = replace(scenario, controller=replace(
        scenario.controller, scan=replace(scenario.controller.scan, snr_min=1000.0)))
    eng = MemberEngine(strict, engine.shared, engine.reference, engine.terms, engine.fit_name)
    results, diverged = eng.run_block([0, 1], [member_seed(7, 0), member_seed(7, 1)])
    assert diverged == [0, 1] and results.members.size == 0
    cold = replace(scenario, controller=replace(
        scenario.controller, search=replace(scenario.controller.search, update_gain=0.5)))
    eng = MemberEngine(cold, engine.shared, engine.reference, engine.terms, engine.fit_name)
    assert any("update_gain" in why for why in eng.unshareable)


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


# ---------------------------------------------------------------------------------------------
# prediction against Monte Carlo
# ---------------------------------------------------------------------------------------------
def test_predicted_sigma_agrees_with_monte_carlo(short_engine):
    """The reduced version of benchmarks/plan_accuracy.py: 96 members of the 3-hour run.
    Tolerance from the sampling error of a standard deviation, 1/sqrt(2(N-1)) = 7.3%: three
    of it per term plus 5% for the prediction's own approximations (linear response, Gaussian
    gusts, the rejections simulated on 64 draws of Gaussian noise); the mean ratio over the
    terms within 5% + 2 of it. This is a daytime run of 33 observations for ten terms: the
    robust fit rejects about one of them (0.90 per member over 192 members), among the
    heating's large deterministic residuals, and that is half of W5's variance; the
    truncated-normal model of the rejections that the simulation replaced predicted 0.30
    and W5's sigma 1.41 times too small."""
    from antsim.plan.fisher import noise_model, predict
    from antsim.simulate.vectorized import MemberResults

    scenario, engine = short_engine
    n = 96
    noise = noise_model(engine, 7, n_thermal=128)
    truth = np.array([scenario.truth_model.as_dict().get(t, 0.0) for t in engine.terms])
    pred = predict(engine.shared, engine.terms, noise, truth=truth)
    parts = []
    for start in range(0, n, 48):
        members = list(range(start, start + 48))
        res, _ = engine.run_block(members, [member_seed(7, m) for m in members])
        parts.append(res)
    res = MemberResults.concat(parts)
    values = res.values[~res.failed]
    assert len(values) >= n - 3
    ratio = values.std(axis=0, ddof=1) / pred.sigma_arcsec
    err = 1.0 / math.sqrt(2 * (len(values) - 1))
    assert np.all(np.abs(ratio - 1.0) <= 0.05 + 3 * err), ratio
    assert abs(np.exp(np.mean(np.log(ratio))) - 1.0) <= 0.05 + 2 * err
    # the Sky RMS of the used observations, predicted and simulated, within 10%
    assert abs(np.mean(res.sky_rms) / pred.sky_rms_arcsec - 1.0) < 0.10
    # observations rejected per member, predicted and simulated: ~0.9 +- 0.9 per member, so
    # the mean of 96 is good to 0.1 and the prediction's 64 draws to 0.12; 0.5 is 3 of both
    rejected = pred.n_scans - res.n_used[~res.failed]
    assert abs(np.mean(rejected) - pred.n_rejected) <= 0.5, (np.mean(rejected), pred.n_rejected)


# ---------------------------------------------------------------------------------------------
# engines, command line, answers
# ---------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def plan_out(tmp_path_factory, short_ghigo_text):
    """``antsim plan PLAN --workers 1 --no-answers --out DIR`` of 6 members in blocks of 2:
    (plan file, DIR)."""
    base = tmp_path_factory.mktemp("plan_out")
    scenario = base / "short.toml"
    scenario.write_text(short_ghigo_text, encoding="utf-8")
    path = base / "plan.toml"
    path.write_text(PLAN.format(scenario=scenario.as_posix(), members=6, block=2, variant="",
                                extra=""), encoding="utf-8")
    out = base / "out"
    assert cli_main(["plan", str(path), "--workers", "1", "--no-answers", "--no-progress",
                     "--out", str(out)]) == 0
    return path, out


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


def test_plan_page_numbers_are_the_json_numbers(plan_out):
    """report.html: the variants' and terms' numbers are plan.json's at plan.txt's precision
    (one source), plan.txt is on the page whole, every figure embedded byte for byte."""
    from antsim.figures.html import format_number
    from antsim.plan.report import TERMS_HEADER, VARIANTS_HEADER

    _, out = plan_out
    doc = json.loads((out / "plan.json").read_text())
    page = read_page(out / "report.html")

    def f(x, spec):
        return "\N{EN DASH}" if x is None else format_number(x, spec)

    assert page.tables["The plan's variants"] == [list(VARIANTS_HEADER)] + [
        [p["name"], f(p["duration_h"], ".1f"), str(p["n_scans"]), str(p["n_monte_carlo"]),
         f(p["sky_rms_fisher_arcsec"], ".1f"), f(p["sky_rms_mc_arcsec"], ".1f")]
        for p in doc["plans"]]
    text = (out / "plan.txt").read_text()
    for p in doc["plans"]:
        rows = page.tables[f"{p['name']}: the fitted terms (arcsec)"]
        assert rows == [list(TERMS_HEADER)] + [
            [n, f(t["truth_arcsec"], "+.1f"), f(t["sigma_fisher_arcsec"], ".2f"),
             f(t["sigma_mc_arcsec"], ".2f"), f(t["bias_arcsec"], "+.1f"),
             f(t["bias_predicted_arcsec"], "+.1f")] for n, t in p["terms"].items()]
        for n, t in p["terms"].items():  # the same figures as plan.txt's table
            assert re.search(rf"^  {n} .*{f(t['sigma_fisher_arcsec'], '.2f')}", text, re.M)
        assert f"predicted {f(p['sky_rms_fisher_arcsec'], '.1f')}\"" in text
    html = (out / "report.html").read_text()
    assert escape(text.rstrip("\n")) in html
    embedded = _embedded(html)
    pngs = sorted(x.name for x in out.glob("*.png"))
    assert sorted(embedded) == pngs and len(pngs) >= 4
    assert all(embedded[n] == (out / n).read_bytes() for n in pngs)


@needs_chromium
def test_plan_page_in_a_headless_browser(plan_out, tmp_path):
    _, out = plan_out
    assert_renders_in_a_browser(out / "report.html", tmp_path, len(list(out.glob("*.png"))))


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
    sig = [c["sigma_arcsec"]["W1"] for c in reached["curve"]]
    assert sig == sorted(sig, reverse=True)  # more hours, smaller sigma
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


def test_a_plan_with_sensors_fits_thermal_terms(write_plan, repo_root, write_scenario,
                                                 short_ghigo_text):
    """A variant on the antenna with sensors that fits the dish's thermal terms (3 hours of
    the 1990 afternoon): the prediction reads the deterministic run's sensors, the members
    are fitted with them; the heating's bias of W1, large without them (the sunny
    afternoon's +50" and more), shrinks with them (scenarios/plans/ghigo1990_sensors_whatif
    .toml asks it of 20 days). A source-list question cannot be asked of such a variant."""
    from tests.conftest import SHORT_EDITS, edit_text

    text = (repo_root / "scenarios" / "ghigo1990_sensors.toml").read_text(encoding="utf-8")
    sensors = write_scenario(edit_text(text, SHORT_EDITS), name="sensors.toml")
    thermal = (f'scenario = "{sensors.as_posix()}"\n'
               'fit_model = "W1,W2,W3,W4,W5,W6,W7,W8,W9,W10,TEDFB,TSDRL"\n')
    more = f'[[variants]]\nname = "plain"\nscenario = "{sensors.as_posix()}"\n'
    plan = load_plan(write_plan(members=2, block=2, variant=thermal, more=more))
    result = run_plan(plan, workers=0, progress=False)
    with_terms, plain = result.variants
    assert list(with_terms.terms[-2:]) == ["TEDFB", "TSDRL"]
    pred = with_terms.prediction
    assert np.all(np.isfinite(pred.sigma_arcsec))
    assert abs(plain.prediction.bias_arcsec[0]) > 50.0
    assert abs(pred.bias_arcsec[0]) < 0.5 * abs(plain.prediction.bias_arcsec[0])
    bad = write_plan(members=2, block=2, variant=thermal,
                     more='[[answers.sources]]\nbased_on = "as run"\n', name="bad.toml")
    with pytest.raises(InputError, match="fits thermal terms"):
        load_plan(bad)

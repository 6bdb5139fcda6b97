"""Monte Carlo members on a shared schedule, vectorized across members
(antsim.simulate.vectorized): fixed seeds, each member's own draws in blocks, effects with a
member axis, and members that reproduce their full simulation or cannot share the schedule."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from antsim.simulate.runner import simulate
from antsim.simulate.vectorized import (
    MemberEngine,
    _MemberDraws,
    member_seed,
)
from antsim.world.effects import PointingState
from antsim.world.effects.thermal import OUProcess


def test_member_seeds_are_fixed_and_distinct():
    seeds = [member_seed(7, i) for i in range(1000)]
    assert len(set(seeds)) == 1000
    assert seeds[:3] == [member_seed(7, 0), member_seed(7, 1), member_seed(7, 2)]
    assert member_seed(8, 0) != seeds[0]


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
    """The stacked thermal effect of three members (the thin cloud on the Sun drawn per
    member; sunlit legs, yoke and pedestal), asked for K integrations at once with a
    direction per member, answers each member's own block errors; asked again with new
    directions (the fixed point's next step) its members' differences restart from before
    the block, and the next block continues from the last."""
    _, engine = short_engine
    seeds = [member_seed(7, m) for m in range(3)]
    stacked = engine._effects(seeds, quiet=False, slow_only=True)[0][1]
    own = [engine._effects([s], quiet=False, slow_only=True)[0][1] for s in seeds]
    assert stacked.name == "thermal" and np.ndim(stacked._absorbed) == 2
    assert stacked.p["absorptivity"] > 0 and stacked.p["cloud_modulation"] > 0
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

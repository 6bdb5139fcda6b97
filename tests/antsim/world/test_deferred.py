"""The antenna's deferred integrations: computed in blocks when first read, with the values
of integrations computed one by one.

The simulated antenna computes an integration's samples when its powers are first read, all
not-yet-read integrations of one track together (:meth:`antsim.world.world.World.sample_blocks`).
These tests hold the pieces to "the same values as one at a time": the Ornstein-Uhlenbeck
processes, the receiver and the tracking jitter in blocks against sequential calls, the
block fixed point against the exact fixed point, and whole integrations read at once
against the same integrations read one by one.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import pickle

import numpy as np
import pytest
import simpy

import antsim.world.world as world_module
from antsim.scenario import load_scenario
from antsim.world.effects import PointingState
from antsim.world.effects.base import BLOCK_FIELDS
from antsim.world.effects.thermal import OUProcess
from antsim.world.receiver import Receiver, ReceiverConfig
from antsim.world.world import World
from tests.conftest import source_trajectory

#: the block computations reorder floating-point sums (a batched matrix product), nothing
#: else: agreement to a few ulps of the values (~1e-13 relative) is the claim
ROUNDING = 1e-12


def _block_times(rng, blocks: int, n: int, dt: float) -> np.ndarray:
    """Block start times with random gaps (slews, moves) between equally long blocks."""
    starts = np.cumsum(rng.uniform(n * dt + 1.0, n * dt + 60.0, blocks))
    return starts[:, None] + (np.arange(n) + 0.5) * dt


@pytest.mark.parametrize("n", [1, 15, 80])
def test_ou_blocks_equal_one_call_per_block(n):
    t = _block_times(np.random.default_rng(1), 6, n, 1.0)
    one = OUProcess(np.random.default_rng(7), np.array([2.0, 0.5]), 60.0)
    blocks = copy.deepcopy(one)
    sequential = np.stack([one.sample(row) for row in t])
    together = blocks.sample(t)
    np.testing.assert_allclose(together, sequential, rtol=ROUNDING, atol=ROUNDING)
    np.testing.assert_allclose(blocks.state, one.state, rtol=ROUNDING)
    assert blocks.t_last == one.t_last
    # and both continue alike
    later = t[-1, -1] + 30.0 + np.arange(n)
    np.testing.assert_allclose(blocks.sample(later), one.sample(later), rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("n", [15, 80])
def test_ou_starts_stationary(n):
    """The first value of a process is a draw of its stationary distribution (rms), not 0.

    20,000 independent processes: the sample rms of their first values has a relative
    standard error of 1/sqrt(2 x 20000) = 0.5%; 3% is six of those."""
    rms = np.full(20000, 3.0)
    first = OUProcess(np.random.default_rng(3), rms, 60.0).sample(np.arange(n) + 0.5)[0]
    assert np.sqrt(np.mean(first ** 2)) == pytest.approx(3.0, rel=0.03)


def test_receiver_blocks_equal_one_call_per_block():
    cfg = ReceiverConfig(gain_fluctuation=1e-3)
    t = _block_times(np.random.default_rng(2), 5, 15, 1.0)
    t_in = np.random.default_rng(4).uniform(0.0, 3.0, (*t.shape, 2))
    one = Receiver(cfg, np.random.default_rng(11))
    blocks = Receiver(cfg, np.random.default_rng(11))
    sequential = np.stack([one.sample(t[k], t_in[k]) for k in range(t.shape[0])])
    np.testing.assert_allclose(blocks.sample(t, t_in), sequential, rtol=ROUNDING)


@pytest.fixture(scope="module")
def ghigo(ghigo_path):
    return load_scenario(ghigo_path)


def _gusty(scenario):
    """The 1990 scenario with a gust in every few minutes (the jitter's per-sample part)."""
    effects = tuple(dataclasses.replace(e, params={**e.params, "gust_rate_per_h": 30.0})
                    if e.name == "tracking_jitter" else e for e in scenario.effects)
    return dataclasses.replace(scenario, effects=effects)


def test_jitter_blocks_equal_one_call_per_block(ghigo):
    scenario = _gusty(ghigo)
    one = World(scenario, simpy.Environment(), seed=5)
    blocks = World(scenario, simpy.Environment(), seed=5)
    (jitter_one,), (jitter_blocks,) = one.fast_effects, blocks.fast_effects
    assert jitter_one.gust_start_s.size > 10
    t = 3600.0 + _block_times(np.random.default_rng(3), 8, 15, 1.0)
    el = np.radians(np.linspace(20.0, 80.0, t.shape[0]))
    sequential = np.stack([np.stack(jitter_one.sample_error(t[k], el[k]))
                           for k in range(t.shape[0])], axis=1)
    together = np.stack(jitter_blocks.sample_error(t, el[:, None]))
    np.testing.assert_allclose(together, sequential, rtol=ROUNDING, atol=1e-18)


def test_block_fixed_point_is_the_exact_one(ghigo):
    """The block's errors solve B + d(B) = encoder at every instant, the dish gradients
    forced from B itself: the errors of a scalar fixed point iterated to convergence,
    instant after instant, each step from the dish state before that instant. The block
    started from errors of the previous source (1e-3 rad away), near the zenith (the
    steepest errors) in the afternoon (a sunlit dish)."""
    world = World(ghigo, simpy.Environment(), seed=2)
    k = 6
    t = 3600.0 + 20.0 * np.arange(k)
    enc_az = np.radians(150.0 + 0.1 * np.arange(k))
    enc_el = np.radians(np.linspace(84.0, 83.7, k))
    start = (1e-3, -1e-3)
    thermal = next(e for e in world.slow_effects if e.name == "thermal")
    thermal.pointing_error(PointingState(t_s=3000.0, az_rad=2.0, el_rad=1.0))  # a past
    before = (thermal._dish_k, thermal._dish_t)

    expected, dish = [], before
    for i in range(k):
        d = start
        for _ in range(30):
            thermal._dish_k, thermal._dish_t = dish
            d = world.pointing_error_rad(PointingState(t_s=float(t[i]), az_rad=enc_az[i] - d[0],
                                                       el_rad=enc_el[i] - d[1]))
        dish = (thermal._dish_k, thermal._dish_t)
        expected.append(d)
    expected = np.array(expected)

    thermal._dish_k, thermal._dish_t = before
    state = PointingState(**{f: np.zeros(k) for f in BLOCK_FIELDS})
    state.t_s = t
    d_az, d_el = world.solve_pointing_block(enc_az, enc_el, state, start)
    tolerance = 2 * world_module.SOLVE_TOL_RAD
    np.testing.assert_allclose(d_az, expected[:, 0], rtol=0, atol=tolerance)
    np.testing.assert_allclose(d_el, expected[:, 1], rtol=0, atol=tolerance)
    np.testing.assert_allclose(state.el_rad, enc_el - d_el)
    assert thermal._dish_t == t[-1] and thermal._dish_k == pytest.approx(dish[0])
    assert min(np.abs(thermal._dish_k)) > 0.1  # sunlit: the dish term is in the test


def _scan_powers(scenario, read_each: bool, seed: int = 4):
    """Ten 15-s integrations on 3C 84's track at five offsets per axis, their powers read
    after each integration (one block each) or all after the tenth (one block)."""
    world = World(scenario, simpy.Environment(), seed=seed)
    env, antenna = world.env, world.antenna
    out: list = []

    def run():
        yield env.timeout(3600.0)  # the Sun is up: the dish gradients act
        yield antenna.track(source_trajectory(world, 0))
        readings = []
        for axis in (0, 1):
            for n in (-4, -1, 0, 1, 4):
                offset = n * 7.0 / 60.0
                yield antenna.set_offset(*((offset, 0.0) if axis == 0 else (0.0, offset)))
                integ = yield antenna.integrate(15.0)
                if read_each:
                    dict(integ.power_k)
                readings.append(integ)
        out.extend((dict(i.power_k), dict(i.std_k)) for i in readings)

    env.run(until=env.process(run()))
    return np.array([[list(p.values()), list(s.values())] for p, s in out])


@pytest.mark.parametrize("span_s", [world_module.TABLE_SPAN_S, 40.0])
def test_integrations_read_together_equal_read_one_by_one(ghigo, monkeypatch, span_s):
    """A block gives the powers of its integrations computed one by one: the gusts, the
    thermal dish, the receiver's gain drift all carry across them. With 40-s path tables
    the block's paths come integration by integration (a table covers none whole).

    Tolerance: both solve the fixed point to SOLVE_TOL_RAD (1e-5"), which moves a power on
    the beam's flank by < 1e-7 K; the rest is rounding."""
    monkeypatch.setattr(world_module, "TABLE_SPAN_S", span_s)
    scenario = _gusty(ghigo)
    each = _scan_powers(scenario, read_each=True)
    together = _scan_powers(scenario, read_each=False)
    assert each.shape == (10, 2, 2)
    np.testing.assert_allclose(together, each, rtol=0, atol=1e-7)
    source_k = each[:, 0, 0] - each[:, 0, 0].min()
    assert source_k.max() > 0.5  # the source is in the scan: the beam's flanks are tested


def _one_integration(scenario):
    """A world of ``scenario`` (seed 1) and one 5-s integration on 3C 84, not yet read."""
    world = World(scenario, simpy.Environment(), seed=1)
    env, antenna = world.env, world.antenna
    got = []

    def run():
        yield antenna.track(source_trajectory(world, 0))
        got.append((yield antenna.integrate(5.0)))

    env.run(until=env.process(run()))
    return world, got[0]


def test_deferred_powers_behave_as_a_dict(ghigo):
    _, integ = _one_integration(ghigo)
    plain = dict(integ.power_k)
    assert set(plain) == {"XR", "XL"} and all(math.isfinite(v) for v in plain.values())
    assert integ.power_k == plain and len(integ.std_k) == 2
    assert pickle.loads(pickle.dumps(integ)).power_k == plain
    assert type(copy.deepcopy(integ).power_k) is dict
    shifted = dataclasses.replace(integ, power_k={c: p - 1.0 for c, p in integ.power_k.items()})
    assert shifted.power_k["XR"] == pytest.approx(plain["XR"] - 1.0)


def test_an_integration_whose_block_failed_says_so(ghigo, monkeypatch):
    world, integ = _one_integration(ghigo)

    def broken(*args, **kwargs):
        raise ValueError("broken physics")

    monkeypatch.setattr(world, "sample_blocks", broken)
    with pytest.raises(ValueError, match="broken physics"):
        dict(integ.power_k)
    with pytest.raises(RuntimeError, match="could not be computed"):
        dict(integ.std_k)


def test_default_block_errors_ask_once_per_instant_with_or_without_members():
    """An effect without a block_error of its own is asked once per instant: plain numbers
    for a World's block (fields (K,)), and with a member axis (fields (K, 1), directions
    (K, members)) one number per integration and the directions per member, its answers
    broadcast to (K, members)."""
    from antsim.world.effects import Effect

    class Tilted(Effect):  # math.sin: a number per instant, as a World gives
        name = "tilted"

        def pointing_error(self, state):
            return (1e-6 * math.sin(state.t_s / 100.0) * np.cos(state.az_rad),
                    2e-6 * math.copysign(1.0, state.approach_el))

    effect = Tilted()
    t = np.array([10.0, 30.0, 50.0])
    az = np.array([[0.1, 0.2], [0.3, 0.4], [0.5, 0.6]])
    fields = {f: np.zeros(3) for f in BLOCK_FIELDS} | {"t_s": t, "approach_el": -np.ones(3)}
    world_block = effect.block_error(PointingState(**fields | {"az_rad": az[:, 0]}))
    members = effect.block_error(PointingState(
        **{f: v[:, None] for f, v in fields.items()} | {"az_rad": az, "el_rad": az}))
    for k in range(3):
        for m in range(2):
            want = effect.pointing_error(PointingState(t_s=float(t[k]), az_rad=az[k, m],
                                                       el_rad=0.0, approach_el=-1.0))
            assert members[0][k, m] == want[0] and members[1][k, m] == want[1] == -2e-6
        assert world_block[0][k] == members[0][k, 0]
    assert members[0].shape == members[1].shape == (3, 2) and world_block[1].shape == (3,)

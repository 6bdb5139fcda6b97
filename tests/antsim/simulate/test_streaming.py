"""The quiet run in a second process, the members integrated as its integrations arrive
(antsim.simulate.streaming): the same schedule and powers, and failures that are errors, not
hangs."""

from __future__ import annotations

import numpy as np
import pytest

from antsim.simulate.vectorized import (
    member_seed,
    quiet_scenario,
)


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

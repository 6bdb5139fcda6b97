"""Shared by the tests of the shared-schedule ensemble: the member engine of the 1990 scenario
cut to 3 hours, and antsim plan's plan files (tests/antsim/plan/conftest.py)."""

from __future__ import annotations

import pytest

from antsim.scenario import load_scenario
from antsim.simulate.vectorized import (
    MemberEngine,
    quiet_scenario,
    record_schedule,
)
from tests.antsim.plan.conftest import short_path, write_plan  # noqa: F401 (the fixtures)


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

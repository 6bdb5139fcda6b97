"""Fixtures of the controller's tests: the 1990 scenario, and antsim serve's virtual-clock
server for the KATCP client's tests (tests/controller/test_wire.py)."""

from pathlib import Path

import pytest

from antsim.scenario import load_scenario
from tests.antsim.serve.conftest import server  # noqa: F401 (the fixture)

ROOT = Path(__file__).resolve().parents[2]
GHIGO = ROOT / "scenarios" / "ghigo1990.toml"


@pytest.fixture(scope="module")
def ghigo():
    return load_scenario(GHIGO)

"""Shared by the tests of the shared-schedule ensemble: the member engine of the 1990 scenario
cut to 3 hours, and antsim plan's plan files (tests/antsim/plan/conftest.py)."""

from __future__ import annotations

import pytest

from tests.antsim.plan.conftest import short_path, write_plan  # noqa: F401 (the fixtures)
from tests.conftest import member_engine


@pytest.fixture(scope="module")
def short_engine(tmp_path_factory, short_ghigo_text):
    """The shared schedule and member engine of the 3-hour scenario."""
    return member_engine(short_ghigo_text, tmp_path_factory.mktemp("short"))

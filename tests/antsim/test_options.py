"""Counts a user gives, checked against their limits (antsim.options)."""

from __future__ import annotations

import os

import pytest

from antsim.options import (
    MAX_SIMULATIONS,
    PROCESSES_PER_CORE,
    check_count,
    check_processes,
)
from controller.errors import InputError


def test_a_count_within_its_limits_is_returned():
    assert check_count(1, "--sims", 1, MAX_SIMULATIONS, "a campaign each") == 1
    assert check_count(MAX_SIMULATIONS, "--sims", 1, MAX_SIMULATIONS, "x") == MAX_SIMULATIONS


def test_a_count_outside_its_limits_is_one_line_naming_the_option():
    with pytest.raises(InputError) as low:
        check_count(0, "--sims", 1, 10, "a campaign each")
    assert str(low.value) == "command line: --sims = 0: must be at least 1"
    with pytest.raises(InputError) as high:
        check_count(11, "--sims", 1, 10, "a campaign each")
    assert str(high.value) == "command line: --sims = 11: must be at most 10 (a campaign each)"


def test_processes_are_limited_per_core_of_this_machine():
    most = PROCESSES_PER_CORE * (os.cpu_count() or 1)
    assert check_processes(most, "--workers") == most
    assert check_processes(0, "--jobs", minimum=0) == 0
    with pytest.raises(InputError, match=rf"--workers = {most + 1}: must be within 1\.\.{most}"):
        check_processes(most + 1, "--workers")
    with pytest.raises(InputError, match="--workers = 0: must be within 1"):
        check_processes(0, "--workers")

"""Why the scheduler's limits let no source be observed at any time of a campaign: each
limit named, and none named where a scan can be made."""

from __future__ import annotations

from dataclasses import replace

import pytest

from antsim.scenario import load_scenario
from controller.program.campaign import plan_targets
from controller.program.observer import why_unschedulable


@pytest.fixture(scope="module")
def config(repo_root):
    """The bad-input base: Green Bank, 1990-02-08 17:00 UTC (local noon), one hour."""
    return load_scenario(repo_root / "tests/data/bad_inputs/scenario/_base.toml").controller


def why(config, **changes):
    config = replace(config, scheduler=replace(config.scheduler, **changes))
    observer, targets = plan_targets(config)
    return why_unschedulable(observer, targets, config.scheduler, config.duration_s)


def test_limits_that_leave_scans_name_nothing(config):
    assert why(config) == ("", "")
    assert why(config, window="day") == ("", "")


def test_each_limit_that_leaves_no_scan_is_named(config):
    key, reason = why(config, window="night")
    assert key == "window" and reason.startswith("the Sun is never below night_sun_max_deg")
    key, reason = why(config, declination_max_deg=-89.0)
    assert key == "declination_max_deg" and "southernmost at +40.7 deg" in reason
    # sources below +42 deg only, and only above 85 deg elevation: none this hour
    key, reason = why(config, declination_max_deg=42.0, elevation_min_deg=84.0,
                      elevation_max_deg=85.0)
    assert key == "elevation_min_deg"
    assert reason == ("no source is between 84 and 85 deg elevation and at or below 42 deg "
                      "of declination at any time of the campaign")

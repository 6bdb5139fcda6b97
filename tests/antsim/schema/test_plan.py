"""The plan schema against the plan's dataclasses: every field a key or said to come from
elsewhere, and a variant's keys the scenario's own (the same ranges)."""

from __future__ import annotations

import pytest

from antsim.plan.planfile import (
    CoverageQuestion,
    DurationQuestion,
    Plan,
    SourcesQuestion,
    VariantSpec,
)
from antsim.schema.plan import PLAN, section
from antsim.schema.scenario import CAMPAIGN, SCAN, SCHEDULER
from tests.antsim.schema.test_scenario import unclaimed_fields


@pytest.mark.parametrize("cls", [Plan, VariantSpec, DurationQuestion, SourcesQuestion,
                                 CoverageQuestion])
def test_every_plan_setting_has_a_key(cls):
    assert unclaimed_fields(cls, PLAN) == []


@pytest.mark.parametrize("name, table", [
    ("window", SCHEDULER), ("duration_h", CAMPAIGN), ("start_utc", CAMPAIGN),
    ("sources", SCHEDULER), ("elevation_min_deg", SCHEDULER),
    ("elevation_max_deg", SCHEDULER), ("step_arcmin", SCAN), ("integration_s", SCAN),
    ("estimator", SCAN)])
def test_a_variant_key_is_the_scenario_key(name, table):
    """Same kind, range and choices as the scenario's key; the base scenario's value as the
    default."""
    ours, theirs = section("variants[]")[name], table[name]
    assert ours.default is None
    for attribute in ("kind", "min", "max", "gt", "lt", "choices", "why", "why_min"):
        assert getattr(ours, attribute) == getattr(theirs, attribute), attribute

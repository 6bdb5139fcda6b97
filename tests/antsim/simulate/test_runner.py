"""A campaign run that makes no scan is refused, and leaves no recordings behind."""

from __future__ import annotations

from pathlib import Path

import pytest

from antsim.scenario import load_scenario
from antsim.simulate.runner import NoScanError, run_campaign

DATA = Path(__file__).resolve().parents[2] / "data" / "bad_inputs"


def test_a_campaign_that_makes_no_scan_is_refused(tmp_path, monkeypatch):
    """The night window in a daytime hour, with the check before the campaign switched off:
    the campaign itself finds no scan made, and refuses rather than leave a header-only
    recordings file and exit 0."""
    import antsim.simulate.runner as runner

    scenario = load_scenario(DATA / "scenario" / "night_window_in_a_daytime_hour.toml")
    with pytest.raises(NoScanError, match="the controller can schedule no scan"):
        run_campaign(scenario, tmp_path / "before", show_progress=False)
    assert not (tmp_path / "before" / "recordings.ecsv").exists()
    monkeypatch.setattr(runner, "why_unschedulable", lambda *args, **kwargs: ("", ""))
    with pytest.raises(NoScanError, match="the controller made no scan in the campaign"):
        run_campaign(scenario, tmp_path / "after", show_progress=False)
    assert not (tmp_path / "after" / "recordings.ecsv").exists()

"""antsim/commands/blindtest.py: a rate over no cases (a draw without a null case has no
false alarms to count) is said in words, never "nan%", and is null in the JSON, which stays
strict JSON."""

from __future__ import annotations

import json

import pytest

from antsim.cli import main
from antsim.commands.blindtest import _no_case_words, _null_for_no_rate


def test_a_rate_of_no_cases_is_said_in_words():
    text = ("correct identification 0/0 = nan% (group-aware nan%)\n"
            "false alarms 0/0 = nan%\namplitude within 3 sigma 2/2 = 100.0%")
    assert _no_case_words(text) == (
        "correct identification 0/0 (no such case was drawn)\n"
        "false alarms 0/0 (no such case was drawn)\namplitude within 3 sigma 2/2 = 100.0%")
    assert _null_for_no_rate({"rates": {"a": float("nan"), "b": 0.5, "c": [float("inf")]}}) \
        == {"rates": {"a": None, "b": 0.5, "c": [None]}}


def _strict(text: str):
    def refuse(constant):
        raise ValueError(f"{constant} is not JSON")
    return json.loads(text, parse_constant=refuse)


@pytest.mark.parametrize("as_json", [False, True])
def test_the_readme_blindtest_without_a_null_case(as_json, diagnose_cache, capsys, tmp_path):
    """The README's blindtest, reduced as tests/end_to_end/test_readme_commands.py runs it (2
    cases, seed 1): both cases hide an effect, so no false alarm can be counted."""
    out = tmp_path / "blind.json"
    assert main(["blindtest", "--n", "2", "--seed", "1", "--cache", str(diagnose_cache),
                 "--no-progress", "--out", str(out), *(["--json"] if as_json else [])]) == 0
    printed = capsys.readouterr().out
    doc = _strict(out.read_text(encoding="utf-8"))
    assert doc["rates"]["null_cases"] == 0 and doc["rates"]["false_alarm_rate"] is None
    if as_json:
        assert _strict(printed) == doc
    else:
        assert "nan" not in printed.lower()
        assert "false alarms 0/0 (no such case was drawn)" in printed

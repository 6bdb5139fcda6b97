"""antsim/diagnose/blind.py: the report's rates, in words and in strict JSON."""

from __future__ import annotations

import json

from antsim.diagnose.blind import NULL, BlindCase, BlindReport


def _case(index: int, hidden: str, named: str) -> BlindCase:
    return BlindCase(index, hidden, {}, 5.0, 1.0, named=named, findings=[named])


def test_a_rate_over_no_cases_is_said_in_words_and_is_null_in_the_json():
    """Two cases with an effect, none without: no false alarm can be counted; and a draw of
    null cases alone has no identification to count."""
    effects = BlindReport([_case(0, "az_track_2a", "az_track_2a"),
                           _case(1, "step[el]", NULL)], {}, {}, 1.0)
    text = effects.text()
    assert "false alarms 0/0 (no such case was drawn)" in text
    assert "correct identification 1/2 = 50.0% (group-aware 50.0%)" in text
    assert "nan" not in text.lower()
    doc = json.loads(json.dumps(effects.to_json(), allow_nan=False))
    assert doc["rates"]["false_alarm_rate"] is None and doc["rates"]["correct_rate"] == 0.5
    # the cases' amplitudes, not measured (NaN), are null too
    assert doc["cases"][0]["fitted_amplitude"] is None
    nulls = BlindReport([_case(0, NULL, NULL)], {}, {}, 1.0)
    text = nulls.text()
    assert "correct identification 0/0 (no such case was drawn)" in text
    assert "false alarms 0/1 = 0.0%" in text and "nan" not in text.lower()
    assert nulls.to_json()["rates"]["correct_rate"] is None

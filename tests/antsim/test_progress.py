"""antsim/progress.py: a campaign's length in the words of a progress line."""

from __future__ import annotations

import pytest

from antsim.progress import span_words


@pytest.mark.parametrize(("seconds", "words"), [
    (3600.0, "1 hour"), (8 * 3600.0, "8 hours"), (86400.0, "24 hours"),
    (20 * 86400.0, "20 days"), (5400.0, "1.5 hours")])
def test_a_campaigns_length_in_words(seconds, words):
    assert span_words(seconds) == words

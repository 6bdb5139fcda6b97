"""``antsim diagnose --help``: what a user reads first."""

from __future__ import annotations

import contextlib
import io
import re

import pytest

from antsim.cli import main


def test_the_help_names_the_inputs_and_cites_nothing_outside():
    out = io.StringIO()
    with contextlib.redirect_stdout(out), pytest.raises(SystemExit) as done:
        main(["diagnose", "--help"])
    assert done.value.code == 0
    text = " ".join(out.getvalue().split())
    recordings = text[text.index("RECORDINGS recordings.ecsv"):text.index("options:")]
    assert "TPOINT" in recordings and "CSV" in recordings, recordings
    assert not re.search(r"\bDESIGN\b|section \d", text), text

"""The README's numbers that come from long commands are checked against the commands' kept
output (``docs/results/``): each number the section quotes must be one the command printed.
The runs that are short enough are checked where they run (``tests/test_pointing_run.py``,
``test_fomalont.py``, ``test_gaincurve.py``, ``test_demo.py``). Regenerate a result file by
running the command named in its section and copying its output there.
"""

from __future__ import annotations

import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
README = (REPO / "README.md").read_text(encoding="utf-8")
RESULTS = REPO / "docs" / "results"


def _section(start: str, end: str) -> str:
    text = README[README.index(start):]
    return text[:text.index(end)]


def _numbers(text: str) -> list[str]:
    """Signed decimal numbers quoted with a unit (") or as counts of scans, nights, hours."""
    return re.findall(r'[-+]?\d+\.\d+(?=")|\d+(?= (?:scans|nights))|\d+\.\d+(?= h)', text)


def test_the_what_if_answer_is_the_plans_output():
    section = _section("**How many nights", "Predicted and Monte Carlo sigmas")
    output = (RESULTS / "ghigo1990_whatif.txt").read_text(encoding="utf-8")
    flat_output = " ".join(output.split())
    answer = " ".join(section[section.index("duration:"):section.index("One night")].split())
    assert answer in flat_output
    numbers = _numbers(section.replace("W4 to 6\"", ""))
    assert len(numbers) >= 12
    for number in numbers:
        assert re.search(rf"(?<![\d.]){re.escape(number.lstrip('+'))}(?![\d])", output), number
    assert "cannot separate W6/W10 (-0.99), W9/W10" in flat_output

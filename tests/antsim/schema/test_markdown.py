"""docs/scenarios.md is what the schema writes now, and says every key."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from antsim.schema.markdown import reference_page, section_markdown
from antsim.schema.plan import PLAN
from antsim.schema.scenario import SCENARIO, section

REPO = Path(__file__).resolve().parents[3]
PAGE = REPO / "docs" / "scenarios.md"


def test_the_page_in_docs_is_what_the_schema_writes():
    """Regenerate with ``python -m antsim.schema --markdown > docs/scenarios.md``."""
    assert PAGE.read_text(encoding="utf-8") == reference_page(), (
        "docs/scenarios.md is out of date: python -m antsim.schema --markdown > "
        "docs/scenarios.md")


def test_the_command_writes_the_page(repo_root):
    proc = subprocess.run([sys.executable, "-m", "antsim.schema", "--markdown"],
                          capture_output=True, text=True, cwd=repo_root, check=True,
                          env={"PYTHONPATH": str(repo_root), "PATH": "/usr/bin:/bin"})
    assert proc.stdout == reference_page()


def test_every_key_is_on_the_page():
    page = reference_page()
    for s in (*SCENARIO, *PLAN):
        text = section_markdown(s)
        assert text in page
        for name in s.keys:
            assert f"| `{name}` |" in text, f"{s.path}.{name}"


def test_a_row_says_type_unit_default_range_meaning_and_source():
    rows = section_markdown(section("controller.scheduler")).splitlines()
    row = next(r for r in rows if r.startswith("| `declination_max_deg` |"))
    assert row == ("| `declination_max_deg` | number | deg | - | -90..90 | the program cannot "
                   "point above this declination (default: no limit) | Crane 1981, section "
                   "II |")
    row = next(r for r in section_markdown(section("mount")).splitlines()
               if r.startswith("| `wrap_margin_s` |"))
    assert "| s | `3600` | 0..3600 |" in row and "bound: the mount plans" in row

"""The project stands alone: nothing in it cites the design notes it was started from, a
folder outside the repository or an issue number (what the code relies on is in docs/), and
every relative link of README.md and docs/*.md leads to a file of the repository."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
#: where the project's own text is
FOLDERS = ("antsim", "controller", "benchmarks", "tests", "docs", "scenarios", "examples")
SUFFIXES = {".py", ".md", ".toml", ".txt", ".mjs", ".cfg", ".ini"}
#: a citation of the design notes, of a folder beside the repository, of an issue (an
#: external project's issue, "astropy issue #10456", is a citation, not one of ours)
OUTSIDE = re.compile(r"\bDESIGN\b|\.\./shared|(?<!astropy )\b[Ii]ssues? [0-9]+[a-z]?\b"
                     r"|\b[Tt]he issue'?s?\b")
#: files still to be swept, each with the reason; drop a file when it is
EXCEPTIONS = {
    # being rewritten by the 1990 scenario's own change
    "scenarios/ghigo1990.toml", "scenarios/ghigo1990_sensors.toml",
    # the simulated world, being changed for the 45-ft's physics at the same time
    "antsim/world/beam.py", "antsim/world/mount.py", "antsim/world/receiver.py",
    "antsim/world/weather.py", "antsim/world/world.py", "antsim/world/effects/drifts.py",
    "antsim/world/effects/steps.py", "antsim/world/effects/thermal.py",
}
#: this file and the README check of tests/end_to_end/test_readme_commands.py name the patterns
SELF = {"tests/end_to_end/test_self_contained.py", "tests/end_to_end/test_readme_commands.py"}


def _project_files() -> list[Path]:
    files = [REPO / "README.md"]
    for folder in FOLDERS:
        files += [p for p in (REPO / folder).rglob("*")
                  if p.suffix in SUFFIXES and p.is_file() and "__pycache__" not in p.parts
                  and not p.relative_to(REPO).as_posix().startswith("tests/data/")]
    return sorted(files)


def test_nothing_cites_the_design_notes_a_folder_outside_or_an_issue():
    found = []
    for path in _project_files():
        name = path.relative_to(REPO).as_posix()
        if name in EXCEPTIONS or name in SELF:
            continue
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            if OUTSIDE.search(line):
                found.append(f"{name}:{number}: {line.strip()}")
    assert not found, "\n".join(found)


def test_the_exceptions_still_need_their_sweep():
    """An exception that no longer cites anything is dropped from the list."""
    for name in EXCEPTIONS:
        assert OUTSIDE.search((REPO / name).read_text(encoding="utf-8")), name


def test_the_pattern_finds_what_it_is_for():
    for text in ('DESIGN section 4', "DESIGN's table", "(issue 28k)", "Issue 25's bullets",
                 "see ../shared/seeds", "the issue's target", "issues 5 and 24"):
        assert OUTSIDE.search(text), text
    for text in ("astropy issue #10456", "design notes", "tissue 3"):
        assert not OUTSIDE.search(text), text


def _links(page: Path) -> list[str]:
    """The relative link targets of a Markdown page (no scheme, no bare anchors)."""
    text = re.sub(r"```.*?```", "", page.read_text(encoding="utf-8"), flags=re.S)
    targets = re.findall(r"\]\(([^)\s]+)\)", text)
    return [t.split("#")[0] for t in targets
            if not re.match(r"[a-z]+:", t) and not t.startswith("#")]


PAGES = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]


@pytest.mark.parametrize("page", PAGES, ids=[p.name for p in PAGES])
def test_every_relative_link_resolves(page):
    for target in _links(page):
        assert (page.parent / target).exists(), f"{page.relative_to(REPO)}: {target}"


def test_the_link_check_sees_the_links():
    assert "docs/outputs.md" in _links(REPO / "README.md")
    assert "outputs.md" in _links(REPO / "docs" / "demo.md")

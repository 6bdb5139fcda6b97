"""Progress on every long command (antsim.progress): a bar on a terminal, a line every few
seconds off one, a campaign's length in words. The clock is injected: a fake one for the rule
itself, a short period for whole commands, so that no test waits for seconds to pass."""

from __future__ import annotations

import io
import json
import re

import pytest

import antsim.progress
from antsim.cli import main
from antsim.progress import Progress, span_words


@pytest.mark.parametrize(("seconds", "words"), [
    (3600.0, "1 hour"), (8 * 3600.0, "8 hours"), (86400.0, "24 hours"),
    (20 * 86400.0, "20 days"), (5400.0, "1.5 hours")])
def test_a_campaigns_length_in_words(seconds, words):
    assert span_words(seconds) == words


class FakeClock:
    def __init__(self):
        self.t = 100.0

    def __call__(self) -> float:
        return self.t


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def _quiet(progress: Progress) -> Progress:
    """``progress`` without its ticking thread: the test ticks it."""
    progress._stop.set()
    progress._thread.join()
    return progress


def test_off_a_terminal_a_line_every_period_of_the_clock_and_none_before():
    clock, stream = FakeClock(), io.StringIO()
    with _quiet(Progress("plan", clock=clock, stream=stream)) as progress:
        assert progress.mode == "lines"
        progress.stage("members", total=800, unit="member")
        clock.t += 4.9
        progress.tick()
        assert stream.getvalue() == ""  # a command that ends within 5 s writes nothing
        clock.t += 0.1
        progress.advance(200)
        progress.detail("2 noise models to go")
        progress.tick()
        clock.t += 3.0
        progress.tick()  # 3 s after the last line: none
        progress.stage("answering")
        clock.t += 2.0
        progress.tick()
    assert stream.getvalue().splitlines() == [
        "antsim plan: members: 200/800 member (25%); 2 noise models to go, 5 s",
        "antsim plan: answering, 10 s"]


def test_on_a_terminal_a_bar_and_off_nothing_at_all():
    terminal = Terminal()
    with _quiet(Progress("run", clock=FakeClock(), stream=terminal)) as progress:
        assert progress.mode == "bar"
        progress.stage("campaign", total=24.0, unit="h")
        progress.set(12.0)
        progress.tick()
    assert "campaign:  50%" in terminal.getvalue()
    silent = io.StringIO()
    with Progress("run", False, stream=silent, every_s=0.0) as progress:
        progress.stage("campaign", total=24.0, unit="h")
        progress.tick()
    assert progress.mode == "off" and silent.getvalue() == ""


@pytest.fixture
def fast_lines(monkeypatch):
    """Commands write their lines every 0.05 s instead of every 5 s."""
    monkeypatch.setattr(antsim.progress, "EVERY_S", 0.05)


def _lines(err: str, command: str) -> list[str]:
    return [line for line in err.splitlines() if line.startswith(f"antsim {command}: ")]


def test_run_writes_lines_off_a_terminal(fast_lines, write_scenario, short_ghigo_text,
                                          tmp_path, capsys):
    scenario = write_scenario(short_ghigo_text)
    assert main(["run", str(scenario), "--out", str(tmp_path / "out"), "--no-report"]) == 0
    lines = _lines(capsys.readouterr().err, "run")
    assert any(re.match(r"antsim run: campaign: [\d.]+/3 h \(\d+%\), \d+ s$", x) for x in lines)
    assert main(["run", str(scenario), "--out", str(tmp_path / "quiet"), "--no-report",
                 "--no-progress"]) == 0
    assert capsys.readouterr().err == ""


def test_plan_writes_lines_through_every_stage(fast_lines, repo_root, tmp_path, capsys):
    plan = tmp_path / "plan.toml"
    plan.write_text(
        f'name = "p"\nscenario = "{repo_root / "tests" / "data" / "scenarios" / "quiet.toml"}"'
        '\nmembers = 2\n[[variants]]\nname = "as run"\n'
        '[[answers.duration]]\nbased_on = "as run"\nterms = ["IA"]\ntarget_arcsec = 1.0\n'
        'unit = "hour"\nmax_days = 0.25\n', encoding="utf-8")
    assert main(["plan", str(plan), "--workers", "0", "--out", str(tmp_path / "out")]) == 0
    stages = {x.split(": ")[1].split(":")[0].split(",")[0]
              for x in _lines(capsys.readouterr().err, "plan")}
    assert {"1 variant", "answering 1 question", "figures"} <= stages, stages
    # its outputs say their units and sign
    doc = json.loads((tmp_path / "out" / "plan.json").read_text())
    assert doc["units"] == "arcsec"
    assert doc["sign_convention"] == "TPOINT's: true (observed) = raw (encoder) + correction"
    assert "all arcsec; sign of the terms: TPOINT's: true (observed) = raw (encoder) + " \
        "correction" in (tmp_path / "out" / "plan.txt").read_text()


def test_diagnose_writes_lines(fast_lines, repo_root, capsys):
    mmt = str(repo_root / "examples" / "mmt_20210821_k_and_e.dat")
    assert main(["diagnose", mmt]) == 0
    assert _lines(capsys.readouterr().err, "diagnose")
    assert main(["diagnose", mmt, "--no-progress"]) == 0
    assert not _lines(capsys.readouterr().err, "diagnose")

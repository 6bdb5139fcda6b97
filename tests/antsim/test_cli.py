"""The command line's own checks and answers: the terminal's encoding, the figures' backend,
the file a failed write was writing; ``antsim help COMMAND``, and a misspelt command or option
answered with the one meant (the bad-input suite holds the option cases)."""

from __future__ import annotations

import errno
import os
import subprocess
import sys
from pathlib import Path

import pytest

from antsim.cli import main, os_error_line

REPO = Path(__file__).resolve().parents[2]
BASE = REPO / "tests" / "data" / "bad_inputs" / "scenario" / "_base.toml"


def test_an_ascii_terminal_gets_escapes_not_a_traceback(tmp_path):
    """A scenario named in Greek on an ASCII stdout (PYTHONIOENCODING=ascii): exit 0, the
    name as backslash escapes (a UnicodeEncodeError after every file was written before)."""
    text = BASE.read_text(encoding="utf-8").replace('name = "bad_inputs_base"',
                                                    'name = "\u03a9mega_\u03b2ase"')
    scenario = tmp_path / "greek.toml"
    scenario.write_text(text, encoding="utf-8")
    env = dict(os.environ, PYTHONPATH=str(REPO), PYTHONIOENCODING="ascii")
    done = subprocess.run([sys.executable, "-m", "antsim", "run", str(scenario), "--out",
                           str(tmp_path / "out"), "--no-report", "--no-progress"],
                          capture_output=True, env=env, timeout=300)
    assert done.returncode == 0, done.stderr.decode("ascii", "replace")
    assert done.stdout.startswith(b"\\u03a9mega_\\u03b2ase: 12 cross scans")
    assert b"Traceback" not in done.stderr
    assert (tmp_path / "out" / "fit.json").exists()


def test_a_valid_backend_is_not_refused(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("MPLBACKEND", "agg")
    assert main(["run", str(BASE), "--out", str(tmp_path / "o"), "--no-progress"]) == 0
    assert (tmp_path / "o" / "report.html").exists()
    capsys.readouterr()


def test_a_failed_write_that_names_no_file_names_the_one_being_written(tmp_path):
    """ENOSPC from ``write`` knows only a descriptor; the line names the path that
    ``Path.write_text`` was writing (its own frame holds it)."""
    path = tmp_path / "diagnose.json"

    def failing_write(data: str) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    class FullPath(type(path)):
        def open(self, *args, **kwargs):
            handle = super().open(*args, **kwargs)
            handle.write = failing_write
            return handle

    with pytest.raises(OSError) as failed:
        FullPath(path).write_text("{}")
    assert failed.value.filename is None
    assert os_error_line(failed.value) == (
        f"{path}: No space left on device [ENOSPC]; files written before it are kept")


def test_a_failure_with_no_file_in_sight_says_system():
    try:
        raise OSError(errno.ENOSPC, "No space left on device")
    except OSError as err:
        assert os_error_line(err).startswith("system: No space left on device [ENOSPC]")


def test_help_command_prints_the_command_s_help(capsys):
    with pytest.raises(SystemExit) as done:
        main(["help", "run"])
    assert done.value.code == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: antsim run") and "--model" in out


def test_help_alone_prints_the_commands(capsys):
    with pytest.raises(SystemExit) as done:
        main(["help"])
    assert done.value.code == 0
    out = capsys.readouterr().out
    assert "run" in out and "antsim help COMMAND" in out


@pytest.mark.parametrize("argv, line", [
    (["rnu", "ghigo1990"], "antsim: error: command line: COMMAND = 'rnu': not a command of "
                           "antsim; did you mean run?"),
    (["help", "plna"], "antsim: error: command line: COMMAND = 'plna': not a command of "
                       "antsim; did you mean plan?"),
    (["xyzzy"], "antsim: error: command line: COMMAND = 'xyzzy': not a command of antsim; "
                "see antsim --help"),
])
def test_a_misspelt_command_is_one_line(argv, line, capsys):
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err == line + "\n"

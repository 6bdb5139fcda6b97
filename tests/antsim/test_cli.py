"""The command line (antsim.cli): the entry point (exit status passed through, no collection
at shutdown, quiet when its reader has left); its own checks and answers: the terminal's
encoding, the figures' backend, the file a failed write was writing; ``antsim help COMMAND``,
and a misspelt command or option answered with the one meant (the bad-input suite holds the
option cases)."""

from __future__ import annotations

import errno
import os
import subprocess
import sys
import tomllib
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


def test_console_script_and_module_use_the_command_entry_point():
    scripts = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["scripts"]
    assert scripts["antsim"] == "antsim.cli:command"
    assert "command()" in (REPO / "antsim" / "__main__.py").read_text()


def test_command_passes_the_exit_status_and_skips_the_shutdown_collection():
    """``command`` returns ``main``'s status (2: no subcommand) and leaves the collector off
    and the heap frozen, so that the interpreter's shutdown does not walk it."""
    code = ("import gc, sys; from antsim.cli import command; sys.argv = ['antsim']; "
            "status = command(); print(status, gc.isenabled(), gc.get_freeze_count() > 0, "
            "file=sys.stderr)")
    done = subprocess.run([sys.executable, "-c", code], env=_env(), capture_output=True,
                          text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stderr.splitlines()[-1] == "2 False True"
    assert "usage: antsim" in done.stdout


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(REPO), *filter(None, [os.environ.get("PYTHONPATH")])])}


def test_a_reader_that_left_ends_the_command_quietly(tmp_path):
    """``antsim scenarios | head -1``: stdout's reader has gone before the listing is
    written. The command ends as a shell expects of a process ended by SIGPIPE (status 141)
    with nothing on stderr: no traceback, no 'Exception ignored' at exit, no error line."""
    read_end, write_end = os.pipe()
    os.close(read_end)  # the reader has left before the first write
    try:
        done = subprocess.run([sys.executable, "-m", "antsim", "scenarios"], env=_env(),
                              stdout=write_end, stderr=subprocess.PIPE, text=True,
                              timeout=120, check=False, cwd=tmp_path)
    finally:
        os.close(write_end)
    assert done.returncode == 141, done.stderr
    assert done.stderr == ""


def test_the_command_line_starts_light():
    """Importing the command line loads neither scipy, astropy.coordinates, matplotlib nor
    simpy (each is large parts of a second): ``antsim --help`` and a misspelt option answer at
    once, and each command imports what it needs when it runs."""
    code = ("import sys, antsim.cli; print(sorted(m for m in sys.modules if m.split('.')[0] in "
            "('scipy', 'matplotlib', 'simpy') or m.startswith('astropy.coordinates')))")
    env = dict(os.environ, PYTHONPATH=str(REPO))
    done = subprocess.run([sys.executable, "-c", code], cwd=REPO, env=env, capture_output=True,
                          text=True, check=True)
    assert done.stdout.strip() == "[]"

"""The ``antsim`` entry point: exit status passed through, no collection at shutdown."""

from __future__ import annotations

import os
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_console_script_and_module_use_the_command_entry_point():
    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    assert scripts["antsim"] == "antsim.cli:command"
    assert "command()" in (ROOT / "antsim" / "__main__.py").read_text()


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
        [str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])])}


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

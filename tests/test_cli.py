"""The ``antsim`` entry point: exit status passed through, no collection at shutdown."""

from __future__ import annotations

import os
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


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
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])])}
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                          text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stderr.splitlines()[-1] == "2 False True"
    assert "usage: antsim" in done.stdout

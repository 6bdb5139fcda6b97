"""What the API's tests share: the 1990 scenario cut to 3 hours (``SHORT_EDITS``), the
command's run of it written once, and the one line a command prints for bad input."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import pytest

from antsim.cli import main as cli_main


def command(argv: list[str]) -> tuple[int, str, str]:
    """``antsim ARGV`` in this process: (exit status, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = cli_main(argv)
    return status, out.getvalue(), err.getvalue()


def command_error(argv: list[str]) -> str:
    """The one line ``antsim ARGV`` prints for bad input, without its ``antsim CMD: error:``
    head (what the API's InputError says)."""
    status, _, err = command(argv)
    assert status == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    head = f"antsim {argv[0]}: error: "
    assert lines[0].startswith(head), lines[0]
    return lines[0][len(head):]


@pytest.fixture(scope="session")
def command_run(tmp_path_factory, short_path) -> Path:
    """``antsim run short.toml --out DIR`` (its report too): DIR."""
    out = tmp_path_factory.mktemp("api_command") / "run"
    status, _, err = command(["run", str(short_path), "--out", str(out), "--no-progress"])
    assert status == 0, err
    return out

"""The command line's own answers: ``antsim help COMMAND``, and a misspelt command or option
answered with the one meant (the bad-input suite holds the option cases)."""

from __future__ import annotations

import pytest

from antsim.cli import main


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

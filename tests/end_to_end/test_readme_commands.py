"""Every command the README shows, run as a new user runs it, where the README says: antsim
installed from its wheel into a fresh virtual environment outside the clone
(``conftest.installed``), the Quick start in a copy of the clone, then the examples in the
README's order in the place its sentence "The examples below run in this order in ..." names
(the clone, or an empty directory), each one exiting 0 without a traceback.

The commands are parsed from the README's ``sh`` code blocks, and the place from its words, so
that a README change that breaks a command, or that sends the examples where the Quick
start's outputs are not, fails here. What differs from typing them, and why:

* ``python3 -m pip install . && REST``: the install is the ``installed`` fixture (this tree's
  wheel, its dependencies taken from the running interpreter: offline, and no minute of
  installing); ``REST`` runs in the copy of the clone.
* The copy of the clone is this tree without what ``.gitignore`` and a clone leave out
  (``.git``, caches, ``runs/``) and without an earlier ``antsim-demo/``.
* The test command of the Quick start runs the whole suite from a clone: it is not run here
  (it would run this test again); ``test_the_quick_start_test_command_is_what_ci_runs``
  holds it to ``.ci/run``.
* Long commands run reduced (``REDUCED``): the what-if plan with 20 members per variant and
  without its questions (the full plan takes minutes), blindtest with 2 cases.
* ``antsim serve`` runs in the background for each client command after it (a fresh server
  each, as a user would start one; ``--port 0``, the free port it prints substituted for the
  README's, so that parallel test runs never collide), and must stop cleanly on SIGINT
  (Ctrl-C). ``node`` commands are skipped when node is not installed.

It takes minutes on two shared cores (the demo, three 24-hour campaigns, diagnose's baseline,
the reduced plan, blindtest): more than the suite's budget for it, so it is not in the
default suite: ``.ci/run`` runs it as its own step
(``ANTSIM_README_COMMANDS=1 python3 -m pytest -q tests/end_to_end/test_readme_commands.py``).
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import signal
import subprocess
import threading
import time
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
README = (REPO / "README.md").read_text(encoding="utf-8")

TEST_COMMAND = 'python3 -m pip install -e ".[test]" && python3 -m pytest -q'
INSTALL = "python3 -m pip install . && "
#: README command -> the reduced one run here (see the module's docstring)
REDUCED = {
    "antsim plan ghigo1990_whatif --out runs/whatif":
        "antsim plan ghigo1990_whatif --out runs/whatif --members 20 --no-answers",
    "antsim blindtest --n 10 --seed 1": "antsim blindtest --n 2 --seed 1",
}
LISTENING = re.compile(r"listening on (\S+):(\d+) ")
#: the README's sentence that says where its examples run, and the places it may name
PLACE = re.compile(r"The examples below run in this order in (the clone|an empty directory), "
                   r"after the Quick start's")

needs_flag = pytest.mark.skipif(
    os.environ.get("ANTSIM_README_COMMANDS") != "1",
    reason="minutes: CI's own step (ANTSIM_README_COMMANDS=1 python3 -m pytest -q "
           "tests/end_to_end/test_readme_commands.py)")


def readme_commands(text: str = README) -> list[str]:
    """The command lines of the README's ``sh`` blocks, in order (continuations joined)."""
    commands = []
    for block in re.findall(r"^```sh\n(.*?)^```", text, re.M | re.S):
        for line in block.replace("\\\n", " ").splitlines():
            line = line.split(" #")[0].strip()
            if line and not line.startswith("#"):
                commands.append(" ".join(line.split()))
    return commands


def test_the_readme_parses_into_the_commands_this_test_knows():
    commands = readme_commands()
    assert commands.count(TEST_COMMAND) == 1
    assert sum(c.startswith(INSTALL) for c in commands) == 1
    for command in REDUCED:  # a README change to a reduced command must update REDUCED
        assert command in commands, command
    used = {c.split()[1] for c in commands if c.startswith("antsim ")}
    # every command of `antsim --help` has its example
    assert used >= {"scenarios", "run", "fit", "diagnose", "plan", "demo", "blindtest", "serve"}
    assert any(c.startswith("antsim serve ") for c in commands)


def _ci_run_lines() -> list[str]:
    """The lines of .ci/run (comments left out)."""
    text = (REPO / ".ci" / "run").read_text(encoding="utf-8")
    return [line for line in (line.strip() for line in text.splitlines())
            if not line.startswith("#")]


def test_the_quick_start_test_command_is_what_ci_runs():
    """The Quick start's second command is, character for character, a line of .ci/run."""
    assert TEST_COMMAND in readme_commands()
    assert TEST_COMMAND in _ci_run_lines(), \
        f".ci/run does not run the README's test command {TEST_COMMAND!r}"
    readme_step = ("ANTSIM_README_COMMANDS=1 python3 -m pytest -q "
                   "tests/end_to_end/test_readme_commands.py")
    assert readme_step in _ci_run_lines()  # this module's own step


def readme_place(text: str = README) -> str:
    """Where the README says its examples run: "the clone" or "an empty directory"."""
    places = PLACE.findall(" ".join(text.split()))
    assert len(places) == 1, "the README must say once where its examples run: " \
        "'The examples below run in this order in the clone (or: an empty directory), " \
        "after the Quick start's run'"
    return places[0]


def test_the_readme_says_where_its_examples_run():
    assert readme_place() in ("the clone", "an empty directory")
    assert readme_place("The examples below run in this order in an empty directory, after "
                        "the Quick start's run.") == "an empty directory"
    with pytest.raises(AssertionError, match="must say once where"):
        readme_place("The examples run somewhere.")


def copy_of_the_clone(target: Path) -> Path:
    """This tree as a fresh clone has it: without ``.git``, what ``.gitignore`` leaves out
    (caches, ``runs/``, builds) and an earlier demo's ``antsim-demo/``."""
    ignored = [line.strip().strip("/") for line in
               (REPO / ".gitignore").read_text(encoding="utf-8").splitlines()
               if line.strip() and not line.startswith("#")]
    shutil.copytree(REPO, target, ignore=shutil.ignore_patterns(".git", "antsim-demo",
                                                                *ignored))
    return target


def test_nothing_in_the_readme_points_outside_the_repository():
    for pattern in (r"\.\./", r"\bissue \d+", r"\bDESIGN\b", r"the issue's"):
        assert not re.search(pattern, README), pattern
    for target in re.findall(r"\]\(([^)#]+)\)", README):
        if not target.startswith("http"):
            assert (REPO / target).exists(), target


class Server:
    """``antsim serve`` of the README in the background on a free port."""

    def __init__(self, command: str, cwd: Path, env: dict[str, str]):
        argv = shlex.split(command)
        argv[argv.index("--port") + 1] = "0"
        self.process = subprocess.Popen(argv, cwd=cwd, env=env, stdin=subprocess.DEVNULL,
                                        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                        text=True)
        self.lines: list[str] = []
        self.port: str | None = None
        listening = threading.Event()

        def read():
            for line in self.process.stderr:
                self.lines.append(line)
                if (m := LISTENING.search(line)) and self.port is None:
                    self.port = m.group(2)
                    listening.set()
            listening.set()

        self.reader = threading.Thread(target=read, daemon=True)
        self.reader.start()
        if not listening.wait(120) or self.port is None:
            self.stop()
            raise AssertionError(f"{command}: not listening:\n{''.join(self.lines)}")

    def stop(self) -> int:
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)  # Ctrl-C, as the README says
            try:
                self.process.wait(60)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self.reader.join(10)
        return self.process.returncode


@needs_flag
def test_every_readme_command_runs_where_the_readme_says(installed, tmp_path):
    clone = copy_of_the_clone(tmp_path / "clone")
    assert not (clone / "runs").exists()
    place = readme_place()
    examples = clone if place == "the clone" else tmp_path / "empty"
    examples.mkdir(exist_ok=True)
    # a fresh machine: no cache of astropy's tables or of diagnose's baselines
    env = installed.environ(ANTSIM_CACHE=str(tmp_path / "cache"))
    serve: str | None = None
    readme_port: str | None = None
    servers = 0
    timings = []
    for command in readme_commands():
        if command == TEST_COMMAND:
            continue
        work = examples
        if command.startswith(INSTALL):  # the Quick start: in the clone, whatever follows
            command, work = command.removeprefix(INSTALL), clone
        command = REDUCED.get(command, command)
        if command.startswith("antsim serve "):
            serve = command
            readme_port = shlex.split(command)[shlex.split(command).index("--port") + 1]
            continue
        if command.startswith("node ") and shutil.which("node") is None:
            continue
        server = None
        if readme_port is not None and readme_port in command:
            servers += 1
            started = serve if servers == 1 else serve.replace("--out runs/served",
                                                               f"--out runs/served-{servers}")
            server = Server(started, work, env)
            command = command.replace(readme_port, server.port)
        start = time.perf_counter()
        try:
            done = subprocess.run(["bash", "-c", command], cwd=work, env=env,
                                  capture_output=True, text=True, timeout=600)
        finally:
            status = server.stop() if server is not None else 0
        timings.append(f"{time.perf_counter() - start:6.1f} s  {command}")
        assert done.returncode == 0, \
            f"{command} (in {place})\n{done.stdout[-2000:]}\n{done.stderr[-3000:]}"
        assert "Traceback" not in done.stderr, f"{command}\n{done.stderr[-3000:]}"
        if server is not None:
            assert status == 0, f"{serve} after SIGINT: {status}\n{''.join(server.lines)}"
    assert servers >= 1 and len(timings) >= 10, timings
    # the files the README tells a user to open
    for path in re.findall(r"`((?:runs|antsim-demo)/[\w./-]+\.\w+)`", README):
        assert (examples / path).is_file() or (clone / path).is_file(), path
    print("\n".join(timings))

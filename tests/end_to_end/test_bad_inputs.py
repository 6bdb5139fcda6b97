"""Bad input of every kind: one line naming the file, the field and the value, exit status 2,
and nothing recorded lost.

The cases are data files under ``tests/data/bad_inputs/<kind>/`` (scenario and plan TOML,
TPOINT data, model files, ECSV recordings, CSV measurements) and command lines, listed with
the line each must produce in ``tests/data/bad_inputs/expectations.toml``. Most files are a
valid base file of their folder (``_base.*``) with one textual edit, which the table states
and a test checks, so each case shows what breaks what. Every case runs through the real
command line in-process (:func:`antsim.cli.main`); a sample of them through a ``python -m
antsim`` subprocess as well. Each must: exit with status 2, print nothing on stdout and one
line on stderr, ``antsim <command>: error: <where>: <field> = <value>: <problem>``, with the
table's where, field and value and a phrase of the problem; and leave an output directory
that held a run's files byte for byte as it was (or, refused before anything ran, hold no
recordings).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tomllib
from contextlib import ExitStack
from pathlib import Path

import pytest

from antsim.cli import main

REPO = Path(__file__).resolve().parents[2]
DATA = REPO / "tests" / "data" / "bad_inputs"
TABLE = tomllib.loads((DATA / "expectations.toml").read_text(encoding="utf-8"))
CASES = {c["file"]: c for c in TABLE["case"]}
#: one case of each kind also runs as a subprocess: the console script's own exit path
SUBPROCESS_SAMPLE = TABLE["subprocess_sample"]


def expand(text: str, out: Path, file: Path) -> str:
    return (text.replace("{file}", str(file)).replace("{out}", str(out))
            .replace("{data}", str(DATA)).replace("{repo}", str(REPO)))


def materialize(case: dict) -> bytes | None:
    """The bytes the case file must hold, from its base and edit (None: not derived)."""
    if "base" not in case:
        return None
    text = (DATA / case["base"]).read_text(encoding="utf-8")
    for old, new in case.get("edits", []):
        count = text.count(old)
        if count != 1:
            raise AssertionError(f"{case['file']}: edit target {old!r} occurs {count} times in "
                                 f"{case['base']} (expected once)")
        text = text.replace(old, new)
    return text.encode("utf-8")


@pytest.fixture(scope="session")
def base_run(tmp_path_factory) -> Path:
    """A run of ``scenario/_base.toml`` (one hour), made once: copied where a case needs an
    output directory that already holds recorded scans."""
    out = tmp_path_factory.mktemp("base_run") / "run"
    assert main(["run", str(DATA / "scenario" / "_base.toml"), "--out", str(out),
                 "--no-report", "--no-progress"]) == 0
    return out


def _snapshot(path: Path) -> dict[str, bytes]:
    return {str(p.relative_to(path)): p.read_bytes() for p in sorted(path.rglob("*"))
            if p.is_file() and p.name != ".antsim.lock"}


def _lock_as(kind: str, precious_name: str = "precious.txt"):
    """A setup: ``out`` holds ``precious.txt`` (or an earlier demo's page) and a lock file
    that is a link to it (or a FIFO, a directory): the command must refuse it and leave the
    file as it was (the snapshot of ``out`` holds it)."""

    def setup(out: Path, base_run: Path) -> None:
        out.mkdir()
        precious = out / precious_name
        precious.write_text("precious\n", encoding="utf-8")
        lock = out / ".antsim.lock"
        {"symlink": lambda: lock.symlink_to(precious),
         "hardlink": lambda: os.link(precious, lock),
         "fifo": lambda: os.mkfifo(lock),
         "directory": lock.mkdir}[kind]()

    return setup


def _run_with(edit):
    def setup(out: Path, base_run: Path) -> None:
        shutil.copytree(base_run, out)
        edit(out)

    return setup


def _foreign_row(out: Path) -> None:
    """A complete row appended after the run's last one: its last row under the next scan
    number, as another program might write it."""
    path = out / "recordings.ecsv"
    last = path.read_text(encoding="utf-8").splitlines()[-1]
    scan, rest = last.split(" ", 1)
    with path.open("a", encoding="utf-8") as fh:
        fh.write(f"{int(scan) + 1} {rest}\n")


def _recordings_as_link(out: Path) -> None:
    elsewhere = out.parent / "elsewhere.ecsv"
    (out / "recordings.ecsv").rename(elsewhere)
    (out / "recordings.ecsv").symlink_to(elsewhere)


def _dangling_report(out: Path, base_run: Path) -> None:
    out.mkdir()
    (out / "report.html").symlink_to(out.parent / "nowhere.html")


def _links_to_precious(*names: str):
    """A setup: ``out`` holds ``precious.txt`` and links to it named as outputs (a dangling
    one where a name ends in "-dangling")."""

    def setup(out: Path, base_run: Path) -> None:
        out.mkdir()
        precious = out / "precious.txt"
        precious.write_text("precious\n", encoding="utf-8")
        for name in names:
            if name.endswith("-dangling"):
                (out / name.removesuffix("-dangling")).symlink_to(out.parent / "nowhere")
            else:
                (out / name).symlink_to(precious)

    return setup


def _earlier_session(out: Path, base_run: Path) -> None:
    out.mkdir()
    (out / "requests.jsonl").write_text('{"request": "clock"}\n', encoding="utf-8")


#: setups of the output directory beyond "run", "lock" and "no_permission"
LINKED_SETUPS = {
    **{f"lock_{kind}": _lock_as(kind) for kind in ("symlink", "hardlink", "fifo", "directory")},
    "demo_lock_symlink": _lock_as("symlink", "demo.html"),
    "run_foreign_row": _run_with(_foreign_row),
    "run_recordings_link": _run_with(_recordings_as_link),
    "dangling_report": _dangling_report,
    "earlier_session": _earlier_session,
    "diagnose_json_link": _links_to_precious("diagnose.json"),
    "diagnose_figure_links": _links_to_precious("diagnose_residuals.png", "report.html"),
    "requests_dangling_link": _links_to_precious("requests.jsonl-dangling"),
    "recordings_fifo": lambda out, base_run: (out.mkdir(), os.mkfifo(out / "recordings.ecsv")),
}


def prepare(case: dict, tmp: Path, base_run: Path | None, monkeypatch,
            stack: ExitStack) -> tuple[list[str], Path]:
    """The command line of ``case`` and its output directory, set up as the case says."""
    out = tmp / "out"
    setup = case.get("setup")
    for name, value in case.get("env", {}).items():
        monkeypatch.setenv(name, value)
    if setup in LINKED_SETUPS:
        LINKED_SETUPS[setup](out, base_run)
    elif setup == "run":
        shutil.copytree(base_run, out)
    elif setup == "lock":
        from antsim.outdir import DirectoryLock

        out.mkdir()
        # the command runs in this process: flock on a second open file of the same lock
        # file conflicts with this one as another process's would
        stack.enter_context(DirectoryLock(out, command="another antsim (test)"))
    elif setup == "no_permission":
        real_open = os.open

        def refuse(path, flags, *args, **kwargs):
            if str(path).startswith(str(out)):
                raise PermissionError(13, "Permission denied", str(path))
            return real_open(path, flags, *args, **kwargs)

        monkeypatch.setattr(os, "open", refuse)
    file = DATA / case["file"]
    return [expand(a, out, file) for a in case["args"]], out


def check_line(case: dict, status: int, stdout: str, stderr: str, out: Path, file: Path):
    command = case["args"][0]
    assert status == 2, f"exit {status}; stderr: {stderr}"
    assert stdout == ""
    assert "Traceback" not in stderr
    lines = stderr.splitlines()
    assert len(lines) == 1, stderr
    line = lines[0]
    head = f"antsim {command}: error: {expand(case['where'], out, file)}: {case['field']} = "
    assert line.startswith(head), f"\n{line}\n{head}"
    rest = line[len(head):]
    if case["value"] != "*":
        value = expand(case["value"], out, file)
        assert rest.startswith(value + ": "), f"\n{line}\nvalue {value}"
        rest = rest[len(value) + 2:]
    assert expand(case["says"], out, file) in rest, line


@pytest.mark.parametrize("name", list(CASES))
def test_bad_input_is_one_line_and_exit_2(name, tmp_path, base_run, monkeypatch, capsys):
    case = CASES[name]
    with ExitStack() as stack:
        args, out = prepare(case, tmp_path, base_run, monkeypatch, stack)
        before = _snapshot(out) if out.exists() else {}
        status = main(args)
    captured = capsys.readouterr()
    check_line(case, status, captured.out, captured.err, out, DATA / case["file"])
    # nothing recorded lost: a directory that held a run holds it byte for byte; a refused
    # command records nothing
    assert (_snapshot(out) if out.exists() else {}) == before


@pytest.mark.parametrize("name", SUBPROCESS_SAMPLE)
def test_bad_input_through_the_console_script(name, tmp_path, base_run, repo_root):
    case = CASES[name]
    assert case.get("setup") in (None, "run"), "a subprocess case cannot be set up in-process"
    with ExitStack() as stack:
        args, out = prepare(case, tmp_path, base_run, None, stack)
    env = dict(os.environ, PYTHONPATH=str(repo_root))
    proc = subprocess.run([sys.executable, "-m", "antsim", *args], capture_output=True,
                          text=True, cwd=tmp_path, env=env, timeout=300)
    check_line(case, proc.returncode, proc.stdout, proc.stderr, out, DATA / case["file"])


@pytest.mark.parametrize("name", [n for n, c in CASES.items() if "base" in c]
                         + [f["file"] for f in TABLE.get("fixture", [])])
def test_each_case_file_is_its_base_with_the_edit_the_table_states(name):
    case = CASES.get(name) or next(f for f in TABLE["fixture"] if f["file"] == name)
    assert (DATA / case["file"]).read_bytes() == materialize(case)


def test_the_base_files_are_good_input(base_run, capsys):
    """Each case fails because of its edit: the bases themselves are accepted."""
    assert (base_run / "fit.json").exists()
    for args in (["fit", str(DATA / "ecsv" / "_base.ecsv")],
                 ["fit", str(DATA / "ecsv" / "_sensors.ecsv"), "--terms", "IA,IE,TEDFB"],
                 ["fit", str(DATA / "csv" / "_base.csv")],
                 ["fit", str(DATA / "tpoint" / "_base.dat")],
                 ["fit", str(DATA / "ecsv" / "_base.ecsv"), "--model",
                  str(DATA / "model" / "_base.mod")],
                 ["fit", str(DATA / "ecsv" / "_base.ecsv"), "--model",
                  str(DATA / "model" / "_base.json")]):
        assert main(args) == 0, capsys.readouterr().err
    from antsim.plan.planfile import load_plan

    assert len(load_plan(DATA / "plan" / "_base.toml").variants) == 2
    capsys.readouterr()


def test_the_suite_covers_every_kind_of_input():
    """At least 150 cases, spread over every kind of input."""
    kinds: dict[str, int] = {}
    for name in CASES:
        kinds[name.split("/")[0]] = kinds.get(name.split("/")[0], 0) + 1
    assert len(CASES) >= 150, kinds
    assert set(kinds) >= {"scenario", "plan", "tpoint", "model", "ecsv", "csv", "cli", "outdir"}
    assert min(kinds.values()) >= 8, kinds

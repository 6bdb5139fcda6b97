"""benchmarks/publish.py: one command regenerates every kept output the docs quote, and the
kept outputs are what the code makes now (each result's reduced check, rerun here, gives the
output recorded when the file was published: a file the code no longer makes fails)."""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
_spec = importlib.util.spec_from_file_location("publish", REPO / "benchmarks" / "publish.py")
publish = importlib.util.module_from_spec(_spec)
sys.modules["publish"] = publish  # dataclasses look their module up while it is made
_spec.loader.exec_module(publish)

#: the results whose files were made before publish.py, with no record of their reduced
#: check yet: the long ones, and blind.py --real/--bound, which fail on main (a thermal
#: candidate in the finding pool needs the recordings' temperatures). `python
#: benchmarks/publish.py NAME` records one; then drop it here (a test says so).
AWAITING = {"recovery", "blind", "blind_nulls", "blind_fomalont", "blind_changes",
            "blind_tpoint", "blind_tpoint_nulls", "blind_real", "blind_bound",
            "crane1981_diagnose", "crane1981_days"}
#: the commands of the long results, as the docs name them (the arguments that made the
#: kept files): the dry run must list exactly these
LONG = {
    "recovery": "python benchmarks/recovery.py --seeds 200 --jobs 2",
    "blind": "python benchmarks/blind.py --n 120 --seed 1 --jobs 2",
    "blind_nulls": "python benchmarks/blind.py --n 100 --seed 2 --null-fraction 1 --jobs 2",
    "blind_fomalont": "python benchmarks/blind.py --fomalont",
    "blind_changes": "python benchmarks/blind.py --changes",
    "blind_tpoint": "python benchmarks/blind.py --tpoint --n 90",
    "blind_tpoint_nulls": "python benchmarks/blind.py --tpoint --n 100 --null-fraction 1",
    "crane1981_diagnose": "python benchmarks/crane1981_diagnose.py --seeds 10 --nulls 6",
    "crane1981_days": "python benchmarks/crane1981_days.py --workers 2",
    "ghigo1990_tables": "python benchmarks/ghigo1990_tables.py --seeds 20 --workers 2",
    "plan_accuracy": "python benchmarks/plan_accuracy.py --workers 1",
}
#: how the docs quote each command (a part of it: the rest are the script's defaults)
QUOTED = {
    "recovery": "python benchmarks/recovery.py",
    "blind": "python benchmarks/blind.py --n 120 --seed 1 --jobs 2",
    "blind_nulls": "--n 100 --seed 2 --null-fraction 1",
    "blind_fomalont": "python benchmarks/blind.py\n--fomalont",
    "blind_changes": "python benchmarks/blind.py --changes",
    "blind_tpoint": "python benchmarks/blind.py --tpoint --n 90",
    "blind_tpoint_nulls": "--n 100\n--null-fraction 1",
    "blind_real": "python benchmarks/blind.py --real --nested",
    "blind_bound": "python benchmarks/blind.py --bound",
    "crane1981_diagnose": "python\nbenchmarks/crane1981_diagnose.py --seeds 10 --nulls 6",
    "crane1981_days": "python benchmarks/crane1981_days.py",
    "crane1981": "python benchmarks/crane1981.py",
    "ghigo1990_tables": "python benchmarks/ghigo1990_tables.py --seeds 20",
    "plan_accuracy": "python benchmarks/plan_accuracy.py --workers 1",
    "ghigo1990_whatif": "antsim plan scenarios/plans/ghigo1990_whatif.toml",
    "ghigo1990_sensors_whatif": "antsim plan scenarios/plans/ghigo1990_sensors_whatif.toml",
    "bima_study": "python benchmarks/bima_study.py",
}
DOCS = "\n".join(p.read_text(encoding="utf-8")
                 for p in [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))])


def test_the_dry_run_lists_every_result_with_its_arguments():
    done = subprocess.run([sys.executable, "benchmarks/publish.py", "--list"], cwd=REPO,
                          capture_output=True, text=True, check=True)
    for result in publish.RESULTS:
        assert f"docs/results/{result.name}.txt" in done.stdout
        assert f"  {result.shown()}\n" in done.stdout
        assert f"  check: {result.shown(result.check)}\n" in done.stdout
    for name, command in LONG.items():
        assert publish.BY_NAME[name].shown() == command, name
        assert publish.BY_NAME[name].minutes > publish.SHORT_MINUTES, name
    short = subprocess.run([sys.executable, "benchmarks/publish.py", "--list", "--short"],
                           cwd=REPO, capture_output=True, text=True, check=True).stdout
    assert "bima_study" in short and "recovery" not in short


def test_every_kept_file_has_its_command_and_the_docs_quote_it():
    kept = {p.stem for p in publish.RESULTS_DIR.glob("*.txt")}
    assert kept <= set(publish.BY_NAME), kept - set(publish.BY_NAME)
    assert set(QUOTED) == set(publish.BY_NAME)
    for result in publish.RESULTS:
        script = next(a for a in result.command if a.endswith(".py") or a == "antsim")
        assert script == "antsim" or (REPO / script).is_file(), script
        quote = QUOTED[result.name]
        assert quote in DOCS, quote
        if quote.startswith("antsim plan"):
            assert quote.split("/")[-1].removesuffix(".toml") in result.command
            continue
        # every argument the docs give is the command's (the others are defaults)
        words = quote.replace("python", "").split()
        for flag, value in zip(words, [*words[1:], ""], strict=True):
            if flag.startswith("--"):
                at = result.command.index(flag)
                if value and not value.startswith("--"):
                    assert result.command[at + 1] == value, (result.name, flag)


def test_wall_times_are_compared_without_their_value():
    blind = publish.BY_NAME["blind"]
    assert publish.normalized("wall time 1337 s\nfalse alarms 0/23", blind) == \
        "<time>\nfalse alarms 0/23"
    assert publish.normalized("tau 4947 +- 1109 s", blind) == "tau 4947 +- 1109 s"
    # a time that ends the first line of many (not the text) is taken out too
    accuracy = publish.BY_NAME["plan_accuracy"]
    assert publish.normalized("plan x: 200 members; 1 worker; 14 s\n\nvariant  W1", accuracy) \
        == "plan x: 200 members; 1 worker<time>\n\nvariant  W1"


def test_the_records_are_the_registrys():
    record = publish.manifest()
    assert set(record) == set(publish.BY_NAME) - AWAITING, (
        "published: drop it from AWAITING" if set(record) & AWAITING else "no record")
    for name, kept in record.items():
        result = publish.BY_NAME[name]
        assert kept["command"] == result.shown() and kept["check"] == result.shown(result.check)
        assert re.match(r"\d{4}-\d\d-\d\d \d\d:\d\d UTC$", kept["date"]) and kept["machine"]


@pytest.mark.parametrize("name", sorted(set(publish.BY_NAME) - AWAITING))
def test_the_kept_file_is_what_the_code_makes_now(name):
    """The reduced check now against the record; where the check is the command itself, the
    file too."""
    result = publish.BY_NAME[name]
    now = publish.check_output(result)
    assert now == publish.manifest()[name]["check_output"], \
        f"docs/results/{name}.txt is stale: python benchmarks/publish.py {name}"
    if result.check == result.command:
        assert now == publish.normalized(result.path.read_text(encoding="utf-8"), result)


def test_a_failing_command_publishes_nothing_unless_its_status_says_a_criterion_missed():
    """A command exiting with a status its result does not declare raises; a declared one
    ('criterion not met', said in the output) is kept as it is; a crash (Python's 1) is never
    published."""
    argv = ("-c", "print('criterion: NOT met'); raise SystemExit(3)")
    with pytest.raises(RuntimeError, match="exited 3"):
        publish.run(publish.Result("strict", argv, argv, 0.0), argv)
    missed = publish.Result("missed", argv, argv, 0.0, exits=(0, 3))
    text, _ = publish.run(missed, argv)
    assert text == "criterion: NOT met\n"
    crash = ("-c", "raise ValueError('boom')")
    with pytest.raises(RuntimeError, match="exited 1"):
        publish.run(publish.Result("crash", crash, crash, 0.0, exits=(0, 3)), crash)
    assert publish.BY_NAME["plan_accuracy"].exits == (0, 3)

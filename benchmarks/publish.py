"""Regenerate every published result: the kept outputs in docs/results/ that the docs quote.

    python benchmarks/publish.py                 # every result (hours: see --list)
    python benchmarks/publish.py bima_study plan_accuracy    # the named ones
    python benchmarks/publish.py --short         # those that take minutes, not hours
    python benchmarks/publish.py --list          # what would run, with its arguments
    python benchmarks/publish.py --check NAME    # only the reduced check, against the record

Each result is one command (a benchmark, or ``antsim plan``) with fixed arguments,
:data:`RESULTS`. Publishing runs it from the repository's root, writes its output to
``docs/results/NAME.txt`` (the repository's path taken out of file names, so that the file
is the same wherever the clone is), prints what changed against the file it replaces, and
records in ``docs/results/manifest.json`` the command, antsim's version, the commit, the
machine, the date and the wall time, with the output of the result's reduced check: the same
command on a few seeds or cases, short enough to run in the tests
(``tests/benchmarks/test_publish.py`` reruns it and compares, so that a file the code no
longer makes fails). Then the docs' numbers are checked against the files by
``tests/end_to_end/test_readme.py`` and the tests named beside them: run the suite after publishing.

Lines that report a wall time are compared without it (:attr:`Result.timing`): a machine's
speed is not a result.
"""

from __future__ import annotations

import argparse
import datetime
import difflib
import json
import os
import platform
import re
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS_DIR = ROOT / "docs" / "results"
MANIFEST = RESULTS_DIR / "manifest.json"
#: the placeholder of a command's output directory (for commands that write their result)
OUT = "{out}"


@dataclass(frozen=True)
class Result:
    """One kept output: ``docs/results/{name}.txt``."""

    name: str
    #: the command, after ``python``: a script of benchmarks/ or ``-m antsim ...``
    command: tuple[str, ...]
    #: the reduced check: the same command on a few seeds or cases (seconds, not minutes)
    check: tuple[str, ...]
    #: roughly how long the full command takes on two shared cores, minutes
    minutes: float
    #: the file the command writes in ``{out}`` (None: its standard output)
    output: str | None = None
    #: regular expressions of the wall times in its output (compared without them)
    timing: tuple[str, ...] = ()
    #: exit statuses that still make an output to keep: a benchmark may exit with a status
    #: of its own (not 1, Python's for a failure) when its criterion is not met, and say so
    #: in the output, which is published as it is
    exits: tuple[int, ...] = (0,)

    @property
    def path(self) -> Path:
        return RESULTS_DIR / f"{self.name}.txt"

    def shown(self, argv: tuple[str, ...] | None = None) -> str:
        return "python " + " ".join(argv or self.command)


def _blind(*args: str) -> tuple[str, ...]:
    return ("benchmarks/blind.py", *args)


def _plan(name: str, *args: str) -> tuple[str, ...]:
    return ("-m", "antsim", "plan", name, "--no-progress", "--out", OUT, *args)


RESULTS: tuple[Result, ...] = (
    Result("recovery", ("benchmarks/recovery.py", "--seeds", "200", "--jobs", "2"),
           ("benchmarks/recovery.py", "--seeds", "2", "--calibration", "2", "--jobs", "1"),
           50.0),
    Result("blind", _blind("--n", "120", "--seed", "1", "--jobs", "2"),
           _blind("--n", "2", "--seed", "1", "--jobs", "1"), 25.0,
           timing=(r"(?m)^wall time \d+ s$",)),
    Result("blind_nulls", _blind("--n", "100", "--seed", "2", "--null-fraction", "1",
                                 "--jobs", "2"),
           _blind("--n", "2", "--seed", "2", "--null-fraction", "1", "--jobs", "1"), 4.0,
           timing=(r"(?m)^wall time \d+ s$",)),
    Result("blind_fomalont", _blind("--fomalont"), _blind("--fomalont", "--seeds", "1"),
           5.0),
    Result("blind_changes", _blind("--changes"), _blind("--changes", "--seeds", "1"), 10.0),
    Result("blind_tpoint", _blind("--tpoint", "--n", "90"), _blind("--tpoint", "--n", "9"),
           5.0),
    Result("blind_tpoint_nulls", _blind("--tpoint", "--n", "100", "--null-fraction", "1"),
           _blind("--tpoint", "--n", "5", "--null-fraction", "1"), 5.0),
    Result("blind_real", _blind("--real", "--nested"), _blind("--real"), 1.0,
           timing=(r"\((?:\d+\.)?\d+ s\)",)),
    Result("blind_bound", _blind("--bound"), _blind("--bound", "--max-findings", "2"), 0.5,
           timing=(r"\(\d+ s, every combination\)",)),
    Result("crane1981_diagnose", ("benchmarks/crane1981_diagnose.py", "--seeds", "10",
                                  "--nulls", "6"),
           ("benchmarks/crane1981_diagnose.py", "--seeds", "1", "--nulls", "0", "--sims", "2",
            "--jobs", "1"), 8.0),
    Result("crane1981", ("benchmarks/crane1981.py",), ("benchmarks/crane1981.py",), 0.3,
           timing=(r"(?m)^\(\d+\.\d+ s\)$",)),
    Result("crane1981_days", ("benchmarks/crane1981_days.py", "--workers", "2"),
           ("benchmarks/crane1981_days.py", "--members", "2", "--workers", "1"), 6.0,
           timing=(r"\(\d+ s\)", r"(?m); \d+ s$")),
    Result("ghigo1990_tables", ("benchmarks/ghigo1990_tables.py", "--seeds", "20",
                                "--workers", "2"),
           ("benchmarks/ghigo1990_tables.py", "--seeds", "1", "--workers", "1"), 4.0),
    Result("plan_accuracy", ("benchmarks/plan_accuracy.py", "--workers", "1"),
           ("benchmarks/plan_accuracy.py", "--workers", "1", "--members", "4"), 3.0,
           timing=(r"(?m); \d+ s$",), exits=(0, 3)),
    Result("ghigo1990_whatif", _plan("ghigo1990_whatif", "--workers", "2"),
           _plan("ghigo1990_whatif", "--workers", "1", "--members", "4", "--no-answers"),
           2.0, output="plan.txt"),
    Result("ghigo1990_sensors_whatif", _plan("ghigo1990_sensors_whatif", "--workers", "2"),
           _plan("ghigo1990_sensors_whatif", "--workers", "1", "--members", "4",
                 "--no-answers"), 2.0, output="plan.txt"),
    Result("bima_study", ("benchmarks/bima_study.py",), ("benchmarks/bima_study.py",), 0.2,
           timing=(r"(?m)^\(\d+\.\d+ s\)$",)),
)
BY_NAME = {r.name: r for r in RESULTS}
#: results quick enough for --short (minutes on two shared cores)
SHORT_MINUTES = 2.5


def normalized(text: str, result: Result) -> str:
    """``text`` with the wall times taken out (``<time>``), for comparing two runs."""
    for pattern in result.timing:
        text = re.sub(pattern, "<time>", text)
    return text


def run(result: Result, argv: tuple[str, ...]) -> tuple[str, float]:
    """Run ``python argv`` from the repository's root (this tree's antsim first on the path)
    and return its output, the repository's path taken out, and its wall time (s)."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])]), MPLBACKEND="Agg")
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        args = [a.replace(OUT, str(out)) for a in argv]
        start = time.perf_counter()
        done = subprocess.run([sys.executable, *args], cwd=ROOT, env=env,
                              capture_output=True, text=True)
        wall = time.perf_counter() - start
        if done.returncode not in result.exits:
            raise RuntimeError(f"{' '.join(args)} exited {done.returncode}:\n{done.stderr}")
        text = (out / result.output).read_text(encoding="utf-8") if result.output \
            else done.stdout
    text = text.replace(str(ROOT) + os.sep, "")
    return re.sub(r"/tmp/[^\s:]*", "<tmp>", text), wall


def manifest() -> dict:
    return json.loads(MANIFEST.read_text(encoding="utf-8")) if MANIFEST.exists() else {}


def check_output(result: Result) -> str:
    """The reduced check's output now, wall times taken out."""
    return normalized(run(result, result.check)[0], result)


def _commit() -> str:
    try:
        done = subprocess.run(["git", "describe", "--always", "--dirty"], cwd=ROOT,
                              capture_output=True, text=True, check=True)
        return done.stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def changes(old: str, new: str, name: str, limit: int = 40) -> str:
    """What changed, as a unified diff cut to ``limit`` lines."""
    if old == new:
        return f"{name}: unchanged"
    diff = list(difflib.unified_diff(old.splitlines(), new.splitlines(), f"{name} (kept)",
                                     f"{name} (now)", n=0, lineterm=""))
    more = f"\n... {len(diff) - limit} more diff lines" if len(diff) > limit else ""
    return "\n".join(diff[:limit]) + more


def publish(result: Result) -> str:
    """Run the result's command and its reduced check, write the file and the record;
    return what changed."""
    from antsim import __version__

    text, wall = run(result, result.command)
    old = result.path.read_text(encoding="utf-8") if result.path.exists() else ""
    result.path.write_text(text, encoding="utf-8")
    record = manifest()
    record[result.name] = {
        "command": result.shown(),
        "check": result.shown(result.check),
        "check_output": check_output(result),
        "antsim": __version__,
        "commit": _commit(),
        "machine": f"{platform.node()}: {os.cpu_count()} cores, {platform.machine()}, "
                   f"Python {platform.python_version()}",
        "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "wall_s": round(wall, 1),
    }
    MANIFEST.write_text(json.dumps(dict(sorted(record.items())), indent=2) + "\n",
                        encoding="utf-8")
    return changes(normalized(old, result), normalized(text, result), result.path.name)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*", metavar="NAME",
                        help=f"results to publish (default: all): {', '.join(BY_NAME)}")
    parser.add_argument("--short", action="store_true",
                        help=f"only those under {SHORT_MINUTES:g} minutes")
    parser.add_argument("--list", "--dry-run", dest="list", action="store_true",
                        help="print what would run, and exit")
    parser.add_argument("--check", action="store_true",
                        help="run only the reduced checks and compare with the record")
    args = parser.parse_args()
    unknown = [n for n in args.names if n not in BY_NAME]
    if unknown:
        parser.error(f"unknown result {', '.join(unknown)}; known: {', '.join(BY_NAME)}")
    chosen = [BY_NAME[n] for n in args.names] if args.names else list(RESULTS)
    if args.short:
        chosen = [r for r in chosen if r.minutes <= SHORT_MINUTES]
    if args.list:
        for r in chosen:
            print(f"{r.path.relative_to(ROOT)}  (~{r.minutes:g} min)\n  {r.shown()}\n"
                  f"  check: {r.shown(r.check)}")
        return 0
    status = 0
    for r in chosen:
        if args.check:
            kept = manifest().get(r.name)
            start = time.perf_counter()
            now = check_output(r)
            same = kept is not None and kept["check_output"] == now
            verdict = ("as recorded" if same else "no record" if kept is None
                       else "DIFFERS from the record")
            print(f"{r.name}: {verdict} ({time.perf_counter() - start:.0f} s)", flush=True)
            status |= not same
            continue
        print(f"publishing {r.name}: {r.shown()}", flush=True)
        print(publish(r), flush=True)
    return status


if __name__ == "__main__":
    sys.exit(main())

"""The checks of tests/test_rendering.py, run in a fresh Python process.

A fork copies only the calling thread, and the test process may have threads left by
earlier tests (dask's), so :mod:`antsim.rendering` would rightly refuse to fork there. This
script starts single-threaded, simulates the short scenario given as ``argv[1]``, runs each
check in a directory under ``argv[2]`` and prints one JSON object of findings.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
import warnings
from dataclasses import replace
from functools import wraps
from pathlib import Path

from antsim import rendering
from antsim.figures import run as figures
from antsim.run.outputs import run_fits, write_outputs
from antsim.run.runner import simulate
from antsim.scenario import load_scenario


def tree_bytes(root: Path) -> dict[str, str]:
    """Every file under ``root`` by its relative path, as hex."""
    return {str(p.relative_to(root)): p.read_bytes().hex()
            for p in sorted(root.rglob("*")) if p.is_file()}


def file_bytes(files) -> dict[str, str]:
    return {Path(f.path).name: Path(f.path).read_bytes().hex() for f in files}


COMMAND = """
import sys, time
from antsim import rendering
process = rendering.OutputProcess.start()
print(process._process.pid, flush=True)
try:
    time.sleep(120)
except KeyboardInterrupt:
    sys.exit(130)
"""


DRAWING_COMMAND = """
import sys, time
from pathlib import Path
from antsim import figures, rendering
from antsim.runner import run_campaign
from antsim.scenario import load_scenario

scenario, out = sys.argv[1], Path(sys.argv[2])

def slow(*args, **kwargs):  # a figure that takes a minute, so that Ctrl-C comes during it
    (out / "drawing").write_text("")
    time.sleep(60)

for name in rendering._COST:
    setattr(figures, name, slow)
process = rendering.OutputProcess.start()
result = run_campaign(load_scenario(scenario), out / "run", show_progress=False)
print(process._process.pid, flush=True)
try:
    process.write_outputs(result)
except KeyboardInterrupt:
    sys.exit(130)
"""


def stat_fields(pid: int | str) -> list[str] | None:
    """The fields of ``/proc/PID/stat`` after the command name (state first, then ppid,
    pgid, ...), None for a process that is gone."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except (FileNotFoundError, ProcessLookupError, IndexError):
        return None


def group_alive(pgid: int) -> list[int]:
    """Processes (not zombies) of process group ``pgid``."""
    alive = []
    for entry in Path("/proc").glob("[0-9]*"):
        fields = stat_fields(entry.name)
        if fields is not None and fields[0] != "Z" and int(fields[2]) == pgid:
            alive.append(int(entry.name))
    return alive


def interrupted_while_drawing(scenario: Path, out: Path) -> dict:
    """Ctrl-C while the output process and its second drawer draw: every process of the
    command's group ends within 10 s (a figure here takes a minute)."""
    out.mkdir()
    command = subprocess.Popen([sys.executable, "-c", DRAWING_COMMAND, str(scenario), str(out)],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               start_new_session=True)
    command.stdout.readline()  # the campaign is done, the outputs asked for
    deadline = time.monotonic() + 60.0
    while not (out / "drawing").exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    drawing = (out / "drawing").exists()
    os.killpg(command.pid, signal.SIGINT)
    command.wait(timeout=30)
    deadline = time.monotonic() + 10.0
    while group_alive(command.pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    left = group_alive(command.pid)
    for pid in left:
        os.kill(pid, signal.SIGKILL)
    return {"drawing": drawing, "left": len(left), "status": command.returncode}


def ended(pid: int) -> bool:
    """Gone, or a zombie waiting for its (new) parent to reap it."""
    fields = stat_fields(pid)
    return fields is None or fields[0] == "Z"


def command_ends(sig: int) -> dict:
    """Start a command that holds an output process, send it ``sig`` (SIGINT to its process
    group, as a terminal's Ctrl-C; SIGKILL to the command alone, as tests/test_campaign.py
    does), and say whether the output process ended within 10 s and what was printed."""
    command = subprocess.Popen([sys.executable, "-c", COMMAND], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, start_new_session=True)
    pid = int(command.stdout.readline())
    time.sleep(0.5)  # the output process is importing matplotlib now
    if sig == signal.SIGINT:
        os.killpg(command.pid, sig)
    else:
        os.kill(command.pid, sig)
    command.wait(timeout=30)
    deadline = time.monotonic() + 10.0
    while not ended(pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    if not ended(pid):
        os.kill(pid, signal.SIGKILL)
        return {"ended": False, "stderr": command.stderr.read()}
    return {"ended": True, "stderr": command.stderr.read()}


def in_dir(result, out: Path):
    out.mkdir(parents=True)
    return replace(result, out_dir=out)


def pid_tagging(func):
    """``func`` (a figure function) leaving the pid of the process that drew beside the PNG."""

    @wraps(func)
    def tagged(*args, **kwargs):
        drawn = func(*args, **kwargs)
        drawn.path.with_suffix(".pid").write_text(str(os.getpid()))
        return drawn

    return tagged


def main() -> None:
    scenario, out = Path(sys.argv[1]), Path(sys.argv[2])
    result = simulate(load_scenario(scenario))
    found: dict = {"available": rendering.rendering_available()}

    # the same files (fits, tables, model, figures, report) as written here, no warning
    here = in_dir(result, out / "here")
    summary_here = write_outputs(here, report=True)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        summary_there = rendering.OutputProcess.start().write_outputs(
            in_dir(result, out / "there"))
    same_files = tree_bytes(out / "here") == tree_bytes(out / "there")
    found["same"] = {
        "files": sorted(tree_bytes(out / "there")),
        "bytes": same_files,
        "summary": summary_here.replace("/here/", "/there/") == summary_there,
        "warnings": [str(w.message) for w in caught],
    }

    # the second drawer draws the figures of the recordings before the fits are given
    fits = run_fits(result)
    begun = in_dir(result, out / "begun")
    with rendering.SecondDrawer(begun) as drawer:
        first = [out / "begun" / "figures" / name
                 for name in ("fig1_sky.png", "fig2_total_errors.png")]
        deadline = time.monotonic() + 60.0
        while not all(p.exists() for p in first) and time.monotonic() < deadline:
            time.sleep(0.05)
        before_fits = all(p.exists() for p in first)
        options = {"truth_arcsec": None, **rendering.recording_figure_options(begun)}
        drawn = drawer.run_figures(begun.rows, fits, out / "begun" / "figures", **options)
    reference = figures.run_figures(result.rows, fits, out / "reference", **options)
    found["begun"] = {"before_fits": before_fits,
                      "bytes": file_bytes(drawn) == file_bytes(reference),
                      "order": [f.path.name for f in drawn] == [f.path.name for f in reference]}

    # other figures than those begun: refused (a programming error, not a silent redraw)
    with rendering.SecondDrawer(in_dir(result, out / "other")) as drawer:
        try:
            drawer.run_figures(result.rows, fits, out / "other" / "figures",
                               **{**options, "name": "another name"})
            found["other"] = None
        except RuntimeError as err:
            found["other"] = str(err)

    # both processes draw, each figure once: each leaves the pid of its drawer beside it
    original = {name: getattr(figures, name) for name in rendering._COST}
    for name, func in original.items():
        setattr(figures, name, pid_tagging(func))
    try:
        with rendering.SecondDrawer(in_dir(result, out / "pids")) as drawer:
            drawn = drawer.run_figures(result.rows, fits, out / "pids" / "figures", **options)
    finally:
        for name, func in original.items():
            setattr(figures, name, func)
    found["drawers"] = {
        "n_files": len({str(f.path) for f in drawn}),
        "pids": sorted({f.path.with_suffix(".pid").read_text() for f in drawn}),
        "this_pid": str(os.getpid()),
        "bytes": file_bytes(drawn) == file_bytes(reference),
    }

    # the second drawer killed: an error naming it, and no process left
    with rendering.SecondDrawer(in_dir(result, out / "dead_drawer")) as drawer:
        os.kill(drawer.pid, signal.SIGKILL)
        try:
            drawer.run_figures(result.rows, fits, out / "dead_drawer" / "figures", **options)
            found["dead_drawer"] = None
        except RuntimeError as err:
            found["dead_drawer"] = str(err)

    # outputs the process cannot write (the directory is a file): it answers with the error,
    # this process warns and writes them itself, which raises the same error here
    blocked = out / "blocked"
    blocked.write_text("not a directory")
    process = rendering.OutputProcess.start()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            process.write_outputs(replace(result, out_dir=blocked))
            raised = None
        except OSError as err:
            raised = type(err).__name__
    found["failing"] = {"raised": raised, "warnings": [str(w.message) for w in caught],
                        "alive": process._process.is_alive()}

    # a process killed before it answers: the outputs are written here, the same files
    process = rendering.OutputProcess.start()
    os.kill(process._process.pid, signal.SIGKILL)
    process._process.join()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        process.write_outputs(in_dir(result, out / "killed"))
    found["killed"] = {"bytes": tree_bytes(out / "killed") == tree_bytes(out / "here"),
                       "warnings": [str(w.message) for w in caught]}

    # the command killed (SIGKILL) or interrupted (Ctrl-C reaches its whole process group):
    # its output process ends too, and says nothing
    found["orphans"] = {name: command_ends(sig) for name, sig in
                        (("killed", signal.SIGKILL), ("interrupted", signal.SIGINT))}

    # Ctrl-C while both processes draw: the second drawer goes with the output process
    found["interrupted_drawing"] = interrupted_while_drawing(scenario, out / "interrupted")

    # with another thread running there is no process
    stop = threading.Event()
    other = threading.Thread(target=stop.wait)
    other.start()
    try:
        found["with_thread"] = rendering.OutputProcess.start() is None
    finally:
        stop.set()
        other.join()
    found["after_thread"] = rendering.rendering_available()
    print(json.dumps(found))


if __name__ == "__main__":
    main()

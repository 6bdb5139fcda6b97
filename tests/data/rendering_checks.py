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
from pathlib import Path

from antsim import figures, rendering
from antsim.outputs import run_fits
from antsim.runner import simulate
from antsim.scenario import load_scenario

OPTIONS = {"name": "short", "el_limit_deg": 10.0, "reference_rms": figures.REPORT_TABLE2_ARCSEC}


def file_bytes(files) -> dict[str, str]:
    return {Path(f.path).name: Path(f.path).read_bytes().hex() for f in files}


COMMAND = """
import sys, time
from antsim import rendering
process = rendering.FigureProcess.start()
print(process._process.pid, flush=True)
try:
    time.sleep(120)
except KeyboardInterrupt:
    sys.exit(130)
"""


def ended(pid: int) -> bool:
    """Gone, or a zombie waiting for its (new) parent to reap it."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError, IndexError):
        return True
    return state == "Z"


def command_ends(sig: int) -> dict:
    """Start a command that holds a figure process, send it ``sig`` (SIGINT to its process
    group, as a terminal's Ctrl-C; SIGKILL to the command alone, as tests/test_campaign.py
    does), and say whether the figure process ended within 10 s and what was printed."""
    command = subprocess.Popen([sys.executable, "-c", COMMAND], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, start_new_session=True)
    pid = int(command.stdout.readline())
    time.sleep(0.5)  # the figure process is importing matplotlib now
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


def main() -> None:
    scenario, out = Path(sys.argv[1]), Path(sys.argv[2])
    result = simulate(load_scenario(scenario))
    fits = run_fits(result)
    rows = result.rows
    found: dict = {"available": rendering.rendering_available()}

    # the same files, titles and captions as drawn here, and no fallback warning
    here = figures.run_figures(rows, fits, out / "here", **OPTIONS)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        there = rendering.FigureProcess.start().run_figures(rows, fits, out / "there",
                                                            **OPTIONS)
    found["same"] = {
        "n": [len(here), len(there)],
        "bytes": file_bytes(here) == file_bytes(there),
        "titles": [f.title for f in here] == [f.title for f in there],
        "captions": [f.caption for f in here] == [f.caption for f in there],
        "folders": sorted({str(Path(f.path).parent) for f in there}),
        "warnings": [str(w.message) for w in caught],
    }

    # begun before the fits: the figures of the recordings alone are there before the
    # fits are sent, and the files are the same; begun with other options: drawn again
    process = rendering.FigureProcess.start()
    early = {"name": OPTIONS["name"], "el_limit_deg": OPTIONS["el_limit_deg"]}
    process.begin(rows, out / "begun", **early)
    first = [out / "begun" / "fig1_sky.png", out / "begun" / "fig2_total_errors.png"]
    deadline = time.monotonic() + 60.0
    while not all(p.exists() for p in first) and time.monotonic() < deadline:
        time.sleep(0.05)
    before_fits = all(p.exists() for p in first)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        begun = process.run_figures(rows, fits, out / "begun", **OPTIONS)
    process = rendering.FigureProcess.start()
    process.begin(rows, out / "other", **{**early, "name": "another name"})
    other = process.run_figures(rows, fits, out / "other", **OPTIONS)
    found["begun"] = {"before_fits": before_fits, "bytes": file_bytes(begun) == file_bytes(here),
                      "titles": [f.title for f in begun] == [f.title for f in here],
                      "other_bytes": file_bytes(other) == file_bytes(here),
                      "warnings": [str(w.message) for w in caught]}

    # both drawing processes draw: each figure leaves the pid of its drawer beside it
    jobs = figures.run_figure_jobs(rows, fits, out / "pids", **OPTIONS)

    def tagged(job):
        def call():
            drawn = job()
            drawn.path.with_suffix(".pid").write_text(str(os.getpid()))
            return drawn
        call.func = job.func  # the cost table is keyed by the figure function
        return call

    drawn = rendering.draw_in_two([tagged(j) for j in jobs])
    found["drawers"] = {
        "n_jobs": len(jobs), "n_files": len({str(f.path) for f in drawn}),
        "pids": sorted({f.path.with_suffix(".pid").read_text() for f in drawn}),
        "order": [f.path.name for f in drawn] == [Path(f.path).name for f in here],
    }

    # a request the process cannot draw: it answers with the error, this process warns and
    # draws the figures itself, which raises the same error here
    process = rendering.FigureProcess.start()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            process.run_figures(rows, fits, out / "failing", no_such_option=1)
            raised = None
        except TypeError as err:
            raised = f"TypeError: {err}"
    found["failing"] = {"raised": raised, "warnings": [str(w.message) for w in caught],
                        "alive": process._process.is_alive()}

    # a process killed before it answers: the figures are drawn here, the same files
    process = rendering.FigureProcess.start()
    os.kill(process._process.pid, signal.SIGKILL)
    process._process.join()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        files = process.run_figures(rows, fits, out / "killed", **OPTIONS)
    found["killed"] = {"bytes": file_bytes(files) == file_bytes(here),
                       "warnings": [str(w.message) for w in caught]}

    # the command killed (SIGKILL) or interrupted (Ctrl-C reaches its whole process group):
    # its figure process ends too, and says nothing
    found["orphans"] = {name: command_ends(sig) for name, sig in
                        (("killed", signal.SIGKILL), ("interrupted", signal.SIGINT))}

    # with another thread running there is no process
    stop = threading.Event()
    other = threading.Thread(target=stop.wait)
    other.start()
    try:
        found["with_thread"] = rendering.FigureProcess.start() is None
    finally:
        stop.set()
        other.join()
    found["after_thread"] = rendering.rendering_available()
    print(json.dumps(found))


if __name__ == "__main__":
    main()

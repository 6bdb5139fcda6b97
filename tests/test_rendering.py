"""A run's outputs written by a forked process (antsim.rendering): the same files, byte for
byte, as written in this process; the second drawer draws the figures of the recordings
before the fits and shares the rest (both processes draw, each figure once); a process that
fails or dies leaves the outputs to this process with a warning; a killed or interrupted
command leaves no process behind; no process while another thread runs.

The checks run in a fresh Python process (tests/data/rendering_checks.py): a fork copies
only the calling thread, and this one may have threads left by earlier tests, so the module
would rightly refuse to fork here. The run is the 1990 scenario cut to 3 hours (conftest's
``short_ghigo_text``).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from antsim import rendering

ROOT = Path(__file__).resolve().parents[1]
CHECKS = Path(__file__).parent / "data" / "rendering_checks.py"

pytestmark = pytest.mark.skipif(
    (os.cpu_count() or 1) < 2 or not sys.platform.startswith("linux"),
    reason="not Linux, or one core: figures are drawn in-process")


@pytest.fixture(scope="module")
def found(short_ghigo_text, tmp_path_factory) -> dict:
    scenario = tmp_path_factory.mktemp("scenario") / "short.toml"
    scenario.write_text(short_ghigo_text, encoding="utf-8")
    out = tmp_path_factory.mktemp("rendering")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])])}
    done = subprocess.run([sys.executable, str(CHECKS), str(scenario), str(out)], env=env,
                          capture_output=True, text=True, timeout=600, check=False)
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_a_fresh_process_may_fork(found):
    assert found["available"] is True


def test_the_process_writes_the_same_files_as_this_one(found):
    """Fits, tables, model, gain curve, figures and report: byte-identical (the fits made in
    the forked process are the same numbers), and the same summary line."""
    same = found["same"]
    assert {"fit.json", "fit_variants.json", "fit.txt", "model.dat", "report.html",
            "figures/fig1_sky.png", "figures/fig10_fit_rms.png"} <= set(same["files"])
    assert same["bytes"] and same["summary"]
    assert same["warnings"] == []  # written there, not by the fallback here


def test_the_figures_of_the_recordings_are_drawn_before_the_fits(found):
    begun = found["begun"]
    assert begun["before_fits"]
    assert begun["bytes"] and begun["order"]


def test_figures_other_than_those_begun_are_refused(found):
    assert found["other"] == "the figures asked for are not those of the run begun"


def test_both_processes_draw_each_figure_once(found):
    drawers = found["drawers"]
    assert drawers["n_files"] == 10
    assert len(drawers["pids"]) == 2 and drawers["this_pid"] in drawers["pids"]
    assert drawers["bytes"]


def test_a_dead_second_drawer_is_an_error(found):
    assert found["dead_drawer"] == "the second drawing process ended without an answer"


def test_a_failing_output_process_leaves_the_outputs_to_this_one(found):
    """The process answers with its error; this process warns and writes the outputs
    itself, which raises the same error where a user sees its traceback."""
    failing = found["failing"]
    assert failing["raised"] is not None
    assert len(failing["warnings"]) == 1
    assert failing["warnings"][0].startswith(
        "writing the outputs here: the output process failed: " + failing["raised"])
    assert failing["alive"] is False


def test_a_killed_output_process_leaves_the_outputs_to_this_one(found):
    killed = found["killed"]
    assert killed["bytes"]
    assert len(killed["warnings"]) == 1
    assert "ended without an answer" in killed["warnings"][0]


def test_the_output_process_ends_with_its_command(found):
    """Killed with SIGKILL (as tests/test_campaign.py does) or interrupted with Ctrl-C, the
    command leaves no output process behind, and the output process prints nothing."""
    for how, outcome in found["orphans"].items():
        assert outcome["ended"], how
        assert outcome["stderr"] == "", (how, outcome["stderr"])


def test_an_interrupted_command_stops_both_drawing_processes(found):
    """Ctrl-C while the output process and its second drawer draw (a figure there takes a
    minute): the command ends with status 130 and no process of it is left 10 s later (the
    output process, stopped by the command, stops its drawer)."""
    outcome = found["interrupted_drawing"]
    assert outcome["drawing"]
    assert outcome["status"] == 130
    assert outcome["left"] == 0


def test_no_output_process_while_another_thread_runs(found):
    assert found["with_thread"] is True
    assert found["after_thread"] is True


def test_cost_table_names_real_figure_functions():
    """A renamed figure function would silently lose its place in the drawing order."""
    from antsim.figures import run as figures

    assert all(callable(getattr(figures, name, None)) for name in rendering._COST)

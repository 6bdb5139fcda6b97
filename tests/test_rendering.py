"""A run's figures drawn in forked processes (antsim.rendering): the same files, byte for
byte, as drawn in this process, also when the figures of the recordings are begun before
the fits; both drawing processes draw; a process that fails or dies
leaves the figures to this process with a warning; a killed or interrupted command leaves no
figure process behind; no process while another thread runs.

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


def test_forked_figures_are_the_same_files_as_in_process(found):
    same = found["same"]
    assert same["n"] == [10, 10]
    assert same["bytes"] and same["titles"] and same["captions"]
    assert len(same["folders"]) == 1 and same["folders"][0].endswith("there")
    assert same["warnings"] == []  # drawn there, not by the fallback here


def test_begun_figures_are_drawn_before_the_fits_and_kept(found):
    """The figures of the recordings alone are drawn as soon as the campaign ends; begun
    with other options they are drawn again (the files always match this process's)."""
    begun = found["begun"]
    assert begun["before_fits"]
    assert begun["bytes"] and begun["titles"] and begun["other_bytes"]
    assert begun["warnings"] == []


def test_both_processes_draw_each_figure_once_in_order(found):
    drawers = found["drawers"]
    assert drawers["n_jobs"] == drawers["n_files"] == 10
    assert len(drawers["pids"]) == 2
    assert drawers["order"]


def test_a_failing_figure_process_leaves_the_figures_to_this_one(found):
    """The process answers with its error; this process warns and draws the figures itself,
    which raises the same error where a user sees its traceback."""
    failing = found["failing"]
    assert failing["raised"] is not None and "no_such_option" in failing["raised"]
    assert len(failing["warnings"]) == 1
    assert failing["warnings"][0].startswith(
        "drawing the figures here: the figure process failed: TypeError")
    assert failing["alive"] is False


def test_a_killed_figure_process_leaves_the_figures_to_this_one(found):
    killed = found["killed"]
    assert killed["bytes"]
    assert len(killed["warnings"]) == 1
    assert "ended without an answer" in killed["warnings"][0]


def test_the_figure_process_ends_with_its_command(found):
    """Killed with SIGKILL (as tests/test_campaign.py does) or interrupted with Ctrl-C, the
    command leaves no figure process behind, and the figure process prints nothing."""
    for how, outcome in found["orphans"].items():
        assert outcome["ended"], how
        assert outcome["stderr"] == "", (how, outcome["stderr"])


def test_no_figure_process_while_another_thread_runs(found):
    assert found["with_thread"] is True
    assert found["after_thread"] is True


def test_cost_table_names_real_figure_functions():
    """A renamed figure function would silently lose its place in the drawing order."""
    from antsim import figures

    assert all(callable(getattr(figures, name, None)) for name in rendering._COST)

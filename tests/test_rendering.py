"""A run's figures drawn in forked processes (antsim.rendering): the same files, byte for
byte, as drawn in this process; a process that fails or dies leaves the figures to this
process with a warning; the two drawing processes each draw some of them.

The run is the 1990 scenario cut to 3 hours (conftest's ``short_ghigo_text``).
"""

from __future__ import annotations

import os
import signal
import warnings
from pathlib import Path

import pytest

from antsim import figures, rendering
from antsim.outputs import run_fits
from antsim.runner import simulate
from antsim.scenario import load_scenario

pytestmark = pytest.mark.skipif(not rendering.rendering_available(),
                                reason="no fork or one core: figures are drawn in-process")


@pytest.fixture(scope="module")
def short_run(short_ghigo_text, tmp_path_factory):
    path = tmp_path_factory.mktemp("scenario") / "short.toml"
    path.write_text(short_ghigo_text, encoding="utf-8")
    result = simulate(load_scenario(path))
    return result, run_fits(result)


def _options() -> dict:
    return {"name": "short", "el_limit_deg": 10.0,
            "reference_rms": figures.REPORT_TABLE2_ARCSEC}


def _bytes(files) -> dict[str, bytes]:
    return {Path(f.path).name: Path(f.path).read_bytes() for f in files}


def test_forked_figures_are_the_same_files_as_in_process(short_run, tmp_path):
    result, fits = short_run
    here = figures.run_figures(result.rows, fits, tmp_path / "here", **_options())
    process = rendering.FigureProcess.start()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # drawn there, not by the fallback here
        there = process.run_figures(result.rows, fits, tmp_path / "there", **_options())
    assert [f.title for f in there] == [f.title for f in here]
    assert [f.caption for f in there] == [f.caption for f in here]
    assert [Path(f.path).parent for f in there] == [tmp_path / "there"] * len(there)
    assert _bytes(there) == _bytes(here)
    assert len(here) == 10


def test_both_processes_draw(short_run, tmp_path):
    """Each of the two processes draws at least one figure (the work is shared)."""
    result, fits = short_run
    jobs = figures.run_figure_jobs(result.rows, fits, tmp_path, **_options())

    def tagged(job):
        def call():
            out = job()
            (tmp_path / f"{out.path.stem}.pid").write_text(str(os.getpid()))
            return out
        call.func = job.func  # the cost table is keyed by the figure function
        return call

    files = rendering.draw_in_two([tagged(j) for j in jobs])
    drawers = {(tmp_path / f"{f.path.stem}.pid").read_text() for f in files}
    assert len(files) == len(jobs) == len({f.path for f in files})
    assert len(drawers) == 2, drawers


def test_a_failing_figure_process_leaves_the_figures_to_this_one(short_run, tmp_path):
    """The process answers with its error; this process warns and draws the figures itself,
    which here raises the same error where a user sees its traceback."""
    result, fits = short_run
    process = rendering.FigureProcess.start()
    with pytest.warns(RuntimeWarning, match="drawing the figures here: the figure process "
                                            "failed: TypeError"), pytest.raises(TypeError):
        process.run_figures(result.rows, fits, tmp_path, no_such_option=1)
    assert not process._process.is_alive()


def test_a_killed_figure_process_leaves_the_figures_to_this_one(short_run, tmp_path):
    result, fits = short_run
    process = rendering.FigureProcess.start()
    os.kill(process._process.pid, signal.SIGKILL)
    process._process.join()
    with pytest.warns(RuntimeWarning, match="drawing the figures here"):
        files = process.run_figures(result.rows, fits, tmp_path, **_options())
    assert _bytes(files) == _bytes(figures.run_figures(result.rows, fits, tmp_path / "ref",
                                                       **_options()))

"""antsim/run/report.py: the report of a run with a model in use (the closed loop, or the
model a scenario names) shows how that model pointed: a figure of the errors with it
against the errors without it, whose numbers are those of the run's own summary line."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from antsim.cli import main
from tests.antsim.run.test_report_page import read_page

REPO = Path(__file__).resolve().parents[3]
BASE = REPO / "tests" / "data" / "bad_inputs" / "scenario" / "_base.toml"
#: a model of the base scenario's two largest terms (TPOINT names the report's W6 = 734" IA,
#: its W1 = -113" -IE): it takes out part of the error, and the figure must say how much
MODEL = """closed-loop test model
T  44  5.460  0.0000  0.0000
  IA       +734.4000     1.00000
  IE       +112.8000     1.00000
END
"""


@pytest.fixture(scope="module")
def closed_loop(tmp_path_factory) -> tuple[Path, str]:
    tmp = tmp_path_factory.mktemp("closed_loop")
    (tmp / "model.dat").write_text(MODEL, encoding="utf-8")
    import contextlib
    import io

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(["run", str(BASE), "--out", str(tmp / "run"), "--model",
                     str(tmp / "model.dat"), "--no-progress"]) == 0
    return tmp / "run", out.getvalue()


def test_the_closed_loop_report_shows_the_errors_with_and_without_the_model(closed_loop):
    run, _ = closed_loop
    page = read_page(run / "report.html")
    caption = page.captions["fig_model_in_use.png"]
    with_it, without = map(float, re.search(r'Sky rms ([\d.]+)" with it, ([\d.]+)" without',
                                            caption).groups())
    # with it: fit.txt's line on the model in use; without it: the recordings' total errors
    assert f"model in use (closed-loop test model): Sky RMS {with_it:.1f}\"" in \
        (run / "fit.txt").read_text(encoding="utf-8")
    from astropy.table import Table

    rows = Table.read(run / "recordings.ecsv", format="ascii.ecsv")
    rows = rows[(rows["polarization"] == "AVG") & rows["good"]]
    total = [60.0 * (rows[f"{a}_arcmin"] + rows[f"model_{a}_arcmin"]
                     + rows[f"applied_{a}_arcmin"]) for a in ("xel", "el")]
    assert without == pytest.approx(float(np.sqrt(np.mean(total[0]**2 + total[1]**2))),
                                    abs=0.05)
    assert with_it < without
    figures = list(page.captions)
    assert figures.index("fig_model_in_use.png") == figures.index("fig2_total_errors.png") + 1


def test_a_run_without_a_model_has_no_such_figure(tmp_path):
    assert main(["run", str(BASE), "--out", str(tmp_path / "run"), "--model", "none",
                 "--no-progress"]) == 0
    assert not (tmp_path / "run" / "figures" / "fig_model_in_use.png").exists()
    assert "fig_model_in_use.png" not in read_page(tmp_path / "run" / "report.html").captions

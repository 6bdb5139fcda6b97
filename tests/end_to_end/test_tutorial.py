"""docs/tutorial.ipynb, the lesson built on the Python API, run from top to bottom in a
Jupyter kernel as a reader runs it: every cell without an error, every figure shown in the
notebook (an ``image/png`` output), the lesson's numbers what the text says, in well under a
minute. The notebook is kept without outputs; this test fails when outputs are saved in it.

It needs ``nbclient``, ``nbformat`` and ``ipykernel`` (the test extra) and a Python kernel:
without them it skips, saying which is missing."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
NOTEBOOK = REPO / "docs" / "tutorial.ipynb"
#: the whole notebook's limit (s): it takes about 15 s on two cores; the limit is the
#: brief's "well under a minute" plus the kernel's start on a loaded machine
LIMIT_S = 90


def _kernel() -> str:
    """The name of a Python kernel, or skip saying what is missing."""
    for module in ("nbclient", "nbformat", "ipykernel"):
        pytest.importorskip(module, reason=f"the tutorial runs with {module} (pip install "
                            "-e '.[test]')")
    from jupyter_client.kernelspec import KernelSpecManager

    specs = KernelSpecManager().find_kernel_specs()
    if "python3" not in specs:
        pytest.skip("no Jupyter kernel 'python3' (python -m ipykernel install --user)")
    return "python3"


def test_the_notebook_is_kept_without_outputs():
    import json

    cells = json.loads(NOTEBOOK.read_text(encoding="utf-8"))["cells"]
    code = [c for c in cells if c["cell_type"] == "code"]
    assert code and all(not c["outputs"] and c["execution_count"] is None for c in code)


def test_the_tutorial_runs_with_its_figures_inline(tmp_path, monkeypatch):
    kernel = _kernel()
    import nbformat
    from nbclient import NotebookClient

    monkeypatch.setenv("ANTSIM_CACHE", str(tmp_path / "cache"))  # the kernel inherits it
    notebook = nbformat.read(NOTEBOOK, as_version=4)
    t0 = time.perf_counter()
    NotebookClient(notebook, timeout=LIMIT_S, kernel_name=kernel,
                   resources={"metadata": {"path": str(tmp_path)}}).execute()
    assert time.perf_counter() - t0 < LIMIT_S
    shown = {}
    for cell in notebook.cells:
        if cell.cell_type == "code":
            kinds = {k for out in cell.outputs for k in out.get("data", {})}
            text = "".join(out.get("text", "") for out in cell.outputs)
            shown[cell.source.strip().splitlines()[-1]] = (kinds, text)
    plots = [line for line in shown if ".plot" in line]
    assert len(plots) >= 6
    for line in plots:
        assert "image/png" in shown[line][0], line
    for table in ("first", "first.fit", "found"):
        assert "text/html" in shown[table][0], table
    # what the text says of the numbers: W5 within 3 honest sigma of the recoverable truth
    # (the refraction counted in it; measured +0.2) and beyond 3 of the mount's terms alone
    # (measured +8.2), the loop closed within 20% of the fit's Sky RMS, the hidden fault
    # named (seeded: fixed numbers; the bounds are the lesson's words)
    pulls = shown[next(line for line in shown if "honest sigma" in line)][1]
    assert abs(float(pulls.split("truth, with the honest sigma: ")[1].split()[0])) < 3.0
    assert float(pulls.split("alone, with the honest sigma: ")[1].split()[0]) > 3.0
    loop = shown["print(second.in_use.line())"][1]
    assert 0.8 < float(loop.split(" times the ")[0].split(", ")[-1]) < 1.2
    found = notebook.cells[[c.source.strip() for c in notebook.cells].index(
        "found = antsim.diagnose_model(third, scenario=scenario)\nfound")].outputs
    assert "az_track_2a" in found[0]["data"]["text/plain"]

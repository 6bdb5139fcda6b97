"""`antsim fit` on inputs at the edge: a model file the disk cannot take, a run at one
position, and options that would silently mean something else."""

from __future__ import annotations

import errno
import os
import warnings
from pathlib import Path

import pytest

from antsim.cli import main

DATA = Path(__file__).resolve().parents[2] / "data" / "bad_inputs"
ECSV = str(DATA / "ecsv" / "_base.ecsv")


def test_a_full_disk_under_write_model_names_the_file_and_leaves_none(tmp_path, monkeypatch,
                                                                       capsys):
    """The model is written to a temporary file, flushed, then renamed: the disk filling up
    (the flush refused with ENOSPC) is one line naming the model file; no 0-byte model file
    is left behind, and the fit printed nothing."""
    target = tmp_path / "model.mod"

    def full(fd):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(os, "fsync", full)
    assert main(["fit", ECSV, "--write-model", str(target), "--no-progress"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith(f"antsim fit: error: {target}: file = ")
    assert "No space left on device" in captured.err and len(captured.err.splitlines()) == 1
    assert list(tmp_path.iterdir()) == []
    monkeypatch.undo()
    assert main(["fit", ECSV, "--write-model", str(target), "--no-progress"]) == 0
    assert target.read_text(encoding="utf-8").startswith("_base.ecsv: antsim fit")


def test_twenty_observations_at_one_position_fit_without_python_warnings(tmp_path, capsys):
    """All at one place on the sky: IA and IE are fitted and every other term is said to be
    undetermined, in the summary's lines; nothing else is printed (the jackknife's 0 x inf
    warned twice before)."""
    path = tmp_path / "one.csv"
    rows = [f"1990-02-08T17:{i:02d}:00,52.31,20.14,-12.5,88.0" for i in range(20)]
    path.write_text("# sign: indicated-minus-true\ntime,az_deg,el_deg,d_xel_arcsec,"
                    "d_el_arcsec\n" + "\n".join(rows) + "\n", encoding="utf-8")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert main(["fit", str(path), "--no-progress"]) == 0
    captured = capsys.readouterr()
    assert captured.err == ""
    assert "NPAE cannot be determined from these data" in captured.out


@pytest.mark.parametrize("model", ["", "   "])
def test_an_empty_model_is_not_the_default_model(model, capsys):
    assert main(["fit", ECSV, "--model", model, "--no-progress"]) == 2
    assert "--model" in capsys.readouterr().err

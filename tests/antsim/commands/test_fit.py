"""antsim/commands/fit.py. One honest sigma per fit: ``antsim fit`` of a run's recordings
gives the honest sigma the run's fit.json gives (observations within 3600 s time blocks,
the data having times), a file without times gets single-observation clusters, and every
output names the clusters it used (docs/outputs.md, "The honest sigma"). Inputs at the
edge: a model file the disk cannot take, a run at one position, and options that would
silently mean something else."""

from __future__ import annotations

import dataclasses
import errno
import json
import os
import warnings
from pathlib import Path

import pytest

from antsim.cli import main

REPO = Path(__file__).resolve().parents[3]
CSV = REPO / "tests" / "data" / "bad_inputs" / "csv" / "_base.csv"
ECSV = str(REPO / "tests" / "data" / "bad_inputs" / "ecsv" / "_base.ecsv")
BLOCKS = "clusters = observations within 3600 s time blocks"
SINGLE = "clusters = single observations (the data have no times)"


@pytest.fixture(scope="module")
def run(tmp_path_factory) -> Path:
    """``antsim run ghigo1990`` (the 24-hour run, its own seed), without the report."""
    out = tmp_path_factory.mktemp("fit") / "ghigo1990"
    assert main(["run", "ghigo1990", "--out", str(out), "--no-report", "--no-progress"]) == 0
    return out


def test_antsim_fit_of_a_runs_recordings_gives_the_runs_honest_sigma(run, capsys):
    capsys.readouterr()
    assert main(["fit", str(run / "recordings.ecsv"), "--json", "--no-progress"]) == 0
    fitted = json.loads(capsys.readouterr().out)
    saved = json.loads((run / "fit.json").read_text(encoding="utf-8"))
    assert fitted["honest_sigma"] == saved["honest_sigma"]
    assert BLOCKS in saved["honest_sigma"]["method"]
    for term, values in saved["terms"].items():
        assert fitted["terms"][term] == pytest.approx(values, rel=1e-12), term
    assert main(["fit", str(run / "recordings.ecsv"), "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert f"honest sigma: cluster jackknife (CV3) of the same least-squares coefficients, " \
           f"{BLOCKS}" in text
    assert f"; {saved['honest_sigma']['clusters']} clusters" in text
    # fit.txt, the run's tables, names the same clusters beside its column
    assert "the honest one (jackknife over observations within 3600 s time blocks)" in \
        (run / "fit.txt").read_text(encoding="utf-8")


def test_ignoring_the_times_makes_every_honest_sigma_smaller(run):
    """docs/outputs.md: on the 1990 recordings single-observation clusters give every term a
    smaller honest sigma, W7's by about 40% (seeded run: the ratios are fixed numbers; the
    bounds say "about")."""
    from controller.pointing.fitting import fit_model
    from controller.pointing.variants import VARIANTS, columns, pointing_data, variant_mask
    from controller.program.recordings import read_recordings

    cols = columns(read_recordings(run / "recordings.ecsv"))
    data = pointing_data(cols, variant_mask(cols, VARIANTS[0]))
    blocks = fit_model(data, "ghigo10")
    single = fit_model(dataclasses.replace(data, t_s=None), "ghigo10")
    assert SINGLE in single.honest_method() and BLOCKS in blocks.honest_method()
    ratio = single.sigma_honest_arcsec / blocks.sigma_honest_arcsec
    assert (ratio < 1).all(), dict(zip(blocks.names, ratio, strict=True))
    assert 0.5 < ratio[blocks.names.index("W7")] < 0.7


def test_a_tpoint_file_has_no_times_and_says_so(capsys):
    assert main(["fit", str(REPO / "examples" / "mmt_20210821_k_and_e.dat"),
                 "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert f"honest sigma: cluster jackknife (CV3) of the same least-squares coefficients, " \
           f"{SINGLE}" in text
    assert "honest sigma blank" not in text


def test_a_csv_with_times_gets_time_blocks_and_too_few_are_named(tmp_path, capsys):
    """The one-hour CSV spans two blocks: too few for an error bar, and the output says so;
    the same file without its time column falls back to single observations."""
    assert main(["fit", str(CSV), "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert BLOCKS in text and "; 2 clusters" in text
    assert "honest sigma blank for IA, IE, NPAE, CA, AN, AW, TF, TX: 2 clusters are too few " \
           "to estimate it" in text
    lines = CSV.read_text(encoding="utf-8").splitlines()
    timeless = tmp_path / "timeless.csv"
    timeless.write_text("\n".join(line if line.startswith("#") else line.split(",", 1)[1]
                                  for line in lines) + "\n", encoding="utf-8")
    assert main(["fit", str(timeless), "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert SINGLE in text and "honest sigma blank" not in text


def test_the_help_states_the_rule(capsys):
    with pytest.raises(SystemExit):
        main(["fit", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    assert "observations within 3600 s time blocks, as in a run's fit.json and report" \
        in help_text
    assert "they are single observations" in help_text


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

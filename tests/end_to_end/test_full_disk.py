"""A full disk while a command writes its outputs: one line naming the file being written,
exit status 2, and every file written before it kept as it was (none torn).

The disk fills for one output: its writes go to ``/dev/full``, whose every write fails with
the kernel's own ENOSPC, whether antsim writes it (:func:`antsim.outdir.write_file`, through
``os.open``) or a library does (``Path.write_text``, through ``io.open``). Before, the line
read "system: No space left on device" and named no file.
"""

from __future__ import annotations

import io
import os
from pathlib import Path

import pytest

from antsim.cli import main

REPO = Path(__file__).resolve().parents[2]
BASE = REPO / "tests" / "data" / "bad_inputs" / "scenario" / "_base.toml"
RECORDINGS = REPO / "tests" / "data" / "bad_inputs" / "ecsv" / "_base.ecsv"
FULL = Path("/dev/full")

pytestmark = pytest.mark.skipif(not FULL.exists(), reason="no /dev/full (Linux's device "
                                                          "whose writes fail with ENOSPC)")


def fill_disk_at(monkeypatch, name: str) -> None:
    """Writes of the file ``name`` (or of its temporary ``.NAME.tmp``) go to /dev/full."""
    real_os_open, real_io_open = os.open, io.open

    def targeted(path) -> bool:
        return Path(os.fspath(path)).name in (name, f".{name}.tmp")

    def os_open(path, flags, *args, **kwargs):
        if targeted(path) and flags & (os.O_WRONLY | os.O_RDWR):
            return real_os_open(FULL, os.O_WRONLY)
        return real_os_open(path, flags, *args, **kwargs)

    def io_open(file, mode="r", *args, **kwargs):
        if isinstance(file, str | os.PathLike) and targeted(file) and "w" in mode:
            return real_io_open(FULL, mode, *args, **kwargs)
        return real_io_open(file, mode, *args, **kwargs)

    monkeypatch.setattr(os, "open", os_open)
    monkeypatch.setattr(io, "open", io_open)


def _files(path: Path) -> dict[str, bytes]:
    return {str(p.relative_to(path)): p.read_bytes() for p in sorted(path.rglob("*"))
            if p.is_file() and p.name != ".antsim.lock"}


@pytest.fixture(scope="module")
def clean_run(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("clean") / "run"
    assert main(["run", str(BASE), "--out", str(out), "--no-progress"]) == 0
    return out


@pytest.mark.parametrize("name", ["report.html", "fig3_residuals.png", "fit.json",
                                  "gaincurve.json", "truth.json"])
def test_a_full_disk_in_run_names_the_file_and_keeps_what_was_written(
        name, clean_run, tmp_path, monkeypatch, capsys):
    out = tmp_path / "run"
    fill_disk_at(monkeypatch, name)
    assert main(["run", str(BASE), "--out", str(out), "--no-progress"]) == 2
    monkeypatch.undo()
    captured = capsys.readouterr()
    target = out / "figures" / name if name.endswith(".png") else out / name
    assert captured.err.splitlines() == [
        f"antsim run: error: {target}: No space left on device [ENOSPC]; files written "
        "before it are kept"]
    written = _files(out)
    assert name not in {Path(k).name for k in written}  # no torn file
    assert not any(Path(k).name.startswith(".") for k in written)  # no temporary one
    reference = _files(clean_run)
    assert "recordings.ecsv" in written
    for key, data in written.items():
        assert data == reference[key], key  # what was written is the clean run's


@pytest.mark.parametrize("name", ["diagnose.json", "report.html", "diagnose_residuals.png"])
def test_a_full_disk_in_diagnose_names_the_file(name, tmp_path, monkeypatch, capsys):
    out = tmp_path / "diagnose"
    fill_disk_at(monkeypatch, name)
    assert main(["diagnose", str(RECORDINGS), "--out", str(out), "--no-progress",
                 "--no-cache"]) == 2
    monkeypatch.undo()
    captured = capsys.readouterr()
    assert captured.err.splitlines() == [
        f"antsim diagnose: error: {out / name}: No space left on device [ENOSPC]; files "
        "written before it are kept"]
    assert (out / "model_updated.dat").stat().st_size > 0  # written before: kept


def test_a_full_disk_when_serve_writes_the_truth_names_it(tmp_path, monkeypatch, capsys):
    out = tmp_path / "served"
    fill_disk_at(monkeypatch, "truth.json")
    assert main(["serve", str(BASE), "--port", "0", "--out", str(out)]) == 2
    monkeypatch.undo()
    err = [line for line in capsys.readouterr().err.splitlines() if "error" in line]
    assert err == [f"antsim serve: error: {out / 'truth.json'}: No space left on device "
                   "[ENOSPC]; files written before it are kept"]
    # neither output: the next session into the directory is not refused
    assert not (out / "truth.json").exists() and not (out / "requests.jsonl").exists()


def test_a_full_disk_keeps_an_earlier_file_whole(tmp_path, monkeypatch):
    """A file written again (a resumed run's truth.json) on a full disk: the earlier one
    stays, whole."""
    from antsim.outdir import write_file

    path = tmp_path / "truth.json"
    path.write_text('{"seed": 3}\n', encoding="utf-8")
    fill_disk_at(monkeypatch, "truth.json")
    with pytest.raises(OSError) as failed:
        write_file(path, '{"seed": 4}\n' * 1000)
    monkeypatch.undo()
    assert failed.value.filename == str(path) and failed.value.strerror
    assert path.read_text(encoding="utf-8") == '{"seed": 3}\n'
    assert sorted(p.name for p in tmp_path.iterdir()) == ["truth.json"]

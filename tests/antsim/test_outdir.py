"""antsim/outdir.py: an output directory is held while a command runs and left clean after it:
the lock file removed however the command ends, a directory the command created and left
empty removed, and the lock's protection kept while the file comes and goes."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

from antsim.cli import main
from antsim.outdir import LOCK_NAME, DirectoryLock, held_output_dir
from controller.errors import InputError

REPO = Path(__file__).resolve().parents[2]
BASE = REPO / "tests" / "data" / "bad_inputs" / "scenario" / "_base.toml"
flock_only = pytest.mark.skipif(sys.platform == "win32", reason="flock")


def test_the_lock_file_is_there_while_held_and_gone_after(tmp_path):
    with DirectoryLock(tmp_path, command="test"):
        assert (tmp_path / LOCK_NAME).read_text().startswith(f"{os.getpid()}\t")
    assert not (tmp_path / LOCK_NAME).exists()
    with pytest.raises(RuntimeError), DirectoryLock(tmp_path, command="test"):
        raise RuntimeError("the command failed")
    assert not (tmp_path / LOCK_NAME).exists()


@flock_only
def test_a_held_directory_is_refused_and_its_lock_kept(tmp_path):
    with DirectoryLock(tmp_path, command="first"):
        with pytest.raises(InputError, match=r"in use by another antsim process \(pid \d+: "
                                             r"first\)"):
            DirectoryLock(tmp_path, command="second").__enter__()
        # the refused one removed nothing: the holder's file is still there
        assert (tmp_path / LOCK_NAME).read_text().endswith("\tfirst\n")


@flock_only
def test_a_lock_taken_on_a_file_removed_meanwhile_is_taken_again(tmp_path, monkeypatch):
    """The holder removes its file while a second process has it open but not yet locked:
    the second must not hold the removed file (a third would then take a new one and both
    would write): it opens the new file and holds that."""
    first = DirectoryLock(tmp_path, command="first").__enter__()
    real_open = os.open
    calls = []

    def open_then_first_ends(path, flags, *args):
        fd = real_open(path, flags, *args)
        calls.append(fd)
        if len(calls) == 1:  # between this open and the flock, the first holder ends
            first.__exit__(None, None, None)
        return fd

    monkeypatch.setattr(os, "open", open_then_first_ends)
    second = DirectoryLock(tmp_path, command="second").__enter__()
    monkeypatch.setattr(os, "open", real_open)
    try:
        assert len(calls) == 2  # the removed file, then the new one
        assert (tmp_path / LOCK_NAME).read_text().endswith("\tsecond\n")
        with pytest.raises(InputError, match="second"):
            DirectoryLock(tmp_path, command="third").__enter__()
    finally:
        second.__exit__(None, None, None)
    assert not (tmp_path / LOCK_NAME).exists()


def test_directories_a_failed_command_created_are_removed_when_empty(tmp_path):
    (tmp_path / "kept").mkdir()
    out = tmp_path / "kept" / "new" / "deeper"
    with pytest.raises(RuntimeError), held_output_dir(out) as held:
        assert held == out and (out / LOCK_NAME).exists()
        raise RuntimeError("the command failed")
    assert not (tmp_path / "kept" / "new").exists()
    assert (tmp_path / "kept").is_dir()  # it was there before


def test_a_directory_with_files_in_it_stays_without_the_lock(tmp_path):
    out = tmp_path / "new" / "run"
    with pytest.raises(RuntimeError), held_output_dir(out):
        (out / "recordings.ecsv").write_text("recorded\n")
        raise RuntimeError("the command failed after recording")
    assert (out / "recordings.ecsv").read_text() == "recorded\n"
    assert sorted(p.name for p in out.iterdir()) == ["recordings.ecsv"]


def test_an_existing_empty_directory_is_left_in_place(tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    with pytest.raises(RuntimeError), held_output_dir(out):
        raise RuntimeError("the command failed")
    assert out.is_dir() and not any(out.iterdir())


def test_a_run_leaves_no_lock_and_a_failed_run_no_directory(tmp_path, monkeypatch, capsys):
    out = tmp_path / "run"
    assert main(["run", str(BASE), "--out", str(out), "--no-report", "--no-progress"]) == 0
    assert (out / "recordings.ecsv").is_file() and not (out / LOCK_NAME).exists()
    # refused inside the lock (the directory holds a run): nothing removed, no lock left
    capsys.readouterr()
    assert main(["run", str(BASE), "--out", str(out), "--no-progress"]) == 2
    assert "already holds" in capsys.readouterr().err
    assert (out / "recordings.ecsv").is_file() and not (out / LOCK_NAME).exists()

    from antsim.simulate import runner

    def broken(*args, **kwargs):
        raise RuntimeError("the simulation broke before its first scan (test)")

    monkeypatch.setattr(runner, "simulate", broken)
    failed = tmp_path / "failed" / "run"
    with pytest.raises(RuntimeError, match="before its first scan"):
        main(["run", str(BASE), "--out", str(failed), "--no-progress"])
    assert not (tmp_path / "failed").exists()

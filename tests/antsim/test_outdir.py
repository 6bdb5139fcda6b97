"""antsim/outdir.py: an output directory is held while a command runs and left clean after it:
the lock file removed however the command ends, a directory the command created and left
empty removed, and the lock's protection kept while the file comes and goes; output files
written whole or not at all and never through a link; the lock file never opened through a
link, nor as a FIFO or a directory."""

from __future__ import annotations

import errno
import os
import sys
import threading
from pathlib import Path

import pytest

from antsim.cli import main
from antsim.outdir import LOCK_NAME, DirectoryLock, held_output_dir, replacing, write_file
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


def test_write_file_writes_text_as_utf8(tmp_path):
    path = write_file(tmp_path / "fit.txt", "Ωmega 1\u2033\n")
    assert path.read_bytes() == "Ωmega 1\u2033\n".encode()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fit.txt"]


def test_a_link_at_the_name_is_replaced_never_written_through(tmp_path):
    victim = tmp_path / "victim"
    victim.write_text("keep me", encoding="utf-8")
    (tmp_path / "report.html").symlink_to(victim)
    write_file(tmp_path / "report.html", "<html>")
    assert victim.read_text(encoding="utf-8") == "keep me"
    assert not (tmp_path / "report.html").is_symlink()
    assert (tmp_path / "report.html").read_text(encoding="utf-8") == "<html>"


def test_a_link_at_the_temporary_name_is_not_followed(tmp_path):
    """A link planted where the temporary file goes: removed, its target untouched."""
    victim = tmp_path / "victim"
    victim.write_text("keep me", encoding="utf-8")
    (tmp_path / ".fit.json.tmp").symlink_to(victim)
    write_file(tmp_path / "fit.json", "{}\n")
    assert victim.read_text(encoding="utf-8") == "keep me"
    assert (tmp_path / "fit.json").read_text(encoding="utf-8") == "{}\n"
    assert not (tmp_path / ".fit.json.tmp").exists()


def test_a_failure_in_the_block_leaves_the_earlier_file(tmp_path):
    path = tmp_path / "fit.json"
    path.write_text("earlier", encoding="utf-8")
    with pytest.raises(RuntimeError), replacing(path) as fh:
        fh.write(b"half of it")
        raise RuntimeError("the writer failed")
    assert path.read_text(encoding="utf-8") == "earlier"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fit.json"]


def test_an_error_names_the_output_not_its_temporary_file(tmp_path):
    blocker = tmp_path / "a_file"
    blocker.write_text("", encoding="utf-8")
    with pytest.raises(NotADirectoryError) as failed:
        write_file(blocker / "fit.json", "{}")
    assert failed.value.filename == str(blocker / "fit.json")
    assert failed.value.errno == errno.ENOTDIR


@pytest.mark.parametrize(("kind", "says"), [
    ("symlink", "a symbolic link"), ("hardlink", "a hard link to another file"),
    ("fifo", "something other than a regular file"), ("directory", "a directory")])
def test_the_lock_file_is_never_written_through(tmp_path, kind, says):
    precious = tmp_path / "precious.txt"
    precious.write_text("precious\n", encoding="utf-8")
    lock = tmp_path / LOCK_NAME
    {"symlink": lambda: lock.symlink_to(precious), "hardlink": lambda: os.link(precious, lock),
     "fifo": lambda: os.mkfifo(lock), "directory": lock.mkdir}[kind]()
    result: list[BaseException | None] = []

    def enter() -> None:
        try:
            with DirectoryLock(tmp_path, command="test"):
                result.append(None)
        except InputError as err:
            result.append(err)

    worker = threading.Thread(target=enter, daemon=True)  # a FIFO must not block it
    worker.start()
    worker.join(10.0)
    assert not worker.is_alive(), "opening the lock file blocked"
    (err,) = result
    assert isinstance(err, InputError) and f"holds {LOCK_NAME} as {says}" in str(err)
    assert precious.read_text(encoding="utf-8") == "precious\n"


def test_a_lock_file_of_its_own_is_taken_and_kept(tmp_path):
    with DirectoryLock(tmp_path, command="antsim test"):
        assert (tmp_path / LOCK_NAME).read_text().endswith("\tantsim test\n")
    with DirectoryLock(tmp_path, command="again"):  # released: taken again
        pass

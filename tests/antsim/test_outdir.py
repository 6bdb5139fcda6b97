"""antsim.outdir: output files written whole or not at all and never through a link; the
lock file never opened through a link, nor as a FIFO or a directory."""

from __future__ import annotations

import errno
import os
import threading

import pytest

from antsim.outdir import LOCK_NAME, DirectoryLock, replacing, write_file
from controller.errors import InputError


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

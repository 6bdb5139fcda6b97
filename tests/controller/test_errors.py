"""Text files read bounded and written whole: /dev/zero refused at once, a file beyond the
bound refused, UTF-16 named, a full disk leaving no partial file and naming the file, an
error line's value bounded whatever it holds."""

from __future__ import annotations

import errno
import os
import time
from pathlib import Path

import pytest

from controller.errors import InputError, read_text_file, write_text_file


def test_a_device_that_never_ends_is_refused_at_once():
    start = time.perf_counter()
    with pytest.raises(InputError, match="is not text: it holds a NUL byte") as err:
        read_text_file("/dev/zero")
    assert time.perf_counter() - start < 1.0  # one chunk, not 1.7 GB
    assert err.value.where == "/dev/zero:1"


def test_a_file_beyond_the_bound_is_refused(tmp_path):
    path = tmp_path / "big.txt"
    path.write_text("x" * 5000, encoding="utf-8")
    assert read_text_file(path, limit=5000) == "x" * 5000
    with pytest.raises(InputError, match="is larger than"):
        read_text_file(path, limit=4999)


@pytest.mark.parametrize(("data", "encoding"), [
    ("a caption\n".encode("utf-16"), "UTF-16"),
    ("a caption\n".encode("utf-16-le"), "UTF-16"),
    ("a caption\n".encode("utf-32"), "UTF-32"),
])
def test_text_in_another_encoding_is_named(tmp_path, data, encoding):
    path = tmp_path / "f.dat"
    path.write_bytes(data)
    with pytest.raises(InputError, match=f"is {encoding} text: antsim reads UTF-8"):
        read_text_file(path)


def test_binary_and_nul_bytes_are_still_said_as_before(tmp_path):
    path = tmp_path / "f.dat"
    path.write_bytes(b"line one\nline two\x00\x00\x00\x00\x00\x00\x00\x00\x00")
    with pytest.raises(InputError, match="holds a NUL byte") as err:
        read_text_file(path)
    assert err.value.where.endswith("f.dat:2")


def test_a_full_disk_leaves_the_earlier_file_and_no_partial_one(tmp_path, monkeypatch):
    """The text goes to a temporary file flushed to the disk, then renamed: the disk filling
    up (simulated: the flush refused with ENOSPC) is one line naming the file, the earlier
    file is as it was, and nothing else is left in the folder."""
    path = tmp_path / "model.dat"
    path.write_text("the earlier model\n", encoding="utf-8")

    def full(fd):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(os, "fsync", full)
    with pytest.raises(InputError) as err:
        write_text_file(path, "a new model\n")
    line = err.value.line()
    assert line.startswith(f"{path}: file = ") and line.endswith(
        "cannot be written (No space left on device); nothing was written to it")
    assert path.read_text(encoding="utf-8") == "the earlier model\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["model.dat"]
    monkeypatch.undo()
    write_text_file(path, "a new model\n")
    assert path.read_text(encoding="utf-8") == "a new model\n"
    assert oct(path.stat().st_mode & 0o777) == oct(0o666 & ~_umask())


def test_a_symbolic_link_is_written_through_and_a_device_never_replaced(tmp_path):
    target = tmp_path / "real.mod"
    target.write_text("old\n", encoding="utf-8")
    link = tmp_path / "link.mod"
    link.symlink_to(target)
    write_text_file(link, "new\n")
    assert link.is_symlink() and target.read_text(encoding="utf-8") == "new\n"
    with pytest.raises(InputError, match="No space left on device"):
        write_text_file("/dev/full", "x\n")
    assert Path("/dev/full").is_char_device()


def test_an_error_line_shows_a_bounded_value_of_any_size():
    bomb: list = ["x"] * 9
    for _ in range(9):
        bomb = [bomb] * 9  # 9**10 leaves: its repr would be gigabytes
    start = time.perf_counter()
    line = InputError("f.ecsv", "meta.site", bomb, "must be a mapping").line()
    assert time.perf_counter() - start < 0.5
    assert len(line) < 120 and line.startswith("f.ecsv: meta.site = [[[[...")


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask

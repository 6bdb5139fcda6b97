"""Errors for bad user input: one line naming the file, the field and the value."""

from __future__ import annotations

import contextlib
import os
import reprlib
import tempfile
from os import PathLike, fspath
from typing import Any

__all__ = ["MAX_INPUT_BYTES", "InputError", "Note", "read_text_file", "write_text_file"]

#: the largest file a reader takes (bytes): 200,000 scans of recordings are 44 MB; anything
#: beyond this is not pointing data antsim reads (``/dev/zero`` would fill the memory)
MAX_INPUT_BYTES = 1 << 30

#: a container's repr, bounded: a YAML alias bomb is a list a few levels deep whose full
#: repr is gigabytes; the line shows a few items of a few levels, then "..."
_CONTAINER_REPR = reprlib.Repr()
_CONTAINER_REPR.maxlevel = 3
_CONTAINER_REPR.maxstring = _CONTAINER_REPR.maxother = 80


def _short(value: Any, limit: int = 60) -> str:
    if type(value).__module__ == "numpy" and hasattr(value, "item"):
        value = value.item()  # 3, not np.int64(3)
    if isinstance(value, list | tuple | dict | set | frozenset):
        text = _CONTAINER_REPR.repr(value)
    else:
        text = repr(value)
    text = " ".join(text.split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


class Note(UserWarning):
    """Something the user should know that is not an error (a damaged cache rebuilt, ...):
    a warning the command line prints as one line, ``antsim COMMAND: note: ...``."""


class InputError(ValueError):
    """Bad input from a file or the command line.

    ``str(err)`` is a single line ``"<where>: <field> = <value>: <problem>[; <hint>]"``
    that the command line prints before exiting with status 2.
    """

    def __init__(self, where: str, field: str, value: Any, problem: str, hint: str = ""):
        self.where = str(where)
        self.field = str(field)
        self.value = value
        self.problem = problem
        self.hint = hint
        # the parts, not the line, are the args: simpy and process pools rebuild an
        # exception as type(err)(*err.args)
        super().__init__(where, field, value, problem, hint)

    def __str__(self) -> str:
        return self.line()

    def line(self) -> str:
        text = f"{self.where}: {self.field} = {_short(self.value)}: {self.problem}"
        if self.hint:
            text += f"; {self.hint}"
        return " ".join(text.split())


def read_text_file(path: str | PathLike[str], what: str = "file",
                   limit: int = MAX_INPUT_BYTES) -> str:
    """The text of a UTF-8 file (a leading byte-order mark dropped), or one InputError line
    for a missing, unreadable, binary or larger than ``limit`` bytes file. It is read a
    chunk at a time, so that a device that never ends (``/dev/zero``) is refused at its
    first NUL byte, or at ``limit``, not when the memory is full."""
    name = fspath(path)
    if not name:
        raise InputError("command line", what, name, "is empty: give a file")
    try:
        with open(name, "rb") as fh:
            data = _read_bounded(fh, name, what, limit)
    except FileNotFoundError:
        raise InputError(name, what, name, "no such file") from None
    except IsADirectoryError:
        raise InputError(name, what, name, "is a directory, not a file") from None
    except OSError as err:
        raise InputError(name, what, name, f"cannot be read ({err.strerror or err})") from None
    return _decoded(data, name, what)


def _read_bounded(fh, name: str, what: str, limit: int) -> bytes:
    chunks: list[bytes] = []
    size = 0
    while True:
        chunk = fh.read(1 << 20)
        if not chunk:
            return b"".join(chunks)
        nul = chunk.find(b"\x00")
        if nul >= 0:  # binary: said at once (or what is wrong before it), with its line
            _other_encoding((b"".join(chunks) + chunk)[:64], name, what)
            _decoded(b"".join(chunks) + chunk[: nul + 1], name, what)
        size += len(chunk)
        if size > limit:
            raise InputError(name, what, name, f"is larger than {limit >> 20} MiB: not a "
                             "file of pointing data, a model or a scenario antsim reads")
        chunks.append(chunk)


#: byte-order marks of the encodings a text editor may save in instead of UTF-8
_OTHER_ENCODINGS = ((b"\xff\xfe\x00\x00", "UTF-32"), (b"\x00\x00\xfe\xff", "UTF-32"),
                    (b"\xff\xfe", "UTF-16"), (b"\xfe\xff", "UTF-16"))


def _other_encoding(head: bytes, name: str, what: str) -> None:
    """InputError for text in UTF-16 or UTF-32 (a byte-order mark, or a NUL byte after
    every character of the first line): text, but not UTF-8, not binary."""
    for mark, encoding in _OTHER_ENCODINGS:
        if head.startswith(mark) or (encoding == "UTF-16" and len(head) >= 8
                                     and head[1::2].count(0) == len(head) // 2
                                     and 0 not in head[0::2]):
            raise InputError(name, what, head[:8], f"is {encoding} text: antsim reads UTF-8",
                             f"convert it, e.g. iconv -f {encoding} -t UTF-8")


def _decoded(data: bytes, name: str, what: str) -> str:
    _other_encoding(data[:64], name, what)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as err:
        line = data.count(b"\n", 0, err.start) + 1
        raise InputError(f"{name}:{line}", what, data[err.start:err.start + 8],
                         f"is not UTF-8 text ({err.reason} at byte {err.start})") from None
    if "\x00" in text:
        line = text.count("\n", 0, text.index("\x00")) + 1
        raise InputError(f"{name}:{line}", what, "\\x00", "is not text: it holds a NUL byte")
    return text.removeprefix("\ufeff")


def write_text_file(path: str | PathLike[str], text: str, what: str = "file") -> None:
    """Write ``text`` (UTF-8) to ``path`` whole or not at all: into a temporary file in the
    same folder, flushed to the disk, then renamed over ``path``; a full disk or a refusal
    is one InputError line naming ``path``, and leaves no partial file and any earlier
    ``path`` as it was."""
    name = fspath(path)
    real = os.path.realpath(name)  # a symbolic link's target is written, as open() would
    if os.path.exists(real) and not os.path.isfile(real):  # a device, a pipe: written to
        try:
            with open(real, "wb") as fh:
                fh.write(text.encode("utf-8"))
        except OSError as err:
            raise InputError(name, what, name, f"cannot be written ({err.strerror or err})")\
                from None
        return
    folder = os.path.dirname(real) or "."
    tmp = None
    try:
        fd, tmp = tempfile.mkstemp(prefix=".", suffix=".tmp", dir=folder)
        with os.fdopen(fd, "wb") as fh:
            fh.write(text.encode("utf-8"))
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, 0o666 & ~_umask())  # as open() would have made it
        os.replace(tmp, real)
        tmp = None
    except OSError as err:
        raise InputError(name, what, name, f"cannot be written ({err.strerror or err})",
                         "nothing was written to it") from None
    finally:
        if tmp is not None:
            with contextlib.suppress(OSError):
                os.unlink(tmp)


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask

"""Output directories: checked with one-line errors, held by one process at a time, and
written file by file whole or not at all.

:func:`output_dir` turns an ``--out`` option into a directory that exists and can be written,
or one :class:`~controller.errors.InputError` line (an empty name, a path through a file, a
read-only file system, no permission). :class:`DirectoryLock` holds an exclusive lock on
``DIR/.antsim.lock`` while a command writes into ``DIR``: a second ``antsim`` process that
wants the same directory is refused with one line naming the first one's process id. The
lock is the operating system's (``fcntl.flock``): the kernel releases it when its holder
exits, however it exits, so a run killed with ``kill -9`` leaves no stale lock behind (the
file stays, unlocked, holding only the last holder's process id and command). A command that
ends (normally, with an error, or with Ctrl-C) removes the file; :func:`held_output_dir`
also removes the directories it created when the command left them empty. The lock file is
never written through a symbolic or hard link: such a lock file is refused in one line.

:func:`write_file` and :func:`replacing` write an output file through a temporary file
renamed into place: a full disk leaves the earlier file (or none) rather than a torn one,
the error names the file, and a symbolic link at the output's name is replaced, never
written through.

May import: :mod:`controller.errors` only.
"""

from __future__ import annotations

import errno
import os
import stat
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import BinaryIO

from controller.errors import InputError

__all__ = ["LOCK_NAME", "DirectoryLock", "held_output_dir", "output_dir", "replacing",
           "write_file"]

#: the lock file each locked output directory holds
LOCK_NAME = ".antsim.lock"
#: open flags: never through a symbolic link (0 where the system has no such flag: checked
#: before opening instead); never waiting on a FIFO put there
_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)
_NONBLOCK = getattr(os, "O_NONBLOCK", 0)


def named(err: OSError, path: str | os.PathLike) -> OSError:
    """``err`` as an OSError that names ``path``, the file being written (a failed write
    names no file: ENOSPC comes from ``write``, which knows only a descriptor; a failure
    with the temporary file is the output's); the same subclass (errno's)."""
    if err.errno is None:
        return err
    return OSError(err.errno, err.strerror or str(err), os.fspath(path))


@contextmanager
def replacing(path: str | os.PathLike) -> Iterator[BinaryIO]:
    """``with replacing(path) as fh:`` writes ``path`` whole or not at all: ``fh`` is a new
    file beside it (``.NAME.tmp``, made with ``O_EXCL``, never through a link), renamed over
    ``path`` when the block ends; on any failure it is removed, and ``path`` (an earlier
    file, or nothing) is as it was. A symbolic link at ``path`` is replaced, its target
    never written. An OSError names ``path``. The directory is the caller's (held by a
    :class:`DirectoryLock`, or a cache of its own): a stale temporary file there is an
    earlier writer's that was killed, and is replaced."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp")
    try:
        tmp.unlink(missing_ok=True)
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | _NOFOLLOW, 0o644)
    except OSError as err:
        raise named(err, path) from None
    try:
        with os.fdopen(fd, "wb") as fh:
            yield fh
        os.replace(tmp, path)
    except OSError as err:
        tmp.unlink(missing_ok=True)
        raise named(err, path) from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def write_file(path: str | os.PathLike, data: str | bytes) -> Path:
    """Write ``data`` (text as UTF-8) to ``path`` with :func:`replacing`; the path."""
    with replacing(path) as fh:
        fh.write(data.encode("utf-8") if isinstance(data, str) else data)
    return Path(path)


def _why(err: OSError) -> str:
    return err.strerror or type(err).__name__


def output_dir(text: str | os.PathLike, option: str = "--out") -> Path:
    """The directory named by ``option``, created with its parents when missing."""
    return _make_output_dir(text, option)[0]


def _make_output_dir(text: str | os.PathLike, option: str) -> tuple[Path, list[Path]]:
    """:func:`output_dir`, and the directories it created (the deepest first)."""
    name = os.fspath(text)
    if not name.strip():
        raise InputError("command line", option, name, "is empty",
                         "name a directory (use . for the current one)")
    path = Path(name)
    if path.exists() and not path.is_dir():
        raise InputError("command line", option, name, "exists and is not a directory")
    missing = []
    for part in (path, *path.parents):
        if part.exists() or part.is_symlink():
            break
        missing.append(part)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except FileExistsError:  # a parent is a file
        raise InputError("command line", option, name,
                         "cannot be created: a part of the path is a file") from None
    except OSError as err:
        raise InputError("command line", option, name,
                         f"cannot be created ({_why(err)})") from None
    return path, missing


@contextmanager
def held_output_dir(text: str | os.PathLike, option: str = "--out",
                    command: str = "antsim") -> Iterator[Path]:
    """``with held_output_dir(args.out, "--out", "antsim run") as out:``: the directory of
    :func:`output_dir`, held by a :class:`DirectoryLock` for the body. On leaving, however
    the command ends, the lock file is removed, and so are the directories this call created
    that the command left empty (a refused or failed command leaves no trace)."""
    path, created = _make_output_dir(text, option)
    try:
        with DirectoryLock(path, option, command):
            yield path
    finally:
        for folder in created:  # the deepest first; one still holding anything stops it
            try:
                folder.rmdir()
            except OSError:
                break


class DirectoryLock:
    """``with DirectoryLock(path, option, command):`` holds ``path`` for this process.

    Entering creates ``path/.antsim.lock`` (which also proves the directory writable) and
    takes an exclusive, non-blocking ``flock`` on it; a directory held by another process,
    or one that cannot be written, is an :class:`InputError`. Where ``fcntl`` does not exist
    (Windows) the directory is only checked for writing.
    """

    def __init__(self, path: str | os.PathLike, option: str = "--out", command: str = "antsim"):
        self.path = Path(path)
        self.option = option
        self.command = command
        self._fd: int | None = None

    def __enter__(self) -> DirectoryLock:
        lock = self.path / LOCK_NAME
        try:
            import fcntl
        except ImportError:  # no advisory locks here: the check for writing is all we do
            fcntl = None
        while True:
            fd = self._open()
            if fcntl is None:
                self._fd = fd
                return self
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                pid, _, command = os.pread(fd, 200, 0).decode("utf-8", "replace").strip() \
                    .partition("\t")
                os.close(fd)
                raise InputError("command line", self.option, str(self.path),
                                 "is in use by another antsim process"
                                 + (f" (pid {pid}: {command})" if pid else ""),
                                 "wait for it to finish, or write into another "
                                 "directory") from None
            if _same_file(fd, lock):
                break
            # the holder before us removed the file between our open and our lock: ours is
            # on a file nobody else can find, and a third process may hold the new one
            os.close(fd)
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\t{self.command}\n".encode(), 0)
        self._fd = fd
        return self

    def _open(self) -> int:
        """The lock file, opened for writing: created if missing, never through a link
        (a symbolic link's target would be overwritten) and only if it is a regular file of
        its own (a hard link shares its bytes with another file)."""
        lock = self.path / LOCK_NAME
        if not _NOFOLLOW and os.path.islink(lock):
            raise self._refuse("a symbolic link")
        try:
            fd = os.open(lock, os.O_RDWR | os.O_CREAT | _NOFOLLOW | _NONBLOCK, 0o644)
        except OSError as err:
            if err.errno == errno.ELOOP:
                raise self._refuse("a symbolic link") from None
            if err.errno == errno.EISDIR:
                raise self._refuse("a directory") from None
            raise InputError("command line", self.option, str(self.path),
                             f"cannot be written ({_why(err)})") from None
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode) or st.st_nlink > 1:  # 0: removed since (retried)
            os.close(fd)
            raise self._refuse("a hard link to another file" if stat.S_ISREG(st.st_mode)
                               else "something other than a regular file (a FIFO, a device)")
        return fd

    def _refuse(self, what: str) -> InputError:
        return InputError("command line", self.option, str(self.path),
                          f"holds {LOCK_NAME} as {what}: antsim writes its process id there and "
                          "does not write through it",
                          f"remove {self.path / LOCK_NAME} (antsim makes a new one)")

    def __exit__(self, *exc) -> None:
        if self._fd is None:
            return
        # removed while still locked: a process that opened the file before this sees, once
        # it holds the lock, that the file is gone, and starts again on a new one
        with suppress(OSError):  # already gone, or a system that cannot remove an open file
            os.unlink(self.path / LOCK_NAME)
        os.close(self._fd)  # closing the last descriptor releases the flock
        self._fd = None


def _same_file(fd: int, path: Path) -> bool:
    """Whether the open file ``fd`` is still the one ``path`` names."""
    try:
        named = os.stat(path)
    except OSError:
        return False
    held = os.fstat(fd)
    return (named.st_dev, named.st_ino) == (held.st_dev, held.st_ino)

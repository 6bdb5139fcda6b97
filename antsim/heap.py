"""Giving the C heap's freed pages back to the operating system between a command's stages.

glibc's malloc keeps memory freed inside its heap resident (an array freed below its
dynamic mmap threshold, which rises as large arrays are freed, up to 32 MiB) and reuses it
only where a new allocation fits; diagnose's stages (whole-design fits, the robust fits of
the fit variants) then extend the heap beside 60-170 MiB of free, resident pages (200,000
scans: the peak RSS was measured that much above the memory in use).
``malloc_trim(0)`` gives those pages back (madvise) without moving anything. Elsewhere (no
glibc: macOS, Windows, musl) :func:`trim_heap` does nothing; a fixed mmap threshold instead
costs a page fault per new array (measured: it made diagnose slower).
"""

from __future__ import annotations

import ctypes
import sys

__all__ = ["trim_heap"]


def _malloc_trim():
    """glibc's ``malloc_trim`` (None where the C library has none)."""
    if not sys.platform.startswith("linux"):
        return None
    try:
        fn = ctypes.CDLL(None).malloc_trim  # the process's own C library
    except (OSError, AttributeError):
        return None
    fn.argtypes = [ctypes.c_size_t]
    fn.restype = ctypes.c_int
    return fn


_TRIM = _malloc_trim()


def trim_heap() -> bool:
    """Give the heap's free pages back to the operating system (about 1 ms at 200,000
    scans); whether the C library could (False: nothing to do here)."""
    if _TRIM is None:
        return False
    _TRIM(0)
    return True

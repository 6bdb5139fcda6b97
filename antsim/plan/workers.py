"""Starting worker processes: one BLAS/OpenMP thread each (the processes are the parallelism).

Light on purpose (no numpy or simulation imports), so that a caller can start a worker before
it imports the simulation itself.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["SINGLE_THREAD_ENV", "single_threaded"]

#: environment of spawned workers
SINGLE_THREAD_ENV = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
                     "MKL_NUM_THREADS": "1"}


@contextmanager
def single_threaded() -> Iterator[None]:
    """Processes spawned inside this block start with :data:`SINGLE_THREAD_ENV`; this
    process's environment is restored after it."""
    saved = {k: os.environ.get(k) for k in SINGLE_THREAD_ENV}
    os.environ.update(SINGLE_THREAD_ENV)
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v

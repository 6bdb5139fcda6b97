"""One BLAS thread for the commands whose linear algebra is thin (2n rows, a few columns).

Such products are bound by memory, not arithmetic: a second OpenBLAS thread gains little on
an idle machine and, when the other core is busy, its spin-waiting costs several times the
time (diagnose at 200,000 scans: 3.4 to 5.3 times the wall time at load 4-5; ``antsim fit``
at 200,000 scans: 2.2 s with one thread, 4.0 to 14.2 s with two at load 2).
"""

from __future__ import annotations

from threadpoolctl import threadpool_limits

__all__ = ["one_blas_thread"]


def one_blas_thread() -> threadpool_limits:
    """A context manager in which BLAS runs on one thread (the limit given back after)."""
    return threadpool_limits(1, user_api="blas")

"""Counts a user gives (simulations, cases, processes) checked against their limits, with
one-line errors: the command line's options and the Python API's arguments alike.

May import: :mod:`controller.errors` only.
"""

from __future__ import annotations

import os

from controller.errors import InputError

__all__ = ["MAX_CASES", "MAX_SIMULATIONS", "PROCESSES_PER_CORE", "check_count",
           "check_processes"]

#: processes per core beyond which more only add start-up time and memory
PROCESSES_PER_CORE = 4
#: the most simulated campaigns an option may ask for (--sims, --resimulate): each is a
#: whole campaign, and the seeds alone of 10^8 took 3 GB before the first one ran
MAX_SIMULATIONS = 1000
#: the most blind-test cases (--n): each is a campaign diagnosed
MAX_CASES = 10_000


def check_count(value: int, option: str, minimum: int, maximum: int, what: str) -> int:
    """``value`` of a count option within ``minimum`` .. ``maximum``, else one InputError
    line (above the maximum, saying what each one costs)."""
    if value < minimum:
        raise InputError("command line", option, value, f"must be at least {minimum}")
    if value > maximum:
        raise InputError("command line", option, value, f"must be at most {maximum} ({what})")
    return value


def check_processes(value: int, option: str, minimum: int = 1) -> int:
    """``value`` of a process-count option (``--workers``, ``--jobs``) within ``minimum`` ..
    4 x the machine's cores, else one InputError line."""
    most = PROCESSES_PER_CORE * (os.cpu_count() or 1)
    if not minimum <= value <= most:
        raise InputError("command line", option, value,
                         f"must be within {minimum}..{most} ({PROCESSES_PER_CORE} per core on "
                         f"this machine's {os.cpu_count() or 1})")
    return value

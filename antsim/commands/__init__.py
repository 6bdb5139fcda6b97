"""The subcommands of ``antsim`` (:mod:`antsim.cli`): one module each, with
``configure(parser)`` and ``main(args)``, imported only when its subcommand runs.

May import any part of antsim and :mod:`controller`; no module outside this package imports
a command (the command line finds them by name; the teaching walk-through, :mod:`.demo`, runs
the others through :mod:`antsim.cli`).
"""

from __future__ import annotations

import os

from controller.errors import InputError

#: processes per core beyond which more only add start-up time and memory
PROCESSES_PER_CORE = 4


def check_processes(value: int, option: str, minimum: int = 1) -> int:
    """``value`` of a process-count option (``--workers``, ``--jobs``) within ``minimum`` ..
    4 x the machine's cores, else one InputError line."""
    most = PROCESSES_PER_CORE * (os.cpu_count() or 1)
    if not minimum <= value <= most:
        raise InputError("command line", option, value,
                         f"must be within {minimum}..{most} ({PROCESSES_PER_CORE} per core on "
                         f"this machine's {os.cpu_count() or 1})")
    return value

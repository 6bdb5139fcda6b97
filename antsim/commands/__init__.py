"""The subcommands of ``antsim`` (:mod:`antsim.cli`): one module each, with
``configure(parser)`` and ``main(args)``, imported only when its subcommand runs. The limits
of their count options (``--sims``, ``--jobs``, ...) are :mod:`antsim.options`', which the
Python API (:mod:`antsim.api`) checks its arguments with too.

May import any part of antsim and :mod:`controller`; no module outside this package imports
a command (the command line finds them by name; the teaching walk-through, :mod:`.demo`, runs
the others through :mod:`antsim.cli`).
"""

"""The simulation engines: scenarios run, once or as ensembles, for every feature that needs them.

* :mod:`.runner`: a campaign, world and control program in one simpy environment;
  recordings written scan by scan (resumable) and ``truth.json``;
* :mod:`.schedule`: the deterministic ("quiet") campaign and the schedule every Monte Carlo
  member shares;
* :mod:`.vectorized`: members on a shared schedule, vectorized across members, and members
  simulated in full;
* :mod:`.streaming`: the quiet run in a second process, its schedule streamed to the members;
* :mod:`.ensemble`: tasks and executors (this process, a local process pool, Dask);
* :mod:`.equivalents`: what a fit of the terms makes of the world's effects at a campaign's
  scans, and the recoverable truth (the mount's terms plus those shares) in ``truth.json``;
* :mod:`.flow`: several chains of tasks on one executor at once (each a generator of the
  tasks it needs next), the longest chains' tasks first.

``antsim run``, ``antsim plan``, ``antsim diagnose`` and the demo use them; none of those
features imports another.

May import: :mod:`antsim.world`, :mod:`antsim.scenario`, :mod:`antsim.progress` and
:mod:`controller`; never figures, a feature or the command line.
"""

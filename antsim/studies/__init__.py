"""The source reports' studies, repeated with the simulator's parts and the fitter.

* :mod:`.memo23`: BIMA memo 23 (Wright 1992): how well the linear equations fit an exact
  tilt and collimation, and the delay of non-intersecting axes;
* :mod:`.crane1981`: NRAO Engineering Memo 147 (Crane 1981): its Tables 4 and 5 as data and
  the comparisons of the 140-ft's simulated runs with them.

May import: :mod:`antsim.world`, :mod:`antsim.simulate` and :mod:`controller`; benchmarks
and tests use it.
"""

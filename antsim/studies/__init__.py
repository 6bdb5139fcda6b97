"""The source reports' studies, repeated with the simulator's parts and the fitter.

* :mod:`.memo23`: BIMA memo 23 (Wright 1992): how well the linear equations fit an exact
  tilt and collimation, and the delay of non-intersecting axes.

May import: :mod:`antsim.world` and :mod:`controller`; benchmarks and tests use it.
"""

"""A campaign run and the files it writes.

* :mod:`.runner`: world and control program in one simpy environment; recordings written
  scan by scan (resumable) and ``truth.json``;
* :mod:`.outputs`: the fits A-F and their files (``fit.json``, ``fit_variants.json``,
  ``fit.txt``, ``model.dat``, ``gaincurve.json``);
* :mod:`.sources`: what each source gave a run (points in fit A, hours in the window);
* :mod:`.report`: the run's ``report.html``; :mod:`.html`: the self-contained page writer
  it (and the teaching walk-through) uses.

May import: :mod:`antsim.world`, :mod:`antsim.scenario`, :mod:`antsim.figures`,
:mod:`antsim.documents` and :mod:`controller`; never plans, diagnosis or the command line.
"""

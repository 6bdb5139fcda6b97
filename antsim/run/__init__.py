"""A campaign run's files: what ``antsim run`` writes after :mod:`antsim.simulate` ran it.

* :mod:`.outputs`: the fits A-F and their files (``fit.json``, ``fit_variants.json``,
  ``fit.txt``, ``model.dat``, ``gaincurve.json``);
* :mod:`.sources`: what each source gave a run (points in fit A, hours in the window);
* :mod:`.report`: the run's ``report.html`` (written with :mod:`antsim.figures.html`).

May import: :mod:`antsim.simulate`, :mod:`antsim.world`, :mod:`antsim.scenario`,
:mod:`antsim.figures`, :mod:`antsim.documents` and :mod:`controller`; never another feature
(plans, diagnosis, the server, the studies) or the command line.
"""

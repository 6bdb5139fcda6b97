"""Fitting a user's file: a pointing model fitted to recordings, a TPOINT data file or a CSV
file of measurements, as ``antsim fit`` fits it (:mod:`.fitfile`). The command line and the
Python API (:func:`antsim.api.fit_model`) fit through here, with the same one-line errors.

May import: :mod:`antsim.progress`, :mod:`antsim.blas` and :mod:`controller` (the reading,
the terms, the fit); never another feature (runs, plans, diagnosis, the server, the studies)
or the command line.
"""

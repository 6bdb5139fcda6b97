"""Diagnosis: from a mismatch between a pointing model and recordings to the missing physics.

``diagnose(observations, baseline)`` locates where the residuals exceed the noise the baseline
predicts, tests a library of physical effects (:mod:`.candidates`) against them with an
honest forward selection (:mod:`.decide`), validated by repeating it (:mod:`.crossval`),
and reports findings in the order chosen
(:class:`~.core.Diagnosis`); :mod:`.modelit` turns findings into an updated scenario and
pointing model and re-simulates; :mod:`.blind` proves the whole chain on recordings with a
hidden effect.

How a finding is decided (docs/diagnose.md says it in words): :mod:`.core` runs it;
:mod:`.baseline` predicts the noise; :mod:`.problem` whitens the data and fits models;
:mod:`.candidates` are the library, each effect's signature and its own test;
:mod:`.decide` is the decision (which findings, by family-corrected tests, within the
parameters the data carry), one cheap function of a set of scans; :mod:`.crossval` repeats
it (inner folds keep what predicts held-out data, resamples check it is chosen again,
outer folds measure the whole); :mod:`.select` tests each finding again on every scan for
its parameters and says it; :mod:`.physics` names it (a harmonic as a harmonic, the
observation that would tell alternatives apart); :mod:`.locate` and :mod:`.report` say
where and write it. Apart, the machinery that makes it fast at scale and decides nothing:
:mod:`.factors` (the model's factorizations and all that is kept in memory),
:mod:`.shapefit` (a candidate's test from the kept factor) and :mod:`.linalg` (the kernels).

May import: :mod:`antsim.simulate` (its shared-schedule simulations predict the noise),
:mod:`antsim.world`, :mod:`antsim.scenario`, :mod:`antsim.figures` and :mod:`controller`;
never another feature (runs, plans, the server, the studies) or the command line.
"""

from __future__ import annotations

from .core import Diagnosis, diagnose
from .data import Observations, load_observations

__all__ = ["Diagnosis", "Observations", "diagnose", "load_observations"]

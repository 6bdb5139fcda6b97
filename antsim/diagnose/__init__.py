"""Diagnosis: from a mismatch between a pointing model and recordings to the missing physics.

``diagnose(observations, baseline)`` locates where the residuals exceed the noise the baseline
predicts, tests a library of physical effects (:mod:`.candidates`) against them with an
honest forward selection (:mod:`.select`), and reports findings best first
(:class:`~.core.Diagnosis`); :mod:`.modelit` turns findings into an updated scenario and
pointing model and re-simulates; :mod:`.blind` proves the whole chain on recordings with a
hidden effect.

How a finding is decided (docs/diagnose.md says it in words): :mod:`.core` runs it;
:mod:`.baseline` predicts the noise; :mod:`.problem` whitens the data and fits models;
:mod:`.candidates` test one effect each against the current model; :mod:`.select` chooses
findings round by round (family-corrected tests confirmed on held-out data);
:mod:`.crossval` adds findings by prediction where the noise is estimated from the data;
:mod:`.locate` and :mod:`.report` say where and write it. Apart, the machinery that makes it
fast at scale and decides nothing: :mod:`.factors` (the model's factorizations and all that
is kept in memory), :mod:`.shapefit` (a candidate's test from the kept factor) and
:mod:`.linalg` (the kernels).

May import: :mod:`antsim.simulate` (its shared-schedule simulations predict the noise),
:mod:`antsim.world`, :mod:`antsim.scenario`, :mod:`antsim.figures` and :mod:`controller`;
never another feature (runs, plans, the server, the studies) or the command line.
"""

from __future__ import annotations

from .core import Diagnosis, diagnose
from .data import Observations, load_observations

__all__ = ["Diagnosis", "Observations", "diagnose", "load_observations"]

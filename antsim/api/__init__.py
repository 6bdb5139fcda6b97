"""The Python API: antsim's commands as functions, for notebooks and scripts.

* :func:`run_campaign` (``antsim run``): a campaign simulated, reduced and fitted, as a
  :class:`Campaign` (fits A-F, the truth, the model in use, the report's figures);
* :func:`fit_model` (``antsim fit``): a pointing model fitted to a file, as a :class:`Fit`;
* :func:`diagnose_model` (``antsim diagnose``): what the model leaves out, as a
  :class:`Diagnosis`;
* :func:`answer_plan` (``antsim plan``): a plan's what-if questions, as
  :class:`PlanAnswers`.

``import antsim`` offers the four functions (``antsim.run_campaign``, ...) without importing
this package until one is used (the command line's start-up stays as it was). Each function
runs the command's own code (the features' functions the command calls) and returns the
numbers its files hold, the same values: ``Campaign.fit_json()`` is the ``fit.json`` the
command writes for the same scenario and seed. Nothing is written to disk without ``out=``
(``write_model=`` for a fit), except the caches the commands keep. Bad input raises
:class:`controller.errors.InputError` with the one line the command prints.

Units: every angle a result returns is an :class:`astropy.units.Quantity` in arcsec (the
documents, ``to_json()``, are the files', with the unit in the key); every angle given may
be a Quantity or a plain number of arcsec. Pointing errors are "indicated minus true", as
the 1990 report writes them. A result shows a short table in a notebook (``_repr_html_``)
and at a prompt; its ``plot...`` methods return matplotlib Figures drawn by
:mod:`antsim.figures` on their own canvases (no pyplot state). docs/api.md has examples;
docs/tutorial.ipynb is a lesson.

May import: every part of antsim but the command line (:mod:`antsim.commands`,
:mod:`antsim.cli`), and :mod:`controller`; nothing but :mod:`antsim`'s own ``__getattr__``
imports it.
"""

from .campaign import Campaign, run_campaign
from .diagnosis import Diagnosis, diagnose_model
from .fit import Fit
from .fitting import fit_model
from .planning import PlanAnswers, answer_plan

__all__ = ["Campaign", "Diagnosis", "Fit", "PlanAnswers", "answer_plan", "diagnose_model",
           "fit_model", "run_campaign"]

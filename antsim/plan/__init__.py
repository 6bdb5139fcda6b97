"""What-if observing plans: predicted and Monte Carlo errors of a pointing campaign.

``antsim plan PLAN.toml`` answers an observer's questions before telescope time is spent.
Modules:

* :mod:`~antsim.plan.planfile`: plan files (a base scenario, variants, questions), validated
  with one-line errors;
* :mod:`~antsim.plan.fisher`: the predicted (Fisher/sandwich) covariance of the fitted terms
  from the design and a noise model of the physics;
* :mod:`~antsim.plan.study`: running a plan, its JSON document and tables;
* :mod:`~antsim.plan.answers`: how long, which sources, which terms cannot be separated;
* :mod:`~antsim.plan.outputs`: the options' limits and the files written (``plan.json``,
  ``plan.txt``, figures, ``report.html``);
* :mod:`~antsim.plan.report`: the page.

The Monte Carlo members, their shared schedule and the executors are the engines of
:mod:`antsim.simulate`; the figures are :mod:`antsim.figures.plan`.

May import: :mod:`antsim.simulate`, :mod:`antsim.world`, :mod:`antsim.scenario`,
:mod:`antsim.schema`, :mod:`antsim.tomlcheck`, :mod:`antsim.figures`, antsim's base modules
(progress, output directories, the options' limits) and :mod:`controller`; never another feature
(runs, diagnosis, the server, the studies) or the command line.
"""

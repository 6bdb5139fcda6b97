"""What-if observing plans: predicted and Monte Carlo errors of a pointing campaign (issue 6).

``antsim plan PLAN.toml`` answers an observer's questions before telescope time is spent.
Modules:

* :mod:`~antsim.plan.planfile`: plan files (a base scenario, variants, questions), validated
  with one-line errors;
* :mod:`~antsim.plan.vectorized`: the deterministic run with the antenna's recorder (the
  shared schedule) and members simulated on it, vectorized across members;
* :mod:`~antsim.plan.fisher`: the predicted (Fisher/sandwich) covariance of the fitted terms
  from the design and a noise model of the physics;
* :mod:`~antsim.plan.ensemble`: tasks and engines (this process, a local pool, Dask);
* :mod:`~antsim.plan.study`: running a plan, its JSON document and tables;
* :mod:`~antsim.plan.answers`: how long, which sources, which terms cannot be separated;
* :mod:`~antsim.plan.schedule` and :mod:`~antsim.plan.streaming`: the shared schedule of a
  quiet run, and its members streamed as it is recorded (also :mod:`antsim.diagnose`'s).

Its figures are :mod:`antsim.figures.plan`. May import: :mod:`antsim.run`,
:mod:`antsim.world`, :mod:`antsim.scenario`, :mod:`antsim.tomlcheck` and :mod:`controller`;
never diagnosis or the command line.
"""

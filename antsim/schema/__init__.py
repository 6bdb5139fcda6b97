"""The one declared schema of scenario and plan files: per key its kind, unit, range,
default, one line of meaning and the document it comes from.

* :mod:`.keys`: :class:`~.keys.Key` (one setting) and :class:`~.keys.Section` (a table of
  them, bound to the settings dataclass it fills), and how a value is read through its key;
* :mod:`.utc`: the times UTC can hold (ERFA's leap seconds; no leap second as a start);
* :mod:`.scenario`: the scenario's tables (the world's parts, the controller's settings and
  each effect's parameters, which the effects declare beside their physics);
* :mod:`.plan`: the plan's tables (a variant's keys are the scenario's);
* :mod:`.markdown`: the reference page, ``docs/scenarios.md``, written from them
  (``python -m antsim.schema --markdown > docs/scenarios.md``).

The readers (:mod:`antsim.scenario`, :mod:`antsim.plan.planfile`) read every key through
these declarations, so validation, the one-line errors and the reference agree.

May import: :mod:`antsim.tomlcheck` and :mod:`controller`; :mod:`.scenario` and :mod:`.plan`
also the world's parts' settings (:mod:`antsim.world`, never the assembled
:mod:`antsim.world.world`). :mod:`.keys` imports nothing of antsim but the TOML reader: the
world's effects declare their parameters with it. Nothing here imports the scenario reader,
the engines, the features or the command line.
"""

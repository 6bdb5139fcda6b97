"""antsim: a simulated radio telescope, and the tool that calibrates its pointing.

It runs the control program (:mod:`controller`, which never imports antsim) against a
simulated world. Each part imports only those listed before it, and :mod:`controller`
(``tests/test_layout.py`` checks it):

* :mod:`.tomlcheck`: TOML read with one-line errors; :mod:`.documents`: what the source
  documents publish (numbers only, beside which a run prints its own); :mod:`.bundled`:
  the scenarios and plans that come with antsim, found by name; :mod:`.progress`: progress
  of long work, on a terminal and off one; :mod:`.outdir`: output directories;
  :mod:`.options`: the limits of a user's counts;
* :mod:`.schema.keys`: a declared setting (kind, unit, range, default, meaning, source);
* :mod:`.world`: the simulated telescope (sky, weather, mount, physical effects, beam,
  receiver, camera) and the protocol's implementation;
* :mod:`.schema`: every key of scenario and plan files, declared once, and the reference
  page written from it (``docs/scenarios.md``);
* :mod:`.scenario`: scenario files, read into the world's and the controller's settings
  through the schema (the world's parts' settings are below it, the world built from a
  scenario above it);
* :mod:`.simulate`: the engines: a campaign run, the quiet run's shared schedule, Monte
  Carlo members vectorized across seeds, and the executors that spread them over processes;
* :mod:`.figures`: figures by page, and the self-contained HTML page writer; they draw values
  and import nothing else of antsim but the documents' numbers;
* the features, each one command's work, none importing another: :mod:`.run` (a campaign
  run's files: fits, report), :mod:`.fit` (a user's file fitted), :mod:`.serve` (the
  simulated antenna as a KATCP device, for control software outside), :mod:`.plan`
  (what-if observing plans), :mod:`.diagnose` (what the model leaves out) and
  :mod:`.studies` (the source reports' studies repeated);
* :mod:`.commands` and :mod:`.cli`: the ``antsim`` command line; :mod:`.api`: the same
  commands as Python functions, for notebooks.

The Python API's functions are attributes of this package: ``antsim.run_campaign``,
``antsim.fit_model``, ``antsim.diagnose_model`` and ``antsim.answer_plan``
(:mod:`antsim.api`, docs/api.md). They are imported when first used (PEP 562), so that
``import antsim`` (the command line's start) stays as quick as it was; their names are no
subpackage's, so importing :mod:`antsim.run` or :mod:`antsim.plan` does not hide them.
"""

# no network, before anything touches astropy
from controller.astro import offline as _offline  # noqa: F401

from ._version import __version__

#: the Python API's functions, imported from :mod:`antsim.api` when first used
API = ("run_campaign", "fit_model", "diagnose_model", "answer_plan")

__all__ = ["__version__", *API]


def __getattr__(name: str):
    if name in API:
        from . import api

        return getattr(api, name)
    raise AttributeError(f"module 'antsim' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *API})

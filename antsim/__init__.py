"""antsim: a simulated radio telescope, and the tool that calibrates its pointing.

It runs the control program (:mod:`controller`, which never imports antsim) against a
simulated world. Each part imports only those listed before it, and :mod:`controller`
(``tests/test_layout.py`` checks it):

* :mod:`.tomlcheck`: TOML read with one-line errors; :mod:`.documents`: what the source
  documents publish (numbers only, beside which a run prints its own); :mod:`.bundled`:
  the scenarios and plans that come with antsim, found by name; :mod:`.progress`: progress
  of long work, on a terminal and off one;
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
  run's files: fits, report), :mod:`.serve` (the simulated antenna as a KATCP device, for
  control software outside), :mod:`.plan` (what-if observing plans), :mod:`.diagnose` (what
  the model leaves out) and :mod:`.studies` (the source reports' studies repeated);
* :mod:`.commands` and :mod:`.cli`: the ``antsim`` command line.
"""

# no network, before anything touches astropy
from controller.astro import offline as _offline  # noqa: F401

from ._version import __version__

__all__ = ["__version__"]

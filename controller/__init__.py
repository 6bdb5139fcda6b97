"""The control program and its pointing mathematics: what would run at a real antenna.

It drives an antenna only through :mod:`controller.protocol` and never imports ``antsim``.
Each part imports only the parts listed before it (``tests/test_layout.py`` checks it):

* :mod:`.errors`, :mod:`.units`, :mod:`.protocol`: bad input as one line (and text files
  read bounded, written whole), angle units and Quantity at the boundary, the narrow
  interface an antenna implements;
* :mod:`.filekind`: what kind of file a user gave (recordings, CSV, TPOINT data, a model),
  the one place that decides it; it imports only the errors;
* :mod:`.wire`: the protocol over KATCP, an antenna reached over the network (``antsim
  serve`` or a real antenna's control unit); it imports only the base modules;
* :mod:`.astro`: time, site, sources, the ephemeris, refraction, the Sun, mount frames, and
  astropy kept offline;
* :mod:`.pointing`: the pointing model's terms, the model, its fit (the 1990 report's
  robust procedure, TPOINT's statistics, honest error bars), the fit variants A-F, TPOINT
  and model files, the equatorial and BIMA models;
* :mod:`.scans`: the scan engine: source trajectories, five-point cross scans and their
  reduction, tipping scans, gain curves;
* :mod:`.program`: the control program: its configuration, the scheduler, the campaign
  loop (radio and optical), recordings, and :mod:`.program.inputs`, the front door every
  command reads a user's file of pointing measurements through.
"""

# astropy's IERS auto-download off before any astropy use
from .astro import offline as _offline  # noqa: F401
from .errors import InputError
from .pointing.model import NAMED_MODELS, PointingModel
from .pointing.terms import Term, get_term

__all__ = ["NAMED_MODELS", "InputError", "PointingModel", "Term", "get_term"]

"""The pointing model and its fit: the mathematics, apart from any antenna.

* :mod:`.terms`: the term vocabulary (TPOINT's, Ghigo's W1..W10, katpoint's P1..P22), each
  term's physics beside its TPOINT name; :mod:`.model`: a model (offset, apply, reverse,
  fit); :mod:`.equatorial` and :mod:`.bima`: the 140-ft's and BIMA memo 23's models;
* the fit: :mod:`.fitting` (the entry point), :mod:`.data` (its input), :mod:`.robust` (the
  1990 report's stages and TPOINT's statistics), :mod:`.solvers` (least squares, LAD),
  :mod:`.jackknife` (honest error bars), :mod:`.result`; :mod:`.variants`: the report's fits
  A-F of one campaign;
* files: :mod:`.tpoint` (TPOINT data and ``.mod`` files), :mod:`.modelio` (named models,
  ``.mod`` files and ``fit.json`` loaded as models), :mod:`.vocabulary` (a model in TPOINT's
  names and signs for a file), :mod:`.signs` (the units and sign of any model in words);
* thermal: :mod:`.thermal` (terms in structure temperatures, imported here so that every
  term name is known wherever a term is looked up), :mod:`.proxies` (their proxies),
  :mod:`.selection` (which extra terms the data support: fit T).

May import: :mod:`controller.astro`, :mod:`controller.errors`, :mod:`controller.units`;
never the scans, the program or the protocol.
"""

from . import thermal  # noqa: F401  (registers the thermal terms with terms.get_term)

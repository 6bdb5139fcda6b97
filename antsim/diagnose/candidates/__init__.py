"""The library of candidate physical effects: signature, parameters, physical cause, test.

Every row of docs/physics.md's signature table is here, and the effects that are not
harmonics. Each candidate knows

* its residual **signature** as regressors: columns of the error (indicated minus true,
  arcsec) it makes per unit of its parameters, xel rows then el rows (``kind = "offsets"``);
  or, for the polarization squint and the beam width, a test on other recorded quantities
  (XR - XL offsets, measured widths: ``kind = "channel"``);
* its **parameters**, linear (amplitudes) and nonlinear (time constants, which source, tilt
  direction), the nonlinear ones searched on a grid and refined (the look-elsewhere effect is
  paid with an effective number of independent trials);
* the simulator **effect** that reproduces it (``antsim.world.effects.EFFECTS``) and its TPOINT
  **terms** where it has them, so that a finding becomes an updated scenario and model;
* a plain **explanation** of the physical cause;
* for the blind harness, how to **draw** random parameters and its **unit signal** (the
  detection threshold is the amplitude whose expected chi^2 decrease equals the critical
  value of its test).

One family per module: :mod:`.base` (the base class, its test and shared helpers),
:mod:`.terms` (linear pointing terms: TPOINT's, harmonic pairs and families, the feed
offset), :mod:`.thermal` (sunset drifts and transients, temperature drifts),
:mod:`.changes` (a step at an unknown time), :mod:`.dynamics` (clock, servo lag, backlash),
:mod:`.optics` (source structure, exact tilt and collimation, squint, beam width);
:mod:`.library` lists them all (:data:`~.library.CANDIDATES`), the term families as tables
(rows of docs/physics.md's signature table, TPOINT's harmonic generator) that a new family extends.
"""

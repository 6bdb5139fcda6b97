"""Astronomy for the control program: where the sky is, seen from the antenna.

* :mod:`.offline`: astropy never reaches the network; the bundled IERS tables, cached;
* :mod:`.site`: the antenna's site and surface weather; :mod:`.sources`: fixed radio sources;
* :mod:`.earth`: the UTC instant and labels, UT1 and polar motion;
  :mod:`.hermite`: piecewise cubics;
* :mod:`.ephemeris`: apparent topocentric positions of the sources and the Sun, fast;
* :mod:`.refraction`: the air's bending; :mod:`.sun`: sunrise, sunset, day and night;
* :mod:`.frames`: the two axes a mount turns in (alt-az or equatorial);
* :mod:`.values`: the number checks they share.

May import: :mod:`controller.errors` and :mod:`controller.units` (and astropy, ERFA,
numpy); nothing else of the control program.
"""

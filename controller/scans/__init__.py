"""The scan engine: what the control program does with the antenna, one scan at a time.

* :mod:`.config`: the scans' settings (cross scan, tipping, a-priori sky, gain curve);
* :mod:`.tracking`: where the encoders must point to follow a source (refraction, model);
* :mod:`.scan`: the five-point cross scan as a simpy process; :mod:`.reduction`: five powers
  to an offset (Clark's method, least squares, the Cramer-Rao bound);
* :mod:`.tipping`: tipping scans and the zenith opacity; :mod:`.gaincurve`: gain curves
  from the scans' amplitudes.

May import: :mod:`controller.pointing`, :mod:`controller.astro`, :mod:`controller.protocol`,
:mod:`controller.errors`, :mod:`controller.units`; never the control program
(:mod:`controller.program`), which runs the scans.
"""

"""The control program: a pointing campaign, from the catalogue to the recordings.

* :mod:`.config`: what an observer sets (catalogue, scheduler, search, optical pointing,
  and :class:`~.config.ControllerConfig`, which holds them and the scans' settings);
* which source next, split as astroplan splits it: :mod:`.observer` (the site's view of the
  sky, targets), :mod:`.constraints` (when a target may be observed; what was), and
  :mod:`.scheduler` (the policies that pick one);
* :mod:`.campaign`: the campaign loop as a simpy process (scan, reduce, record, search);
  :mod:`.optical`: the same with a TV camera on stars;
* :mod:`.recordings`: one ECSV row per scan and polarization, written as scans complete;
* :mod:`.csvdata`: one's own measurements as CSV; :mod:`.inputs`: the front door to a
  user's file of pointing measurements (TPOINT data, recordings or CSV: its kind decided by
  :mod:`controller.filekind`, read once, checked).

May import every other part of :mod:`controller`; nothing of ``antsim``.
"""

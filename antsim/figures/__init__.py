"""Figures, by the page that shows them.

* :mod:`.style`: what every figure shares (the canvas with the project's pinned style, saving
  without timestamps, colours, small helpers): same inputs, same bytes;
* :mod:`.charts`: figure types several pages draw (errors against elevation and azimuth,
  residual arrows on the sky, histograms, grouped bars);
* :mod:`.run`: the run report's Figs. 1-10 (``antsim run``);
* :mod:`.diagnose`: residuals before and after a finding (``antsim diagnose --out``);
* :mod:`.plan`: the plan's comparisons (``antsim plan --out``);
* :mod:`.demo`: the teaching walk-through's cross scans (``antsim demo``);
* :mod:`.html`: the self-contained HTML page every report is written with.

Conventions on every page: errors and residuals are "indicated minus true" (the sign of the
recordings' corrections and of :class:`controller.pointing.data.PointingData`),
cross-elevation = dA cos E, arcsec unless a label says otherwise; azimuth North = 0, East =
90 deg.

May import: :mod:`controller` (the fit results and recordings they draw), matplotlib
(inside the drawing, so that importing a page stays cheap) and :mod:`antsim.documents` (the
published numbers drawn beside the run's). Figures are drawn from values, never from a
simulation: nothing here imports the rest of :mod:`antsim`.
"""

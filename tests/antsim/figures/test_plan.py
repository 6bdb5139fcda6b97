"""antsim/figures/plan.py: the duration answer's curve reads in plain numbers."""

from __future__ import annotations

import re

import pytest


def _answer() -> dict:
    """Twenty nights of a sigma falling as 1/sqrt(n) from 19" (the 1990 plan's W4)."""
    curve = [{"count": n, "sigma_arcsec": {"W4": 19.0 / n ** 0.5}} for n in range(1, 21)]
    return {"terms": ["W4"], "target_arcsec": 6.0, "targets_arcsec": {"W4": 6.0},
            "unit": "night", "based_on": "night only", "reached": True,
            "answer": {"count": 11}, "curve": curve}


def test_duration_axes_are_labelled_with_plain_numbers():
    """Both axes are logarithmic (1 to 20 nights, 4" to 19"); every tick label is a plain
    number ("20", "5"), none in powers of ten ("2x10^1"), and the minor ticks say nothing."""
    pytest.importorskip("matplotlib")
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from antsim.figures.plan import draw_duration

    fig = Figure(figsize=(7.0, 4.2), dpi=100)
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0.11, 0.13, 0.85, 0.74))
    draw_duration(ax, _answer())
    fig.canvas.draw()
    assert ax.get_xscale() == ax.get_yscale() == "log"
    for axis in (ax.xaxis, ax.yaxis):
        lo, hi = sorted(axis.get_view_interval())
        labels = [t.get_text() for t in axis.get_majorticklabels()
                  if lo <= t.get_position()[axis is ax.yaxis] <= hi]
        assert labels and all(re.fullmatch(r"\d+(\.\d+)?", x) for x in labels), labels
        assert not any(t.get_text() for t in axis.get_minorticklabels())
    y_labels = [t.get_text() for t in ax.yaxis.get_majorticklabels()]
    assert "10" in y_labels and "5" in y_labels

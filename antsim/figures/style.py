"""What every figure shares: a canvas with the project's style, saving, colours, helpers.

Determinism: matplotlib's object API on the non-interactive Agg canvas (pyplot is never
imported: no global figure state, no GUI backend), matplotlib's default style reset for every
figure (:class:`Canvas`), fixed size and resolution (:data:`FIG_DPI`), no timestamps: PNG
metadata carry only ``Software: antsim``, SVG files a fixed ``svg.hashsalt`` and no date. The
same inputs give byte-identical files.

Inside :func:`in_memory` (the Python API, :mod:`antsim.api`) a figure is drawn the same way
and kept, not written: its :class:`FigureFile` holds the matplotlib Figure and names the file
it would have been.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple

import matplotlib
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from antsim.outdir import replacing
from controller.astro.sun import DAY_SUN_MIN_DEG, NIGHT_SUN_MAX_DEG

__all__ = [
    "FIG_DPI",
    "SERIES_COLORS",
    "BinnedMean",
    "Canvas",
    "FigureFile",
    "binned_mean",
    "day_night_groups",
    "figure_file",
    "in_memory",
    "keeping",
    "rms",
]

#: resolution of every PNG (dots per inch); figure sizes are given in inches
FIG_DPI = 100

DAY_COLOR = "#d95f02"
TWILIGHT_COLOR = "#8c8c8c"
NIGHT_COLOR = "#1f4e9c"
REJECT_COLOR = "#d62728"
SERIES_COLORS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b",
                  "#e377c2", "#7f7f7f", "#bcbd22", "#17becf")
#: pinned settings on top of matplotlib's defaults (the user's matplotlibrc is ignored)
_STYLE = {
    "figure.dpi": FIG_DPI,
    "savefig.dpi": FIG_DPI,
    "font.size": 9.0,
    "axes.titlesize": 10.0,
    "axes.grid": True,
    "grid.alpha": 0.35,
    "legend.fontsize": 8.0,
    "svg.hashsalt": "antsim",
    "svg.fonttype": "path",
    "path.simplify": True,
    # a fixed title height: matplotlib otherwise measures every tick label of the axes to
    # lift the title above any on top (none of ours has labels there: same pixels, ~4% less
    # drawing time)
    "axes.titley": 1.0,
}
_PNG_METADATA = {"Software": "antsim"}
#: zlib level of the PNGs: 3 encodes in 2/3 of the time of PIL's default 6 for files <1% larger
_PNG_COMPRESS_LEVEL = 3
_SVG_METADATA = {"Creator": "antsim", "Date": None}


@dataclass(frozen=True)
class FigureFile:
    """A figure written to disk: ``path`` (the PNG), a ``title`` saying what is plotted and a
    ``caption`` for a report; ``extra`` lists the same figure in other formats (e.g. SVG).
    Drawn inside :func:`in_memory`: nothing written, ``path`` the file it would have been,
    ``figure`` the matplotlib Figure (None otherwise)."""

    path: Path
    title: str
    caption: str
    extra: tuple[Path, ...] = ()
    figure: Any = field(default=None, compare=False, repr=False)


#: whether figures drawn now are kept in memory instead of written (:func:`in_memory`)
_KEEP: ContextVar[bool] = ContextVar("antsim_figures_in_memory", default=False)


@contextmanager
def in_memory() -> Iterator[None]:
    """``with in_memory():`` every figure drawn inside is kept, not written: the drawing
    functions return :class:`FigureFile` s whose ``figure`` is the matplotlib Figure, and
    write no file (the Python API draws a command's figures so, for a notebook)."""
    token = _KEEP.set(True)
    try:
        yield
    finally:
        _KEEP.reset(token)


def keeping() -> bool:
    """True inside :func:`in_memory` (figures kept, not written)."""
    return _KEEP.get()


class Canvas:
    """``with Canvas(w, h) as fig:`` a Figure on an Agg canvas inside matplotlib's default
    style plus :data:`_STYLE` (restored afterwards)."""

    def __init__(self, width_in: float, height_in: float):
        self.size = (width_in, height_in)

    def __enter__(self):
        self._rc = matplotlib.rc_context()
        self._rc.__enter__()
        matplotlib.rcdefaults()
        matplotlib.rcParams.update(_STYLE)
        self.fig = Figure(figsize=self.size, dpi=FIG_DPI)
        FigureCanvasAgg(self.fig)
        return self.fig

    def __exit__(self, *exc) -> None:
        self._rc.__exit__(*exc)


def _save(fig, path: Path, formats: Sequence[str]) -> tuple[Path, tuple[Path, ...]]:
    """Write ``fig`` as ``path`` (PNG) and in any further ``formats`` beside it."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    unknown = set(formats) - {"png", "svg"}
    if unknown:
        raise ValueError(f"unknown figure format(s) {sorted(unknown)}: use 'png' and/or 'svg'")
    png = path.with_suffix(".png")
    with replacing(png) as fh:  # whole or not at all; an error names the file
        fig.savefig(fh, format="png", dpi=FIG_DPI, metadata=_PNG_METADATA,
                    pil_kwargs={"compress_level": _PNG_COMPRESS_LEVEL})
    extra = []
    if "svg" in formats:
        svg = path.with_suffix(".svg")
        with replacing(svg) as fh:
            fig.savefig(fh, format="svg", metadata=_SVG_METADATA)
        extra.append(svg)
    return png, tuple(extra)


def figure_file(fig, path: Path, title: str, caption: str,
                 formats: Sequence[str]) -> FigureFile:
    """``fig`` titled and written as ``path`` (PNG) and ``formats``; inside
    :func:`in_memory` kept instead (nothing written)."""
    fig.suptitle(title, fontsize=11, fontweight="bold")
    if keeping():
        return FigureFile(Path(path).with_suffix(".png"), title, caption, figure=fig)
    png, extra = _save(fig, path, formats)
    return FigureFile(png, title, caption, extra)


def rms(x: np.ndarray) -> float:
    x = np.asarray(x, dtype=float)
    return float(np.sqrt(np.mean(x * x))) if x.size else math.nan


class BinnedMean(NamedTuple):
    """Bins of :func:`binned_mean`: their centres, the means in them and their standard
    errors (in the units of x and y)."""

    centres: np.ndarray
    means: np.ndarray
    errors: np.ndarray


def binned_mean(x: np.ndarray, y: np.ndarray, edges: np.ndarray
                 ) -> BinnedMean:
    """Bin centres, means and standard errors of ``y`` in bins of ``x`` (bins with fewer than
    three points left out)."""
    idx = np.digitize(x, edges) - 1
    centres, means, errors = [], [], []
    for k in range(len(edges) - 1):
        sel = y[idx == k]
        if sel.size >= 3:
            centres.append(0.5 * (edges[k] + edges[k + 1]))
            means.append(sel.mean())
            errors.append(sel.std(ddof=1) / math.sqrt(sel.size))
    return BinnedMean(np.array(centres), np.array(means), np.array(errors))


def day_night_groups(sun_el_deg: np.ndarray) -> list[tuple[str, np.ndarray, str]]:
    """(label, mask, colour) for day, twilight and night by the Sun's elevation (the
    thresholds of fits D and E)."""
    sun = np.asarray(sun_el_deg, dtype=float)
    day = sun > DAY_SUN_MIN_DEG
    night = sun < NIGHT_SUN_MAX_DEG
    return [
        (f"day (Sun > {DAY_SUN_MIN_DEG:g}\N{DEGREE SIGN})", day, DAY_COLOR),
        ("twilight", ~day & ~night, TWILIGHT_COLOR),
        (f"night (Sun < {NIGHT_SUN_MAX_DEG:g}\N{DEGREE SIGN})", night, NIGHT_COLOR),
    ]

"""The figures of the teaching walk-through (``antsim demo``) that no other page draws:
cross scans as powers against offset."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .style import SERIES_COLORS, Canvas, FigureFile, figure_file

__all__ = ["ScanTrace", "scan_trace_figure"]


@dataclass(frozen=True)
class ScanTrace:
    """The powers of one cross scan for plotting: sky offsets (arcmin; azimuth scan in
    cross-elevation) and total powers (K) of each axis, and a label for the legend."""

    label: str
    az_offsets_arcmin: np.ndarray
    az_power_k: np.ndarray
    el_offsets_arcmin: np.ndarray
    el_power_k: np.ndarray


def scan_trace_figure(traces: Sequence[ScanTrace], path: str | Path, *, hpbw_arcmin: float,
                      title: str = "", caption: str = "", ylabel: str = "total power (K)",
                      formats: Sequence[str] = ("png",)) -> FigureFile:
    """Total power (K) against sky offset (arcmin) for the azimuth (cross-elevation) and
    elevation halves of one or more cross scans, with the beam's half-power width marked."""
    if not traces:
        raise ValueError("scan_trace_figure needs at least one scan")
    title = title or "Cross scans"
    with Canvas(10.0, 4.6) as fig:
        axes = fig.subplots(1, 2, sharey=True)
        fig.subplots_adjust(left=0.07, right=0.98, bottom=0.12, top=0.84, wspace=0.08)
        for ax, axis_name in zip(axes, ("azimuth scan (cross-elevation offset)",
                                        "elevation scan (elevation offset)"), strict=True):
            ax.axvspan(-hpbw_arcmin / 2, hpbw_arcmin / 2, color="0.9", lw=0,
                       label=f"half-power beam width ({hpbw_arcmin:g}')")
            ax.set_xlabel(f"{axis_name} (arcmin)")
            ax.axvline(0.0, color="k", lw=0.6)
        for k, trace in enumerate(traces):
            color = SERIES_COLORS[k % len(SERIES_COLORS)]
            for ax, x, y in ((axes[0], trace.az_offsets_arcmin, trace.az_power_k),
                             (axes[1], trace.el_offsets_arcmin, trace.el_power_k)):
                x = np.asarray(x, float)
                y = np.asarray(y, float)
                order = np.argsort(x)
                ax.plot(x[order], y[order], "-o", color=color, ms=5, lw=1.2, label=trace.label)
        axes[0].set_ylabel(ylabel)
        axes[0].legend(loc="upper left", fontsize=7)
        return figure_file(fig, Path(path), title, caption or title, formats)

"""Piecewise cubics on a uniform grid (Hermite, slopes by 4th-order finite differences):
the ephemeris' interpolant, without a linear solve and without importing scipy."""

from __future__ import annotations

import numpy as np

__all__ = ["hermite_evaluate", "hermite_table"]


def hermite_table(values: np.ndarray, step: float) -> np.ndarray:
    """Piecewise-cubic coefficients for samples on a uniform grid along axis 0.

    ``values`` has shape ``(n, ...)`` with ``n >= 5``; returns ``(n, 4, ...)`` holding, per
    interval, the coefficients of s^3, s^2, s, 1 (s = seconds into the interval); the extra
    last row is the linear continuation from the last node, so a time exactly at the grid's
    end needs no clipping. Slopes at the nodes come from 5-point finite differences (4th
    order; one-sided at the two ends), so the interpolant is C1 and its error ~ h^4 f''''/384,
    like a cubic spline's, without a linear solve (and without importing scipy).
    """
    f = values
    d = np.empty_like(f)
    d[2:-2] = (f[:-4] - 8.0 * f[1:-3] + 8.0 * f[3:-1] - f[4:]) / (12.0 * step)
    d[0] = (-25.0 * f[0] + 48.0 * f[1] - 36.0 * f[2] + 16.0 * f[3] - 3.0 * f[4]) / (12.0 * step)
    d[1] = (-3.0 * f[0] - 10.0 * f[1] + 18.0 * f[2] - 6.0 * f[3] + f[4]) / (12.0 * step)
    d[-1] = (25.0 * f[-1] - 48.0 * f[-2] + 36.0 * f[-3] - 16.0 * f[-4] + 3.0 * f[-5]) / (
        12.0 * step
    )
    d[-2] = (3.0 * f[-1] + 10.0 * f[-2] - 18.0 * f[-3] + 6.0 * f[-4] - f[-5]) / (12.0 * step)
    slope = (f[1:] - f[:-1]) / step
    table = np.zeros((f.shape[0], 4, *f.shape[1:]))
    table[:-1, 0] = (d[:-1] + d[1:] - 2.0 * slope) / step**2
    table[:-1, 1] = (3.0 * slope - 2.0 * d[:-1] - d[1:]) / step
    table[:, 2] = d
    table[:, 3] = f
    return table


def hermite_evaluate(table: np.ndarray, start: float, step: float, t: np.ndarray) -> np.ndarray:
    """Evaluate a :func:`hermite_table` at times ``t`` (1-d) inside its grid; ``(len(t), ...)``."""
    position = (t - start) / step
    k = position.astype(np.intp)
    s = ((position - k) * step).reshape((-1,) + (1,) * (table.ndim - 2))
    c = table[k]
    return ((c[:, 0] * s + c[:, 1]) * s + c[:, 2]) * s + c[:, 3]

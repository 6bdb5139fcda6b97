"""The outcome of a fit: the fitted model, TPOINT's statistics, honest error bars, warnings."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .data import LinearModel
from .jackknife import JackknifeResult
from .legacy import w_terms_marker
from .signs import UNITS, sign_convention

__all__ = ["FitResult", "readonly"]


def _json_float(x: float) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def readonly(a: np.ndarray) -> np.ndarray:
    """A read-only copy of ``a`` (a result's arrays cannot be changed by who reads them)."""
    a = np.array(a, copy=True)
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class FitResult:
    """The outcome of :func:`~controller.pointing.fitting.fit_model`. Arrays are read-only; nothing
    here mutates inputs.

    ``model``: the fitted :class:`~controller.pointing.model.PointingModel` (unconstrained terms 0).
    ``sigma_arcsec``: per term, NaN for unconstrained terms. ``used``: mask of the observations
    in the final fit. ``residual_*_arcsec``: data minus fitted model for ALL observations,
    rejected ones included. ``correlation``: M x M, NaN in rows/columns of unconstrained terms.
    ``condition_number``: 2-norm condition number of the final design matrix of the fitted
    (constrained) terms with columns scaled to unit length. ``warnings``: plain sentences.
    ``sigma_honest_arcsec``: honest error bars of the same coefficients: the cluster
    jackknife (CV3) standard error ``sigma_jackknife_arcsec`` times sqrt(nu / (nu - 2)), nu
    its Satterthwaite degrees of freedom ``honest_dof`` (see :mod:`controller.pointing.jackknife`),
    so that (error / sigma_honest) spreads by 1; ``honest_clusters`` the clusters used,
    ``honest_phases`` the time-block grids averaged. These are computed on first use.
    """

    model: LinearModel
    sigma_arcsec: np.ndarray
    n_input: int
    n_used: int
    n_rejected: int
    used: np.ndarray
    residual_xel_arcsec: np.ndarray
    residual_el_arcsec: np.ndarray
    sky_rms_arcsec: float
    xel_rms_arcsec: float
    el_rms_arcsec: float
    popn_sd_arcsec: float
    condition_number: float
    correlation: np.ndarray
    unconstrained: tuple[str, ...]
    warnings: tuple[str, ...] = ()
    robust: bool = True
    weighted: bool = False
    n_fitted: int = 0
    #: the rms (arcsec, or dimensionless when weighted) that scales sqrt(diag((A^T W A)^-1))
    sigma_scale: float = field(default=float("nan"))
    honest_block_s: float | None = None
    #: computes the honest error bars on first use (they cost about a third of a fit of
    #: 100,000 observations, and many callers need only TPOINT's statistics)
    honest_source: Callable[[], JackknifeResult] | None = field(
        default=None, repr=False, compare=False)
    #: terms held at a given value, not fitted (no sigma; ``fit_model(fixed=...)``)
    fixed: tuple[str, ...] = ()
    #: how the terms were chosen, where a procedure chose them (fit T's selection), as sentences
    notes: tuple[str, ...] = ()

    @cached_property
    def _jackknife(self) -> JackknifeResult | None:
        return None if self.honest_source is None else self.honest_source()

    @property
    def sigma_honest_arcsec(self) -> np.ndarray | None:
        j = self._jackknife
        return None if j is None else readonly(j.sigma_t_scaled)

    @property
    def sigma_jackknife_arcsec(self) -> np.ndarray | None:
        j = self._jackknife
        return None if j is None else readonly(j.sigma)

    @property
    def honest_dof(self) -> np.ndarray | None:
        j = self._jackknife
        return None if j is None else readonly(j.dof)

    @property
    def honest_clusters(self) -> int:
        j = self._jackknife
        return 0 if j is None else j.clusters

    @property
    def honest_phases(self) -> int:
        """Time-block grids whose jackknife variances were averaged (1 without times)."""
        j = self._jackknife
        return 0 if j is None else j.phases

    @property
    def names(self) -> tuple[str, ...]:
        return self.model.names

    @property
    def values_arcsec(self) -> np.ndarray:
        return self.model.values_arcsec

    def to_json(self) -> dict:
        """The ``antsim fit --json`` document (docs/contract.md): plain types, null for NaN."""
        names = list(self.names)
        return {
            "n_input": int(self.n_input),
            "n_used": int(self.n_used),
            "n_rejected": int(self.n_rejected),
            "model": self.model.name,
            **w_terms_marker(names),
            "sign_convention": sign_convention(names),
            "terms": {
                n: {"value_arcsec": _json_float(v), "sigma_arcsec": _json_float(s),
                    "sigma_honest_arcsec": _json_float(h)}
                for n, v, s, h in zip(names, self.model.values_arcsec, self.sigma_arcsec,
                                      self._honest(), strict=True)
            },
            "sky_rms_arcsec": _json_float(self.sky_rms_arcsec),
            "xel_rms_arcsec": _json_float(self.xel_rms_arcsec),
            "el_rms_arcsec": _json_float(self.el_rms_arcsec),
            "popn_sd_arcsec": _json_float(self.popn_sd_arcsec),
            "condition_number": _json_float(self.condition_number),
            "correlations": {
                "names": names,
                "matrix": [[_json_float(x) for x in row] for row in self.correlation],
            },
            "unconstrained": list(self.unconstrained),
            **({"fixed": list(self.fixed)} if self.fixed else {}),
            **({"notes": list(self.notes)} if self.notes else {}),
            "honest_sigma": {
                "method": self.honest_method(),
                "clusters": int(self.honest_clusters),
                "dof": {n: _json_float(v) for n, v in zip(
                    names, self.honest_dof if self.honest_dof is not None
                    else np.full(len(names), np.nan), strict=True)},
            },
        }

    @property
    def honest_clusters_words(self) -> str:
        """What the honest sigma's jackknife leaves out at a time, in a few words: the
        observations within each time block where the data have times, else each single
        observation (docs/outputs.md, "The honest sigma")."""
        if self.honest_block_s:
            return f"observations within {self.honest_block_s:g} s time blocks"
        return "single observations (the data have no times)"

    def honest_method(self) -> str:
        """How the honest sigma is computed, in words."""
        return ("cluster jackknife (CV3) of the same least-squares coefficients, "
                f"clusters = {self.honest_clusters_words}"
                + (f", variances averaged over {self.honest_phases} block grids "
                   f"shifted by 1/{self.honest_phases} block"
                   if self.honest_block_s and self.honest_phases > 1 else "")
                + (", scaled by the mean variance ratio of replicates that repeat the "
                   "fit's outlier rejection" if self.robust and self.honest_block_s else "")
                + ", times sqrt(dof/(dof-2)) for its Satterthwaite degrees of freedom")

    def _honest(self) -> np.ndarray:
        if self.sigma_honest_arcsec is None:
            return np.full(len(self.names), np.nan)
        return self.sigma_honest_arcsec

    def table(self) -> str:
        """Fixed-width text table of term, value, TPOINT's sigma and the honest sigma
        (arcsec) for humans."""
        width = max([8, *(len(n) for n in self.names)])
        heads = ('value (")', 'sigma (")', 'honest sigma (")')
        lines = [f"{'term':<{width}}  {heads[0]:>12}  {heads[1]:>10}  {heads[2]:>16}"]
        for n, v, s, h in zip(self.names, self.model.values_arcsec, self.sigma_arcsec,
                              self._honest(), strict=True):
            if math.isfinite(s):
                sigma = f"{s:10.4f}  {h:16.4f}" if math.isfinite(h) else f"{s:10.4f}"
            else:
                sigma = f"{'fixed' if n in self.fixed else 'not fitted':>10}"
            lines.append(f"{n:<{width}}  {v:+12.4f}  {sigma}".rstrip())
        return "\n".join(lines)

    def summary(self) -> str:
        """Table plus the TPOINT statistics and the warnings, as printed by ``antsim fit``."""
        how = "robust (LAD, 4x MAD, LSQ, 3x rms, LSQ)" if self.robust else "plain least squares"
        lines = [
            f"model {self.model.name}: {self.n_used} of {self.n_input} observations used, "
            f"{self.n_rejected} rejected; {how}{', weighted' if self.weighted else ''}",
            f"units: {UNITS}; sign: {sign_convention(self.names)}",
            self.table(),
            f"Sky RMS = {self.sky_rms_arcsec:.3f}\"   Popn SD = {self.popn_sd_arcsec:.3f}\"   "
            f"(xel rms {self.xel_rms_arcsec:.3f}\", el rms {self.el_rms_arcsec:.3f}\")",
            f"condition number {self.condition_number:.3g}",
        ]
        if self.sigma_honest_arcsec is not None:
            lines.append(f"honest sigma: {self.honest_method()}; {self.honest_clusters} "
                         "clusters")
            fitted = np.isfinite(self.sigma_arcsec)
            blank = [n for n, ok, h in zip(self.names, fitted, self.sigma_honest_arcsec,
                                           strict=True) if ok and not math.isfinite(h)]
            if blank:
                lines.append(f"honest sigma blank for {', '.join(blank)}: "
                             f"{self.honest_clusters} clusters are too few to estimate it")
        lines += [f"warning: {w}" for w in self.warnings]
        return "\n".join(lines)

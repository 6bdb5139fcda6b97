"""Which extra terms the data support: forward selection by a nested test, confirmed on
held-out data.

Used for the thermal terms of fit T (:mod:`controller.pointing.variants`): the geometric terms
are always fitted; a candidate (a thermal term) enters only when the data support it, by the
rules ``antsim diagnose`` selects by (``antsim.diagnose.select``; the controller cannot import
it, so the rules are restated here):

* each round, every remaining candidate is added to the current model in turn and tested by
  an F test of the drop in chi^2 (1 dof) on the observations the current robust fit keeps,
  each axis' rows weighted by that axis' residual rms (cross-elevation and elevation scatter
  differ); the noise is estimated from the data;
* the candidates are a family: a p-value is multiplied by the number of candidates tested in
  the first round (Bonferroni), and must stay below ``alpha`` (0.005, diagnose's ALPHA);
* the most significant candidate is refused when it correlates with the current model above
  0.95 (TPOINT's "cannot reliably be distinguished"), or when it does not lower the chi^2 of
  held-out data (5 folds interleaved in time); the next is then tried;
* selection stops when no candidate passes.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from .data import PointingData
from .model import PointingModel
from .robust import Equations

__all__ = ["ALPHA", "DISTINGUISH_R", "Selection", "select_terms"]

#: family-wise false-alarm probability (antsim.diagnose.select.ALPHA)
ALPHA = 0.005
#: TPOINT's level: a candidate this correlated with the model cannot be told from it
DISTINGUISH_R = 0.95
FOLDS = 5


@dataclass(frozen=True)
class Step:
    """One candidate's test: its name, F, family p-value, correlation with the model,
    held-out chi^2 without and with it, and whether it was accepted (else ``reason``)."""

    name: str
    f: float
    p_family: float
    r_model: float
    cv_before: float
    cv_after: float
    accepted: bool
    reason: str = ""

    def describe(self) -> str:
        if self.accepted:
            return (f"{self.name} added (F = {self.f:.1f}, family p = {self.p_family:.2g}; "
                    f"held-out chi2 {self.cv_before:.0f} -> {self.cv_after:.0f})")
        return f"{self.name} not added: {self.reason}"


@dataclass(frozen=True)
class Selection:
    """The terms to fit (the base, then the accepted candidates in the candidates' order)
    and every test made, in order."""

    terms: tuple[str, ...]
    accepted: tuple[str, ...]
    steps: tuple[Step, ...]
    n_family: int


def _weighted_rows(data: PointingData, names: Sequence[str], used: np.ndarray,
                   scale: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
    """Design and target of the ``used`` observations, each axis' rows divided by its rms."""
    eq = Equations.of(data, PointingModel(list(names)), weighted=False)
    n = eq.n
    rows = np.concatenate([used, used])
    w = np.concatenate([np.full(n, 1.0 / scale[0]), np.full(n, 1.0 / scale[1])])
    return eq.design[rows] * w[rows, None], eq.target[rows] * w[rows]


def _chi2(a: np.ndarray, y: np.ndarray) -> float:
    coef, *_ = np.linalg.lstsq(a, y, rcond=None)
    r = y - a @ coef
    return float(r @ r)


def _cv_chi2(a: np.ndarray, y: np.ndarray, fold: np.ndarray) -> float:
    """Held-out chi^2: each fold predicted from a fit of the others."""
    total = 0.0
    for k in range(FOLDS):
        test = fold == k
        coef, *_ = np.linalg.lstsq(a[~test], y[~test], rcond=None)
        r = y[test] - a[test] @ coef
        total += float(r @ r)
    return total


def _multiple_r(a: np.ndarray, column: np.ndarray) -> float:
    """How much of ``column`` the columns ``a`` reproduce (multiple correlation)."""
    norm = float(np.linalg.norm(column))
    if norm == 0.0:
        return 1.0
    coef, *_ = np.linalg.lstsq(a, column, rcond=None)
    return min(1.0, float(np.linalg.norm(a @ coef)) / norm)


def select_terms(data: PointingData, base: Sequence[str], candidates: Sequence[str], *,
                 robust: bool = True, fixed: Mapping[str, float] | None = None,
                 alpha: float = ALPHA) -> Selection:
    """Forward selection of ``candidates`` on top of ``base`` (see the module docstring).
    ``fixed`` terms (held values) are taken off the data as the final fit does."""
    from scipy.stats import f as f_dist

    from .fitting import fit_model, without_fixed

    current = list(base)
    remaining = list(candidates)
    steps: list[Step] = []
    accepted: list[str] = []
    n_family = 0
    fixed = {n.strip().upper(): float(v) for n, v in (fixed or {}).items()}
    free_data = without_fixed(data, fixed)
    while remaining:
        fit = fit_model(data, current, robust=robust, fixed=fixed)
        used = np.asarray(fit.used, dtype=bool)
        scale = (max(fit.xel_rms_arcsec, 1e-9), max(fit.el_rms_arcsec, 1e-9))
        free = [n for n in current if not fixed or n not in fixed]
        a0, y = _weighted_rows(free_data, free, used, scale)
        chi0 = _chi2(a0, y)
        tests = []
        for name in remaining:
            a1, _ = _weighted_rows(free_data, [*free, name], used, scale)
            column = a1[:, -1]
            if not np.any(column):
                continue  # the data carry nothing of it (e.g. a sensor that never changed)
            chi1 = _chi2(a1, y)
            dof = y.size - a1.shape[1]
            if dof <= 0 or chi1 <= 0.0:
                continue
            f_value = (chi0 - chi1) / (chi1 / dof)
            tests.append((float(f_dist.sf(max(f_value, 0.0), 1, dof)), f_value, name, a1))
        if not n_family:
            n_family = max(len(tests), 1)
        tests.sort(key=lambda x: x[0])
        chosen = None
        for p, f_value, name, a1 in tests:
            p_family = min(1.0, p * n_family)
            if p_family >= alpha:
                break
            r = _multiple_r(a0, a1[:, -1])
            if r > DISTINGUISH_R:
                steps.append(Step(name, f_value, p_family, r, math.nan, math.nan, False,
                                  f"it and the model cannot reliably be distinguished "
                                  f"(r = {r:.2f})"))
                remaining.remove(name)
                continue
            fold = np.arange(y.size) % (y.size // 2) % FOLDS  # an observation's two rows
            cv0, cv1 = _cv_chi2(a0, y, fold), _cv_chi2(a1, y, fold)
            if not cv1 < cv0:
                steps.append(Step(name, f_value, p_family, r, cv0, cv1, False,
                                  f"significant in-sample but it does not predict held-out "
                                  f"data (held-out chi2 {cv0:.0f} -> {cv1:.0f})"))
                remaining.remove(name)
                continue
            chosen = Step(name, f_value, p_family, r, cv0, cv1, True)
            break
        if chosen is None:
            break
        steps.append(chosen)
        accepted.append(chosen.name)
        current.append(chosen.name)
        remaining.remove(chosen.name)
    ordered = tuple(c for c in candidates if c in accepted)
    return Selection((*base, *ordered), ordered, tuple(steps), n_family)


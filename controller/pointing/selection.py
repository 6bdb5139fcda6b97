"""Which extra terms the data support: forward selection by a nested test, confirmed on
held-out data.

Used for the thermal terms of fit T (:mod:`controller.pointing.variants`): the geometric terms
are always fitted; a candidate enters only when the data support it, by the rules ``antsim
diagnose`` selects by (``antsim.diagnose.select``; the controller cannot import it, so the
rules are restated here). A candidate is one term or a group of terms that enter together
(fit T's structure-sensor terms are one group, its proxies one term each: see
:func:`controller.pointing.variants.thermal_fit` for why):

* each round, every remaining candidate is added to the current model in turn and tested by
  an F test of the drop in chi^2 (as many dof as the candidate has terms) on the
  observations the current robust fit keeps, each axis' rows weighted by that axis' residual
  rms (cross-elevation and elevation scatter differ); the noise is estimated from the data;
* the candidates are a family: a p-value is multiplied by the number of candidates tested in
  the first round (Bonferroni), and must stay below ``alpha`` (0.005, diagnose's ALPHA);
* the most significant candidate is refused when it correlates with the current model above
  0.95 (TPOINT's "cannot reliably be distinguished"), or when it does not lower the chi^2 of
  held-out data (5 folds interleaved in time); the next is then tried. A member of a group
  that the model and the group's other members reproduce above 0.95 leaves the group (a
  step says so), and the rest of the group is tested again;
* a group's terms whose data are all zero (a sensor that never changed) are left out of it;
* selection stops when no candidate passes.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.stats import f as f_dist

from .data import PointingData
from .fitting import fit_model, without_fixed
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
    """One candidate's test: its name (a group's terms joined by "+"), F, family p-value,
    correlation with the model, held-out chi^2 without and with it, whether it was accepted
    (else ``reason``), and its number of terms (the F test's dof)."""

    name: str
    f: float
    p_family: float
    r_model: float
    cv_before: float
    cv_after: float
    accepted: bool
    reason: str = ""
    dof: int = 1

    def describe(self) -> str:
        if self.accepted:
            what = (f"{self.name} added" if self.dof == 1 else
                    f"{self.name.replace('+', ', ')} added together")
            on = "" if self.dof == 1 else f" on {self.dof} dof"
            return (f"{what} (F = {self.f:.1f}{on}, family p = {self.p_family:.2g}; "
                    f"held-out chi2 {self.cv_before:.0f} -> {self.cv_after:.0f})")
        return f"{self.name.replace('+', ', ')} not added: {self.reason}"


@dataclass(frozen=True)
class Selection:
    """The terms to fit (the base, then the accepted candidates in the candidates' order)
    and every test made, in order; ``n_family``: the candidates (groups) of the first round."""

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


def _group(candidate: str | Sequence[str]) -> tuple[str, ...]:
    return (candidate,) if isinstance(candidate, str) else tuple(candidate)


def select_terms(data: PointingData, base: Sequence[str],
                 candidates: Sequence[str | Sequence[str]], *, robust: bool = True,
                 fixed: Mapping[str, float] | None = None, alpha: float = ALPHA) -> Selection:
    """Forward selection of ``candidates`` (a term, or a sequence of terms that enter
    together) on top of ``base`` (see the module docstring). ``fixed`` terms (held values)
    are taken off the data as the final fit does."""
    current = list(base)
    remaining = [_group(c) for c in candidates]
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
        n0 = a0.shape[1]
        chi0 = _chi2(a0, y)
        tests = []
        for group in remaining:
            a1, _ = _weighted_rows(free_data, [*free, *group], used, scale)
            # the data carry nothing of a term whose column is all zero (a sensor that never
            # changed): the group is tested without it
            live = [j for j in range(len(group)) if np.any(a1[:, n0 + j])]
            if not live:
                continue
            if len(live) < len(group):
                a1 = np.concatenate([a0, a1[:, [n0 + j for j in live]]], axis=1)
            chi1 = _chi2(a1, y)
            dof = y.size - a1.shape[1]
            if dof <= 0 or chi1 <= 0.0:
                continue
            k = len(live)
            f_value = (chi0 - chi1) / k / (chi1 / dof)
            tests.append((float(f_dist.sf(max(f_value, 0.0), k, dof)), f_value, group,
                          tuple(group[j] for j in live), a1))
        if not n_family:
            n_family = max(len(tests), 1)
        tests.sort(key=lambda x: x[0])
        chosen = None
        regroup = False
        for p, f_value, group, terms, a1 in tests:
            p_family = min(1.0, p * n_family)
            if p_family >= alpha:
                break
            k, label = len(terms), "+".join(terms)
            # each term against the model and the group's other terms (a single term: the model)
            r_each = [_multiple_r(a0 if k == 1 else np.delete(a1, n0 + j, axis=1), a1[:, n0 + j])
                      for j in range(k)]
            worst = int(np.argmax(r_each))
            r = r_each[worst]
            if r > DISTINGUISH_R and k > 1:
                steps.append(Step(terms[worst], f_value, p_family, r, math.nan, math.nan, False,
                                  f"left the group {label.replace('+', ', ')}: the model and "
                                  f"the group's other terms reproduce it (r = {r:.2f})"))
                remaining[remaining.index(group)] = tuple(t for t in group if t != terms[worst])
                regroup = True
                break
            if r > DISTINGUISH_R:
                steps.append(Step(label, f_value, p_family, r, math.nan, math.nan, False,
                                  f"it and the model cannot reliably be distinguished "
                                  f"(r = {r:.2f})"))
                remaining.remove(group)
                continue
            fold = np.arange(y.size) % (y.size // 2) % FOLDS  # an observation's two rows
            cv0, cv1 = _cv_chi2(a0, y, fold), _cv_chi2(a1, y, fold)
            if not cv1 < cv0:
                steps.append(Step(label, f_value, p_family, r, cv0, cv1, False,
                                  f"significant in-sample but it does not predict held-out "
                                  f"data (held-out chi2 {cv0:.0f} -> {cv1:.0f})", k))
                remaining.remove(group)
                continue
            chosen = (Step(label, f_value, p_family, r, cv0, cv1, True, dof=k), group, terms)
            break
        if regroup:
            continue
        if chosen is None:
            break
        steps.append(chosen[0])
        accepted.extend(chosen[2])
        current.extend(chosen[2])
        remaining.remove(chosen[1])
    order = [t for c in candidates for t in _group(c)]
    ordered = tuple(t for t in order if t in accepted)
    return Selection((*base, *ordered), ordered, tuple(steps), n_family)

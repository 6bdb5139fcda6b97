"""The cross-validated selection stage, for data without a noise prediction (TPOINT files,
recordings diagnosed without a scenario).

The significance tests of :mod:`.select` estimate the noise from the residuals. Once they
have shown a mismatch (at least one finding), those residuals still hold whatever else the
model leaves out, and the tests lose power exactly where it matters; a further effect is
then judged by prediction instead. Forward, the stage adds the library's linear
candidate (each order of a family, each value of a nonlinear parameter, as a separate
option; none that the model mimics, r > 0.95, whose size prediction cannot fix) that most
lowers the held-out Sky RMS of an unweighted fit of the raw errors
(TPOINT's statistic), while it lowers the held-out losses by more than one standard error
of their paired mean (:data:`MARGIN_T`), up to :data:`MAX_FINDINGS_CV` findings in all.
Held out: :data:`K_FOLDS` contiguous blocks of the observations in time order (a TPOINT
file's order, which is the order they were taken): errors of neighbouring observations are
correlated (the same source, the same weather), and leaving one out at a time lets its
neighbours vouch for a term that only fits them (measured on held-out-style TPOINT files:
twice the spurious additions of contiguous blocks). Without a significant finding the stage
adds nothing: data the model explains stay silent, and the false-alarm rate is that of the
significance tests.

The closed-form leave-one-star-out statistics (each star's two rows together) serve the
benchmarks that cross-validate whole procedures (``benchmarks/blind.py --real --nested``).
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
import scipy.linalg

from .candidates.base import DISTINGUISH_R, Candidate, TestResult, p_value, with_trials
from .linalg import (
    HELDOUT_MIN_EIG,
    added_basis,
    economic_qr,
    heldout_lstsq,
    lstsq,
    qt_dot,
    rows_fortran,
)
from .problem import Problem

__all__ = ["MAX_FINDINGS_CV", "contiguous_folds", "heldout_losses", "heldout_sky_rms",
           "loo_blocks", "loo_residuals", "loo_rms", "mimicked", "orthonormal"]

#: findings in all (significant and cross-validated) for data without a noise prediction
MAX_FINDINGS_CV = 4
#: a cross-validated finding must lower the held-out losses (paired, per observation) by
#: this many standard errors of their mean: a guard against options that win by a hair.
#: Measured with contiguous blocks (``benchmarks/blind.py --real --nested`` for AuxTel, and
#: ``--tpoint`` for the extra findings of 32 single-effect held-out-style TPOINT files): at
#: 0 the AuxTel procedure cross-validates at 10.26" with 55 extra findings, at 0.5 10.26"
#: and 44, at 1.0 10.37" and 22 (the automatic 22-term search: 11.11"); leaving one star
#: out instead, 0.5 gave 10.39" and 86 (all measured while options the model mimics were
#: still allowed; without them, at 1.0: 10.99", benchmarks/blind.py --real --nested)
MARGIN_T = 1.0
#: held-out blocks of the cross-validated stage
K_FOLDS = 5


def orthonormal(x: np.ndarray) -> np.ndarray | None:
    """An orthonormal basis of the columns of ``x`` (QR), or None when they are not
    independent (a column in the span of the others)."""
    if x.shape[1] == 0:
        return x
    q, r = np.linalg.qr(x)
    diag = np.abs(np.diag(r))
    return None if diag.min() < 1e-8 * max(diag.max(), 1e-300) else q


def loo_blocks(q: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-observation 2x2 blocks (xel-xel, el-el, xel-el) of the hat matrix q q^T (rows
    stacked as n xel rows, then n el rows)."""
    return (np.einsum("ij,ij->i", q[:n], q[:n]), np.einsum("ij,ij->i", q[n:], q[n:]),
            np.einsum("ij,ij->i", q[:n], q[n:]))


def loo_residuals(h: tuple, e: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray] | None:
    """Each star's held-out (xel, el) residuals of a least-squares fit from its residuals
    ``e`` (2n,) and hat-matrix blocks ``h``: (I - H_ii)^-1 e_i, exactly what refitting
    without its two rows gives; None when a star alone determines a term."""
    a, d, b = 1.0 - h[0], 1.0 - h[1], -h[2]
    det = a * d - b * b
    if np.any(det < 1e-9):
        return None
    return (d * e[:n] - b * e[n:]) / det, (a * e[n:] - b * e[:n]) / det


def loo_rms(h: tuple, e: np.ndarray, n: int) -> float:
    """Leave-one-star-out Sky RMS from :func:`loo_residuals` (inf where it has none)."""
    r = loo_residuals(h, e, n)
    return math.inf if r is None else math.sqrt(float(np.mean(r[0] ** 2 + r[1] ** 2)))


def heldout_losses(x: np.ndarray | tuple[np.ndarray, ...], y: np.ndarray, used: np.ndarray,
                   folds: np.ndarray | None, basis: tuple | None = None) -> np.ndarray:
    """Squared held-out residual (xel^2 + el^2, arcsec^2) of each ``used`` observation under
    an unweighted fit of ``y`` (2n,) on ``x`` (2n, k; or a tuple of column blocks, stacked
    only if the closed form fails): each left out in turn (``folds`` None, closed form) or
    each fold predicted from the others (closed form, :func:`heldout_lstsq`, with the used
    rows' ``basis`` of ``x`` when given: (Q or its column blocks, |diag R|)). Infinite where
    an observation alone determines a term."""
    n = used.size
    rows = np.concatenate([used, used])
    if folds is None:
        m = int(used.sum())
        q = orthonormal(_design(x)[rows])
        if q is None:
            return np.full(m, np.inf)
        yy = y[rows]
        r = loo_residuals(loo_blocks(q, m), yy - q @ (q.T @ yy), m)
        return np.full(m, np.inf) if r is None else r[0] ** 2 + r[1] ** 2
    lab = folds[used]
    # with the basis given the fit needs no copy of the design's rows
    r = heldout_lstsq(None if basis is not None else _design(x)[rows], y[rows],
                      np.concatenate([lab, lab]), basis)
    if r is not None:
        r = r.reshape(2, -1)
        return r[0] ** 2 + r[1] ** 2
    x = _design(x)
    out = np.zeros(n)
    for k in np.unique(folds[used]):
        test = used & (folds == k)
        train = used & (folds != k)
        coef, _ = lstsq(x[np.concatenate([train, train])], y[np.concatenate([train, train])])
        r = (y - x @ coef).reshape(2, n)
        out[test] = r[0, test] ** 2 + r[1, test] ** 2
    return out[used]


def _design(x) -> np.ndarray:
    """A design given as its columns' blocks (stacked here, only when needed) or whole."""
    return np.column_stack(x) if isinstance(x, tuple) else x


def heldout_sky_rms(x: np.ndarray, y: np.ndarray, used: np.ndarray,
                    folds: np.ndarray | None) -> float:
    """Held-out Sky RMS (arcsec) of :func:`heldout_losses`."""
    return math.sqrt(float(np.mean(heldout_losses(x, y, used, folds))))


def improves(now: np.ndarray, new: np.ndarray) -> bool:
    """Whether held-out losses ``new`` beat ``now`` by more than their scatter allows: the
    mean paired improvement exceeds ``MARGIN_T`` times its standard error."""
    d = now - new
    if not np.all(np.isfinite(d)) or d.size < 3:
        return False
    se = float(np.std(d, ddof=1)) / math.sqrt(d.size)
    return float(np.mean(d)) > MARGIN_T * se


def contiguous_folds(t_s: np.ndarray, k: int) -> np.ndarray:
    """Fold labels 0..k-1: ``k`` contiguous blocks of (nearly) equal size in time order."""
    n = t_s.size
    order = np.argsort(t_s, kind="stable")
    folds = np.empty(n, dtype=int)
    folds[order] = (np.arange(n) * k) // max(n, 1)
    return folds


def mimicked(problem: Problem, raw: np.ndarray, rows: np.ndarray | None = None) -> bool:
    """Whether the current model mimics any of the raw columns (2n, q) above
    ``DISTINGUISH_R`` over the used scans (its correlation with the model's span).
    ``rows``: the columns' used rows [xel; el] when the caller has them (white noise: the
    whitened columns are those rows times their weights, as :meth:`Problem.whiten` makes them)."""
    whitened = problem.whiten(raw) if rows is None else rows * problem.weights()[:, None]
    q = problem.basis()
    full2 = np.einsum("ij,ij->j", whitened, whitened)
    # the squared norm of the part in the model's span (q orthonormal): r^2 without
    # forming the projection off it (2 n_used x q floats per option)
    inside = qt_dot(q, whitened)
    with np.errstate(invalid="ignore", divide="ignore"):
        r2 = np.where(full2 > 0, np.einsum("ij,ij->j", inside, inside) / full2, 1.0)
    return bool(np.any(r2 > DISTINGUISH_R**2))


def _cv_thetas(problem: Problem, candidates: Sequence[Candidate],
               taken: set[str]) -> list[tuple[Candidate, list]]:
    """Each linear candidate not yet taken with the parameter values the stage tries."""
    return [(c, c.cv_thetas(problem)) for c in candidates
            if c.kind == "offsets" and c.linear_signature and c.name not in taken]


def _options(problem: Problem, thetas: list[tuple[Candidate, list]], model_terms: set[str],
             idx: np.ndarray | None) -> Iterator[Option]:
    """Every linear option not yet in the model and not mimicked by it (:func:`mimicked`;
    ``idx``: the used rows, gathered once for both, white noise only; None: not gathered).
    Only a significance test can accept a term the model mimics (its size is then set by
    the terms it is confused with, and prediction cannot tell it from a change of theirs):
    on the AuxTel file the stage would otherwise add HESE2/HECE2 at 1744" (r = 1.00 with
    IE, TF, TX), which predicts held-out stars better (the procedure's leave-one-star-out
    Sky RMS 10.37" with it, benchmarks/blind.py --real --nested) but measures nothing."""
    obs = problem.obs
    for c, values in thetas:
        for theta in values:
            cols, names = c.columns(obs, theta)
            if set(names) <= model_terms:
                continue
            rows = None if idx is None else cols.take(idx, axis=0)
            if mimicked(problem, cols, rows):
                continue
            yield Option(c, theta, cols, names, rows)


@dataclass
class CrossValidated:
    """A finding of the cross-validated stage: its test, the held-out and in-sample Sky RMS
    (arcsec) of the model before and after it, and its fitted signal (2n, arcsec)."""

    result: TestResult
    heldout_sky_rms_before: float
    heldout_sky_rms_after: float
    sky_rms_before: float
    sky_rms_after: float
    signal: np.ndarray


class Option(NamedTuple):
    """A linear option of the stage: a candidate at one shape, its raw columns (2n, q),
    their names and, where the caller gathered them, their used rows."""

    candidate: Candidate
    theta: Any
    raw: np.ndarray
    names: tuple[str, ...]
    rows: np.ndarray | None


class Ranked(NamedTuple):
    """An option by its summed held-out losses (arcsec^2)."""

    total: float
    candidate: Candidate
    theta: Any
    names: tuple[str, ...]


class Best(NamedTuple):
    """The option the stage would add: its held-out losses per observation (arcsec^2)."""

    losses: np.ndarray
    candidate: Candidate
    theta: Any
    raw: np.ndarray
    names: tuple[str, ...]


def cv_stage(problem: Problem, candidates: Sequence[Candidate], taken: set[str],
             model_terms: set[str], room: int, signal_of) -> list[CrossValidated]:
    """Up to ``room`` cross-validated findings (see the module docstring), added to
    ``problem`` (``signal_of(problem, the model's columns before, the result's columns)``:
    the finding's fitted signal once it is added)."""
    folds = contiguous_folds(problem.obs.t_s, K_FOLDS)
    out = []
    while len(out) < room:
        # before the round's basis: a step's change time comes from O(n k) sums over every
        # scan, not held beside q0 (200,000 scans: ~40 MB each)
        thetas = _cv_thetas(problem, candidates, taken)
        cur = problem.current_columns()
        # the model's basis over the used rows once; each option adds its columns to it
        rows = problem.rows()
        q0, r0 = economic_qr(rows_fortran(cur, rows), overwrite=True)
        d0 = np.abs(np.diag(r0))
        now = heldout_losses(cur, problem.y_raw, problem.used, folds, (q0, d0))
        idx = np.flatnonzero(rows)
        sums = FoldSums(q0, d0, problem.y_raw[rows],
                        np.concatenate([folds[problem.used]] * 2), idx)
        # each option's used rows gathered once (white noise, the folds' rows in place): for
        # the mimicry check and, times the offset scale where it is not 1 (as cand() makes
        # the columns), for the sums
        share = problem.white() and sums.idx is idx
        f2 = None if problem.unscaled else np.concatenate(
            [problem.offset_scale, problem.offset_scale])[idx, None]
        ranked = []
        for option in _options(problem, thetas, model_terms, idx if share else None):
            if option.rows is None:
                total = sums.total(problem.cand(option.raw))
            else:
                total = sums.total_rows(option.rows if f2 is None else option.rows * f2)
            if total is None:  # degenerate there: the per-option losses say it
                total = float(_losses(problem, cur, q0, d0, folds, option.raw).sum())
            ranked.append(Ranked(total, option.candidate, option.theta, option.names))
        del sums
        tried = len(ranked)
        best = _best(problem, cur, q0, d0, folds, ranked)
        # the model's unweighted basis (2 n_used x m floats): not beside the test's factor
        # and the whole-design fits below
        del q0, r0
        if best is None or not improves(now, best.losses):
            break
        c = best.candidate
        perp, z_perp = problem.perp_for(problem.used)
        res = _tested(problem, c, best.theta, best.raw, best.names, perp, z_perp, tried)
        if not res.testable:
            break
        sky_before = problem.sky_rms()
        taken.add(c.name)
        model_terms |= set(res.comp_names)
        extra = res.columns  # read once (a result may make its columns again when read)
        signal = signal_of(problem, problem.add(c.name, extra, res.comp_names), extra)
        del extra
        problem.update_outliers()
        out.append(CrossValidated(res, math.sqrt(float(np.mean(now))),
                                  math.sqrt(float(np.mean(best.losses))), sky_before,
                                  problem.sky_rms(), signal))
    return out


#: options whose summed held-out losses (from :class:`FoldSums`) lie within this fraction of
#: the least are told apart by their losses computed in full (:func:`heldout_losses`), in the
#: order tried: the sums agree with those to rounding (~1e-15 relative; tests/
#: test_diagnose.py), so the choice is the one the full losses make
TIE_RTOL = 1e-9


def _losses(problem: Problem, cur: np.ndarray, q0: np.ndarray, d0: np.ndarray,
            folds: np.ndarray, raw: np.ndarray) -> np.ndarray:
    """:func:`heldout_losses` of the model plus the option's raw columns, from the model's
    basis ``q0`` (|diag R| ``d0``) over the used rows."""
    x = problem.cand(raw)
    q, d1 = added_basis(q0, x[problem.rows()])  # (q0, the option's block): q0 not copied
    return heldout_losses((cur, x), problem.y_raw, problem.used, folds,
                          (q, np.concatenate([d0, d1])))


def _best(problem: Problem, cur: np.ndarray, q0: np.ndarray, d0: np.ndarray,
          folds: np.ndarray, ranked: list[Ranked]) -> Best | None:
    """The option with the least summed held-out losses (the first of equals, as tried),
    or None without options: the sums rank, the full losses decide among those within
    :data:`TIE_RTOL` of the least."""
    if not ranked:
        return None
    least = min(r.total for r in ranked)
    best = None
    for total, c, theta, names in ranked:
        if not total <= least + TIE_RTOL * abs(least):
            continue
        raw, _ = c.columns(problem.obs, theta)
        new = _losses(problem, cur, q0, d0, folds, raw)
        if best is None or new.sum() < best.losses.sum():
            best = Best(new, c, theta, raw, names)
    return best


class FoldSums:
    """The summed held-out losses of :func:`heldout_losses` (contiguous folds) of the model
    plus one option at a time, from small per-fold matrices. With Q = [q0, q1] an orthonormal
    basis of the model (q0, fixed for the round) and the option (q1), e the full fit's
    residual and S a fold's rows, the held-out residual is r_S = e_S + Q_S u with
    u = (I - Q_S^T Q_S)^-1 Q_S^T e_S (:func:`heldout_lstsq`), so
    |r_S|^2 = |e_S|^2 + 2 u.(Q_S^T e_S) + u.(Q_S^T Q_S) u, and e = e0 - q1 (q1^T e0) (e0 the
    model's residual). The option's columns x enter through q1 = (x - q0 C) L^-T
    (C = q0^T x, L L^T the Cholesky factor of their part off q0), so every fold's matrices
    follow from [q0, e0, x]_S^T x_S: one pass over the rows per option, what depends on the
    model alone formed once per round. The sums rank the options (:func:`_best`); they are
    the full losses' sums to rounding, and None where rounding could matter or the full
    losses take another path (a model or an option whose columns are nearly dependent, a
    fold that nearly determines a direction)."""

    #: an option whose part off the model keeps less than this of a column's squared norm,
    #: or whose Cholesky factor is this ill-conditioned, is left to the full losses (the
    #: Gram matrices' rounding grows as the inverse of it: 1e-16 / 1e-4 stays far below
    #: :data:`TIE_RTOL`)
    MIN_OFF = 1e-4

    #: where the folds' rows make this many runs or more (scans not in time order), they are
    #: grouped by fold in a copy of the model's basis; below, the basis is read in place
    MAX_RUNS = 64

    def __init__(self, q0: np.ndarray, d0: np.ndarray, y: np.ndarray, labels: np.ndarray,
                 rows: np.ndarray):
        """``q0`` (2 n_used, k0; |diag R| ``d0``) and ``y`` over the used rows ``rows``
        (indices of the 2n rows), ``labels`` their folds."""
        # the full losses refit fold by fold where the model's columns are dependent
        # (heldout_lstsq's rule): no sums then
        self.d0max = float(d0.max()) if d0.size else 0.0
        self.dependent = bool(d0.size) and float(d0.min()) <= 1e-10 * max(self.d0max, 1e-300)
        e0 = y - q0 @ (q0.T @ y)
        cut = np.flatnonzero(np.diff(labels)) + 1
        if cut.size >= self.MAX_RUNS:
            # rows of a fold scattered (scans not in time order): grouped by fold in a copy
            order = np.argsort(labels, kind="stable")
            q = np.empty(q0.shape, order="F")
            for j in range(q0.shape[1]):  # a column at a time: np.take buffers a strided out
                np.take(q0[:, j], order, out=q[:, j], mode="clip")  # order: a permutation
            q0, e0, labels, rows = q, e0[order], labels[order], rows[order]
            cut = np.flatnonzero(np.diff(labels)) + 1
        # q0 as given where each fold is a few runs of rows (scans in time order: one run per
        # fold and axis), not a copy of it grouped by fold
        self.q0, self.e0, self.idx = q0, e0, rows
        self.k0 = q0.shape[1]
        self.folds: dict[int, list[slice]] = {}
        for a, b in zip(np.r_[0, cut], np.r_[cut, y.size], strict=True):
            self.folds.setdefault(int(labels[a]), []).append(slice(int(a), int(b)))
        self.grams = [sum(self._gram(s) for s in runs)
                      for runs in self.folds.values()]

    def _gram(self, s: slice) -> np.ndarray:
        """[q0, e0]^T [q0, e0] over the rows ``s`` (from its blocks: no stacked copy)."""
        q, e = self.q0[s], self.e0[s]
        qe = (q.T @ e)[:, None]
        return np.block([[q.T @ q, qe], [qe.T, np.array([[e @ e]])]])

    def _products(self, s: slice, x: np.ndarray) -> np.ndarray:
        """[q0, e0]^T x over the rows ``s`` (x: those rows)."""
        return np.vstack([self.q0[s].T @ x, self.e0[s] @ x])

    def total(self, x: np.ndarray) -> float | None:
        """Summed held-out losses with the option's columns ``x`` (2n, q) added; None where
        the full losses must say it (see the class docstring)."""
        if self.dependent:
            return None
        return self.total_rows(x.take(self.idx, axis=0))

    def total_rows(self, xg: np.ndarray) -> float | None:
        """:meth:`total` from the columns' rows ``xg`` (x's rows ``idx``, in that order)."""
        if self.dependent:
            return None
        k0 = self.k0
        wx = [(sum(self._products(s, xg[s]) for s in runs), sum(xg[s].T @ xg[s] for s in runs))
              for runs in self.folds.values()]
        c0 = sum(a[:k0] for a, _ in wx)  # q0^T x
        xx = sum(g for _, g in wx)
        off = xx - c0.T @ c0  # (x - q0 C)^T (x - q0 C)
        if not np.all(np.diag(off) > self.MIN_OFF * np.diag(xx)):
            return None
        try:
            chol = np.linalg.cholesky(off)
        except np.linalg.LinAlgError:
            return None
        dl = np.diag(chol)  # the option's |diag R| off the model, to rounding
        if dl.min() <= self.MIN_OFF * max(float(dl.max()), self.d0max):
            return None
        inv = scipy.linalg.solve_triangular(chol, np.eye(dl.size), lower=True)  # L^-1
        xe = sum(a[k0] for a, _ in wx)  # x^T e0 (q0^T e0 = 0)
        c = inv @ xe  # q1^T e0
        k = k0 + dl.size
        total = 0.0
        for (a, g), g0 in zip(wx, self.grams, strict=True):
            g00, g0e, gee = g0[:k0, :k0], g0[:k0, k0], g0[k0, k0]
            p0 = (a[:k0] - g00 @ c0) @ inv.T  # q0_S^T q1_S
            pe = (a[k0] - g0e @ c0) @ inv.T  # e0_S^T q1_S
            m = g - c0.T @ a[:k0]
            p1 = inv @ (m - a[:k0].T @ c0 + c0.T @ g00 @ c0) @ inv.T  # q1_S^T q1_S
            gram = np.block([[g00, p0], [p0.T, p1]])
            b = np.concatenate([g0e - p0 @ c, pe - p1 @ c])
            ee = gee - 2.0 * float(pe @ c) + float(c @ p1 @ c)
            w, v = np.linalg.eigh(np.eye(k) - gram)
            if w.min() < HELDOUT_MIN_EIG:
                return None
            u = v @ ((v.T @ b) / w)
            total += ee + 2.0 * float(u @ b) + float(u @ gram @ u)
        return total


def _tested(problem: Problem, c: Candidate, theta, raw: np.ndarray, names: tuple[str, ...],
            perp, z_perp: np.ndarray, tried: int) -> TestResult:
    """The option's added-variable test, its parameters and its p-value with the
    look-elsewhere effect of every option tried."""
    res = c.linear_test(problem, perp, z_perp, raw, tuple(names), theta)
    if res.testable:
        res.trials = float(tried)
        res.p = with_trials(p_value(problem, res.delta_chi2, res.dof, res.chi2_now, res.mask),
                            res.trials)
        c.finish(problem, res)
    return res


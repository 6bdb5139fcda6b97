"""The decision: which findings the data support, as one cheap function of a set of scans.

:func:`decide` is the whole of diagnose's choice of findings. It runs on the file's scans and
again, unchanged, inside every fold of the nested validation and on every resample of the
stability check (:mod:`.crossval`), so it is cheap by design rather than by machinery: a
:class:`Design` computes every candidate's shapes ("options": a harmonic family's orders, a
time constant's grid, a source, a change time) as columns once per file and whitens them
once, and a decision on any set of scans (a weight per scan: 0 or 1 for a fold, a count for
a bootstrap resample) is small linear algebra on those rows. No candidate is asked
anything during a decision and nothing is simulated.

Whitening: each row (a scan's cross-axis or second-axis error) is divided by its predicted
noise; where the noise is correlated in time (as a scenario's simulations predict it, or as
the residuals of recordings without one show it), the rows of each axis are decorrelated
once, over the design's scans, by the inverse Cholesky factor of their correlation, and a
set of scans is then a set of independent rows. Without a noise prediction each axis'
noise level is estimated from the residuals, as :mod:`.problem` does.

The rule, round by round (forward selection, as docs/diagnose.md states it):

1. **Outliers.** A scan whose residual exceeds ``OUTLIER_Z`` times its noise on either axis
   is left out (twice, from every scan of the set, after every change of the model). An
   option that lives mostly on the scans left out (``READMIT_FRACTION``) is also tested on
   the scans a model with it keeps, as a candidate's own test is.
2. **Each option's test.** Its columns projected off the current model (the added-variable
   test: what the model cannot absorb; a column with less than ``ABSORBED_1MR2`` of its
   square norm left is absorbed and not counted); the chi^2 decrease of fitting the rest,
   its parameters the degrees of freedom: a chi^2 test with a noise prediction, an F test
   with the noise estimated from the residuals.
3. **Each candidate's p-value.** Its best option's, with its look-elsewhere effect
   (:attr:`.candidates.base.Candidate.look_elsewhere`): the number of its shapes (a family's
   orders, the sources), the effective number of independent shapes of a grid (Nyholt
   2004), the tube formula for a change at an unknown time (Davies 1987); then Bonferroni
   over the candidates tested (``n_family``): the family's false-alarm probability is
   ``ALPHA``, and a finding needs at least ``sigma_from_p(ALPHA)`` = 2.58 sigma.
4. **The round's choice.** The most significant candidate below ``ALPHA``, or a simpler one
   (fewer parameters, itself below ``ALPHA``) that is part of its terms while the rest is
   not significant, or that the data cannot tell from it (fitted signatures correlated above
   0.95) and that explains as much (each parameter it lacks would add at most Akaike's 2 of
   chi^2).
5. **The parameters the data carry.** The model's parameters never exceed a fifth of the
   numbers fitted (``NUMBERS_PER_PARAMETER``: two per scan).
6. **Stops.** No candidate below ``ALPHA``; the next would exceed the parameters the data
   carry; the residuals match the predicted noise on both axes (chi^2 p > 0.05; with a
   noise prediction only); ``MAX_FINDINGS``.

Above ``DECIDE_SCANS`` scans the design holds every k-th scan in time (a cheap decision at
scale): the findings' parameters, the Sky RMS and the model are still made from every scan
(:mod:`.select`, :mod:`.core`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import pvalues
from .candidates.base import ABSORBED_1MR2, DISTINGUISH_R, Candidate, nyholt_gram, with_trials
from .candidates.changes import tube_trials
from .candidates.terms import TermsCandidate
from .linalg import economic_qr
from .problem import OUTLIER_Z, Problem

__all__ = ["ALPHA", "DECIDE_SCANS", "MAX_FINDINGS", "NUMBERS_PER_PARAMETER", "Design",
           "Option", "Path", "Pick", "decide", "parameter_bound", "sigma_from_p"]

#: the family-wise false-alarm probability of a decision (2.58 sigma one-sided)
ALPHA = 0.005
#: findings at most, whatever the data carry
MAX_FINDINGS = 5
#: numbers fitted per parameter at least: with p parameters fitted to N numbers, least
#: squares' expected held-out error exceeds its in-sample error by (N + p) / (N - p); at
#: N / p = 5 that is 1.5, and beyond it the held-out figures that judge a finding become as
#: noisy as the gains they judge
NUMBERS_PER_PARAMETER = 5
#: scans a design holds at most (every k-th scan in time above it)
DECIDE_SCANS = 5000
#: a simpler form "explains as much" when each parameter it lacks would add at most this
#: much chi^2 (Akaike's 2)
AKAIKE_PER_PARAMETER = 2.0
#: the residuals "match the predicted noise" above this chi^2 p-value on both axes
MATCH_P = 0.05
#: an option with at least this fraction of its signature's square norm on the scans the
#: model rejects is also tested on the scans a model with it keeps (more than half: it lives
#: there, as a source offset whose every scan is an outlier of the model without it)
READMIT_FRACTION = 0.5
#: below this correlation of successive scans an outlier leaks less than a fifth of itself
#: into the next scan's decorrelated row: the design keeps it (a decision rejects it)
WEAK_CORRELATION = 0.2
#: a scan within this of the one before it on the sky repeats it (deg)
REPEAT_DEG = 1.0


def sigma_from_p(p: float, log_p: float | None = None) -> float:
    """One-sided Gaussian equivalent of a p-value (handles underflow through log p); 0 for
    p >= 0.5 (no evidence at all)."""
    if log_p is None:
        log_p = math.log(p) if p > 0 else -745.0
    if log_p > -700:
        return max(0.0, float(pvalues.norm_isf(math.exp(log_p))))
    x = -2.0 * log_p
    return float(math.sqrt(max(x - math.log(x) - math.log(2 * math.pi), 0.0)))


def parameter_bound(n_scans: float) -> int:
    """The parameters ``n_scans`` scans carry (two numbers each): the rule of
    :data:`NUMBERS_PER_PARAMETER`."""
    return int(2.0 * n_scans // NUMBERS_PER_PARAMETER)


@dataclass(frozen=True)
class Option:
    """One candidate at one shape: its columns in the design, and their names."""

    candidate: Candidate
    theta: Any
    cols: slice
    names: tuple[str, ...]

    @property
    def q(self) -> int:
        return self.cols.stop - self.cols.start

    @property
    def label(self) -> str:
        return self.candidate.label(self.theta)


@dataclass(frozen=True)
class Group:
    """A candidate's options (indices into :attr:`Design.options`)."""

    candidate: Candidate
    options: tuple[int, ...]


class Design:
    """Every candidate's options as whitened columns over the design's scans, made once per
    file (see the module docstring).

    Rows are [cross-axis rows of the scans; second-axis rows], scans in the order of
    ``scans`` (indices into the problem's observations). ``a``, ``x``, ``z``: the base
    columns, the options' columns and the data, whitened with unit noise scale; ``a_raw``,
    ``x_raw``, ``y``: the same raw (arcsec; the data less the predicted systematic residual)
    for Sky RMS; ``sigma``: the predicted noise per row (arcsec).
    """

    def __init__(self, problem: Problem, candidates: list[Candidate] | tuple[Candidate, ...],
                 n_family: int):
        obs = problem.obs
        self.problem = problem
        self.white = not problem.pred.known_noise
        #: the noise is correlated in time (predicted, or estimated from the residuals)
        self.correlated = bool(problem.pred.corr_xel or problem.pred.corr_el)
        # every valid scan (a decision rejects its own outliers: a source whose every scan
        # is an outlier of the base model is found by the offset that readmits them), but
        # where the noise is strongly correlated: the scans the base model keeps (an outlier
        # would spread through the decorrelated rows of the scans after it, by the
        # correlation times its size)
        strong = _successive_correlation(problem) > WEAK_CORRELATION
        mask = (problem.used if strong else problem.valid).copy()
        self.n_file = int(mask.sum())
        if self.n_file > DECIDE_SCANS:
            every = -(-self.n_file // DECIDE_SCANS)
            idx = np.flatnonzero(mask)
            idx = idx[np.argsort(obs.t_s[idx], kind="stable")][::every]
            mask = np.zeros_like(mask)
            mask[idx] = True
        self.mask = mask
        self.scans = np.flatnonzero(mask)
        self.u = u = self.scans.size
        self.n_family = max(int(n_family), 1)
        rows = np.concatenate([self.scans, self.scans + problem.n])
        sub = obs.select(mask)
        f2 = np.concatenate([problem.offset_scale[mask], problem.offset_scale[mask]])
        options: list[Option] = []
        groups: list[Group] = []
        blocks: list[np.ndarray] = []
        k = 0
        for c in candidates:
            mine = []
            for theta, cols, names in c.options(sub):
                if cols.shape[1] == 0:
                    continue
                blocks.append(cols * f2[:, None])
                options.append(Option(c, theta, slice(k, k + cols.shape[1]), tuple(names)))
                mine.append(len(options) - 1)
                k += cols.shape[1]
            if mine:
                groups.append(Group(c, tuple(mine)))
        self.options = options
        self.groups = groups
        self.a_raw = np.ascontiguousarray(problem.base[rows])
        self.x_raw = np.hstack(blocks) if blocks else np.zeros((2 * u, 0))
        self.y = problem.y[rows].copy()
        self.sigma = problem.sigma[rows].copy()
        self.a = self._whiten(self.a_raw)
        self.x = self._whiten(self.x_raw)
        self.z = self._whiten(self.y)
        self.m = self.a.shape[1]
        #: the time order of the design's scans (folds in time are runs of it)
        self.order = np.argsort(obs.t_s[self.scans], kind="stable")
        #: repeats: runs of scans in time order that point within REPEAT_DEG of the one
        #: before (the same star measured again): a fold or a resample takes them together
        self.group = _repeats(obs.az_rad[self.scans], obs.el_rad[self.scans], self.order)
        self.option_names = [o.label for o in options]
        # what the base model keeps of every scan and its noise scale: the scans the
        # held-out losses are taken over, and the scale they are measured in
        base = decide_base(self, np.ones(u))
        self.kept0 = base.active
        self.scale0 = base.scale

    def _whiten(self, v: np.ndarray) -> np.ndarray:
        """Raw rows ``v`` (2u[, k]) divided by their predicted noise and, where the noise is
        correlated, decorrelated per axis over the design's scans."""
        p = self.problem
        vv = v[:, None] if v.ndim == 1 else v
        with np.errstate(divide="ignore"):
            w = np.where(self.sigma > 0, 1.0 / self.sigma, 0.0)
        out = vv * w[:, None]
        if self.correlated:
            for axis, factor in enumerate(p.factors.noise_factors(self.mask)):
                if factor is not None:
                    sl = slice(axis * self.u, (axis + 1) * self.u)
                    out[sl] = factor @ out[sl]
        return out[:, 0] if v.ndim == 1 else np.ascontiguousarray(out)

    def columns(self, options: list[int] | tuple[int, ...]) -> list[int]:
        """The design's columns of ``options`` (indices), in order."""
        out: list[int] = []
        for j in options:
            s = self.options[j].cols
            out += range(s.start, s.stop)
        return out

    def positions(self, option: int, cols: tuple[int, ...]) -> list[int]:
        """The places of design columns ``cols`` among option ``option``'s own."""
        return [c - self.options[option].cols.start for c in cols]

    # ------------------------------------------------------------------ fits
    def row_weights(self, counts: np.ndarray, active: np.ndarray, scale: np.ndarray
                    ) -> np.ndarray:
        """sqrt(count) / noise scale per row (2u) of the scans ``active`` (zero elsewhere)."""
        c = np.where(active, counts, 0.0)
        s = np.sqrt(c)
        return np.concatenate([s / scale[0], s / scale[1]])

    def fit(self, counts: np.ndarray, active: np.ndarray, scale: np.ndarray,
            cols: list[int]) -> np.ndarray:
        """Coefficients of the base and the design's columns ``cols`` fitted to the scans
        ``active`` (weighted by ``counts`` and the noise ``scale``); a pseudo-inverse where
        they are dependent."""
        sw = self.row_weights(counts, active, scale)
        idx = np.flatnonzero(sw)
        c = np.hstack([self.a[idx], self.x[idx][:, cols]]) * sw[idx, None]
        coef, *_ = np.linalg.lstsq(c, self.z[idx] * sw[idx], rcond=1e-10)
        return coef

    def residuals(self, coef: np.ndarray, cols: list[int]) -> tuple[np.ndarray, np.ndarray]:
        """(whitened, raw) residual rows (2u each) of the base and the design's columns
        ``cols`` at ``coef`` (the whitened ones at unit noise scale)."""
        m = self.m
        w = self.z - self.a @ coef[:m]
        r = self.y - self.a_raw @ coef[:m]
        if cols:
            w -= self.x[:, cols] @ coef[m:]
            r -= self.x_raw[:, cols] @ coef[m:]
        return w, r

    def scan_losses(self, whitened: np.ndarray) -> np.ndarray:
        """Per scan (u), its two rows' squared whitened residuals in the base model's noise
        scale (:attr:`scale0`): the loss held-out predictions are judged by."""
        u = self.u
        return (whitened[:u] / self.scale0[0]) ** 2 + (whitened[u:] / self.scale0[1]) ** 2


@dataclass(frozen=True)
class Tested:
    """One option's test in a round: chi^2 decrease, degrees of freedom, its local p-value
    and its fitted signature off the model (rows of the round's fit)."""

    option: int
    delta_chi2: float
    dof: int
    p: float
    r_model: float = 0.0
    cols: tuple[int, ...] = ()


@dataclass(frozen=True)
class Pick:
    """An option's test in a round: chi^2 decrease, degrees of freedom, its candidate's
    look-elsewhere factor, its family-corrected log p-value, its local p-value and how
    closely the model mimics it (the largest correlation of a column with the model)."""

    option: int
    delta_chi2: float
    dof: int
    trials: float
    log_p: float
    p_local: float = 1.0
    r_model: float = 0.0
    #: the option's design columns the test kept (those the model does not absorb)
    cols: tuple[int, ...] = ()

    @property
    def significance(self) -> float:
        """Sigma (one-sided) of the family-corrected p-value."""
        return sigma_from_p(math.exp(self.log_p), self.log_p)


@dataclass
class Path:
    """A decision: its picks in order, why it stopped, the scans its final model keeps and
    the noise scale per axis; per round, every option significant at the family's level
    (the candidates the data may not tell from the round's pick)."""

    picks: list[Pick]
    stop: str
    active: np.ndarray
    scale: np.ndarray
    #: per round, each option significant at the family's level by itself with the
    #: correlation of its fitted signature with the round's pick's
    rounds: list[list[tuple[Pick, float]]] = field(default_factory=list)
    #: the last round's test of each candidate (its best option), most significant first
    last: list[Pick] = field(default_factory=list)

    @property
    def options(self) -> list[int]:
        return [p.option for p in self.picks]

    def cols(self, k: int | None = None) -> list[int]:
        """The design columns of the first ``k`` picks (all by default), in order."""
        return [c for p in self.picks[:k] for c in p.cols]


@dataclass
class _Round:
    """The statistics of one round over the weighted rows."""

    xp: np.ndarray  # the options' columns off the model (weighted rows)
    zp: np.ndarray  # the data off the model
    tests: dict[int, Tested]
    chi2_now: float
    n_eff: float
    m: int  # the model's parameters


def _repeats(az_rad: np.ndarray, el_rad: np.ndarray, order: np.ndarray) -> np.ndarray:
    """Group labels (0, 1, ... in time order) of scans that repeat the one before them in
    time order: within :data:`REPEAT_DEG` of it on the sky."""
    a, e = az_rad[order], el_rad[order]
    cos_sep = (np.sin(e[1:]) * np.sin(e[:-1])
               + np.cos(e[1:]) * np.cos(e[:-1]) * np.cos(a[1:] - a[:-1]))
    new = np.concatenate([[True], cos_sep < math.cos(math.radians(REPEAT_DEG))])
    out = np.empty(order.size, dtype=int)
    out[order] = np.cumsum(new) - 1
    return out


def decide_base(design: Design, counts: np.ndarray) -> Path:
    """The base model alone on the scans ``counts`` (its outliers and noise scale)."""
    active, scale = _reject(design, counts, [], np.ones(2))
    return Path([], "base", active, scale)


def decide(design: Design, counts: np.ndarray, alpha: float = ALPHA,
           max_findings: int = MAX_FINDINGS) -> Path:
    """The findings the scans ``counts`` (a weight per design scan: 0 leaves it out) support,
    by the rule of the module docstring."""
    d = design
    counts = np.asarray(counts, dtype=float)
    picks: list[Pick] = []
    rounds: list[list[tuple[Pick, float]]] = []
    last: list[Pick] = []
    active, scale = _reject(d, counts, [], np.ones(2))
    stop = "no further candidate is significant"
    while True:
        if len(picks) >= max_findings:
            stop = f"the limit of {max_findings} findings"
            break
        cols = [c for p in picks for c in p.cols]
        rnd = _round(d, counts, active, scale, cols, taken_names(d, picks))
        if rnd is None:
            stop = "the model's terms are not independent on these scans"
            break
        _readmit(d, counts, rnd, active, scale, cols, taken_names(d, picks))
        groups = _group_picks(d, rnd)
        ranked = _candidates(groups)
        last = [pick for _, pick in ranked]
        significant = [pick for _, pick in ranked if pick.log_p < math.log(alpha)]
        if not significant:
            rounds.append([])
            break
        pick = _simpler(d, rnd, significant[0], significant, alpha)
        rounds.append([(p, 1.0 if p.option == pick.option else
                        signature_r(d, rnd, pick.option, p.option))
                       for _, options in groups for p in options
                       if p.log_p < math.log(alpha)])
        bound = parameter_bound(float(np.sum(counts[active])))
        if rnd.m + pick.dof > bound:
            stop = (f"the next finding would exceed the {bound} parameters these scans carry "
                    f"(a fifth of the numbers fitted)")
            break
        picks.append(pick)
        cols = [c for p in picks for c in p.cols]
        active, scale = _reject(d, counts, cols, scale)
        if not d.white and _matches_noise(d, counts, active, scale, cols):
            stop = "the residuals match the predicted noise"
            break
    return Path(picks, stop, active, scale, rounds, last)


def _reject(d: Design, counts: np.ndarray, accepted: list[int], scale: np.ndarray,
            iterations: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """The scans of ``counts`` a model of the base and the design's columns ``accepted``
    keeps (residual within
    OUTLIER_Z of the noise on both axes, from every scan of the set) and, without a noise
    prediction, each axis' noise scale re-estimated from the kept scans
    (:meth:`.problem.Problem.update_outliers`' rule)."""
    live = counts > 0
    active = live.copy()
    scale = scale.copy()
    m = d.m + len(accepted)
    u = d.u
    for _ in range(iterations):
        coef = d.fit(counts, active, scale, accepted)
        if d.white:
            scale = _rescale(d, counts, active, scale, accepted, coef)
            coef = d.fit(counts, active, scale, accepted)
        _, raw = d.residuals(coef, accepted)
        with np.errstate(divide="ignore", invalid="ignore"):
            z = np.abs(raw) / (d.sigma * np.repeat(scale, u))
        keep = live & (z[:u] <= OUTLIER_Z) & (z[u:] <= OUTLIER_Z)
        if keep.sum() < max(m, 3) or np.array_equal(keep, active):
            break
        active = keep
    if d.white:
        scale = _rescale(d, counts, active, scale, accepted,
                         d.fit(counts, active, scale, accepted))
    return active, scale


def _rescale(d: Design, counts: np.ndarray, active: np.ndarray, scale: np.ndarray,
             accepted: list[int], coef: np.ndarray) -> np.ndarray:
    """Each axis' noise scale from its weighted residual rms, corrected for the fitted
    parameters (:meth:`.problem.Problem._rescale`)."""
    w, _ = d.residuals(coef, accepted)
    c = np.where(active, counts, 0.0)
    n = float(c.sum())
    m = d.m + len(accepted)
    factor = 2.0 * n / max(2.0 * n - m, 1.0)
    out = scale.copy()
    u = d.u
    for axis in range(2):
        part = w[axis * u:(axis + 1) * u] / scale[axis]
        ms = float(c @ part**2) / n * factor if n > 0 else 1.0
        if ms > 0:
            out[axis] *= math.sqrt(ms)
    return out


def _matches_noise(d: Design, counts: np.ndarray, active: np.ndarray, scale: np.ndarray,
                   accepted: list[int]) -> bool:
    """Whether both axes' residuals are consistent with the predicted noise (chi^2 p >
    MATCH_P; :meth:`.problem.Problem.gof`'s statistic)."""
    coef = d.fit(counts, active, scale, accepted)
    w, _ = d.residuals(coef, accepted)
    c = np.where(active, counts, 0.0)
    n = float(c.sum())
    m = d.m + len(accepted)
    u = d.u
    for axis in range(2):
        chi2 = float(c @ w[axis * u:(axis + 1) * u] ** 2)
        if not pvalues.chi2_sf(chi2, max(n - m / 2.0, 1.0)) > MATCH_P:
            return False
    return True


def _round(d: Design, counts: np.ndarray, active: np.ndarray, scale: np.ndarray,
           accepted: list[int], taken: set[str], only: int | None = None) -> _Round | None:
    """Every option of a candidate not in the model (``taken``: their names; ``accepted``:
    the model's design columns; ``only``: that option alone) tested against it (None where
    the model's own columns are dependent on these scans)."""
    sw = d.row_weights(counts, active, scale)
    idx = np.flatnonzero(sw)
    w = sw[idx, None]
    model = np.hstack([d.a[idx], d.x[idx][:, accepted]]) * w
    x = d.x[idx] * w
    z = d.z[idx] * sw[idx]
    q, r = economic_qr(model)
    diag = np.abs(np.diag(r))
    if not diag.size or diag.min() <= 1e-10 * max(float(diag.max()), 1e-300):
        return None
    xp = x - q @ (q.T @ x)
    zp = z - q @ (q.T @ z)
    full2 = np.einsum("ij,ij->j", x, x)
    left2 = np.einsum("ij,ij->j", xp, xp)
    ok = left2 > ABSORBED_1MR2 * full2
    xz = xp.T @ zp
    chi2_now = float(zp @ zp)
    n_eff = float(np.sum(np.where(active, counts, 0.0)))
    m = model.shape[1]
    tests: dict[int, Tested] = {}
    for j, o in enumerate(d.options):
        if o.candidate.name in taken or (only is not None and j != only):
            continue
        cols = np.arange(o.cols.start, o.cols.stop)[ok[o.cols]]
        if not cols.size:
            continue
        if cols.size == 1:
            dchi2 = float(xz[cols[0]] ** 2 / left2[cols[0]])
        else:
            g = xp[:, cols].T @ xp[:, cols]
            try:
                dchi2 = float(xz[cols] @ np.linalg.solve(g, xz[cols]))
            except np.linalg.LinAlgError:
                continue
        r2 = 1.0 - float(np.min(left2[cols] / full2[cols]))
        tests[j] = Tested(j, dchi2, int(cols.size),
                          _p_value(d.white, dchi2, int(cols.size), chi2_now, n_eff, m),
                          math.sqrt(min(max(r2, 0.0), 1.0)), tuple(int(c) for c in cols))
    return _Round(xp, zp, tests, chi2_now, n_eff, m)


def _successive_correlation(problem: Problem) -> float:
    """The larger of the two axes' noise correlations between successive valid scans (at
    their median spacing in time; 0 for white noise)."""
    models = [m for m in (problem.pred.corr_xel, problem.pred.corr_el) if m]
    if not models:
        return 0.0
    t = np.sort(problem.obs.t_s[problem.valid])
    if t.size < 2:
        return 0.0
    dt_s = float(np.median(np.diff(t)))
    return max(abs(sum(w * math.exp(-dt_s / tau_s) for w, tau_s in m)) for m in models)


def taken_names(d: Design, picks: list[Pick]) -> set[str]:
    """The names of the candidates already in the model."""
    return {d.options[p.option].candidate.name for p in picks}


def _readmit(d: Design, counts: np.ndarray, rnd: _Round, active: np.ndarray,
             scale: np.ndarray, accepted: list[int], taken: set[str]) -> None:
    """An option that lives mostly on the scans the model rejects (a source offset whose
    every scan is an outlier of the model without it) is tested on the scans a model with
    it keeps, as a candidate's own test is (:meth:`.candidates.base.Candidate.test`); its
    test in ``rnd`` is replaced where that one is more significant."""
    live = counts > 0
    out = live & ~active
    if not out.any():
        return
    rows_out = np.concatenate([out, out])
    rows_live = np.concatenate([live, live])
    e_out = np.einsum("ij,ij->j", d.x[rows_out], d.x[rows_out])
    e_live = np.einsum("ij,ij->j", d.x[rows_live], d.x[rows_live])
    for j, o in enumerate(d.options):
        if o.candidate.name in taken:
            continue
        total = float(e_live[o.cols].sum())
        if total <= 0.0 or float(e_out[o.cols].sum()) < READMIT_FRACTION * total:
            continue
        own = list(range(o.cols.start, o.cols.stop))
        kept, kept_scale = _reject(d, counts, [*accepted, *own], scale)
        if kept.sum() <= active.sum() or kept.sum() < 3:
            continue
        other = _round(d, counts, kept & live, kept_scale, accepted, taken, only=j)
        if other is None or j not in other.tests:
            continue
        t = other.tests[j]
        if j not in rnd.tests or t.p < rnd.tests[j].p:
            rnd.tests[j] = t


def _p_value(white: bool, dchi2: float, q: int, chi2_now: float, n_eff: float,
             m: int) -> float:
    """A chi^2 test with known noise; an F test with the noise estimated from the residuals
    (:func:`.candidates.base.p_value`)."""
    if not white:
        return float(pvalues.chi2_sf(dchi2, q))
    dof = 2.0 * n_eff - m - q
    if dof <= 0:
        return 1.0
    rest = max(chi2_now - dchi2, 1e-12)
    return float(pvalues.f_sf((dchi2 / q) / (rest / dof), q, dof))


def _trials(d: Design, rnd: _Round, group: Group, best: Tested) -> float:
    """The look-elsewhere effect of a candidate's best option among its options."""
    kind = group.candidate.look_elsewhere
    tested = [j for j in group.options if j in rnd.tests]
    if kind == "count":
        return float(len(group.options))
    if kind == "grid":
        cols = [d.options[j].cols.start for j in tested if d.options[j].q == 1]
        if len(cols) < 2:
            return 1.0
        return nyholt_gram(rnd.xp[:, cols].T @ rnd.xp[:, cols])
    if kind == "tube":
        length = 0.0
        for axis in {d.options[j].theta[0] for j in tested}:
            cols = [d.options[j].cols.start for j in tested if d.options[j].theta[0] == axis]
            xs = rnd.xp[:, cols]
            n2 = np.einsum("ij,ij->j", xs, xs)
            dots = np.einsum("ij,ij->j", xs[:, 1:], xs[:, :-1])
            if n2.size > 1:
                # neighbours both seen on these scans (a change time between scans the set
                # leaves out has no column here, and no length)
                both = (n2[1:] > 0) & (n2[:-1] > 0)
                cos = np.abs(dots[both]) / np.sqrt(n2[1:][both] * n2[:-1][both])
                length += float(np.arccos(np.clip(cos, 0.0, 1.0)).sum())
        return tube_trials(best.delta_chi2, length, ends=2)
    return 1.0


def _log_p_family(p: float, trials: float, n_family: int, dchi2: float, dof: int,
                  white: bool) -> float:
    """log of min(1, with_trials(p, trials) x n_family), precise far in the tail."""
    if p > 1e-250:
        return math.log(min(1.0, max(with_trials(p, trials), 1e-320) * n_family))
    base = float(pvalues.chi2_logsf(dchi2, max(dof, 1))) if not white else math.log(
        max(p, 1e-320))
    return min(0.0, base + math.log(max(trials, 1.0)) + math.log(n_family))


def _group_picks(d: Design, rnd: _Round) -> list[tuple[int, list[Pick]]]:
    """Per tested candidate (index into :attr:`Design.groups`), each of its tested options
    as a pick with the candidate's look-elsewhere factor (that of its best option) and
    its family-corrected log p, best first."""
    out = []
    for g, group in enumerate(d.groups):
        tested = sorted((rnd.tests[j] for j in group.options if j in rnd.tests),
                        key=lambda t: -t.delta_chi2)
        if not tested:
            continue
        trials = _trials(d, rnd, group, tested[0])
        out.append((g, [Pick(t.option, t.delta_chi2, t.dof, trials,
                             _log_p_family(t.p, trials, d.n_family, t.delta_chi2, t.dof,
                                           d.white), t.p, t.r_model, t.cols)
                        for t in tested]))
    return out


def _candidates(groups: list[tuple[int, list[Pick]]]) -> list[tuple[int, Pick]]:
    """Each tested candidate's best option, most significant first (ties: the larger chi^2
    decrease)."""
    out = [(g, picks[0]) for g, picks in groups]
    out.sort(key=lambda gp: (gp[1].log_p, -gp[1].delta_chi2))
    return out


def _kept(d: Design, rnd: _Round, j: int) -> list[int] | slice:
    """Option ``j``'s columns its test kept this round (all of them where it was not
    tested)."""
    t = rnd.tests.get(j)
    return list(t.cols) if t is not None else d.options[j].cols


def _fitted(d: Design, rnd: _Round, j: int) -> np.ndarray:
    """Option ``j``'s fitted signature off the model (weighted rows)."""
    xs = rnd.xp[:, _kept(d, rnd, j)]
    coef, *_ = np.linalg.lstsq(xs, rnd.zp, rcond=1e-10)
    return xs @ coef


def signature_r(d: Design, rnd: _Round, a: int, b: int) -> float:
    """How much of option ``a``'s fitted signature option ``b``'s columns reproduce (off the
    model): the correlation of the two."""
    sa = _fitted(d, rnd, a)
    xb = rnd.xp[:, _kept(d, rnd, b)]
    beta, *_ = np.linalg.lstsq(xb, sa, rcond=1e-10)
    den = float(np.linalg.norm(sa))
    return float(np.linalg.norm(xb @ beta)) / den if den > 0 else 0.0


def _explains_as_much(d: Design, rnd: _Round, simple: Pick, full: Pick) -> bool:
    """Akaike's criterion (:data:`AKAIKE_PER_PARAMETER`); without a noise prediction the
    chi^2 in units of the fuller model's residual variance."""
    gap = full.delta_chi2 - simple.delta_chi2
    if d.white:
        dof = 2.0 * rnd.n_eff - rnd.m - full.dof
        if dof <= 0:
            return False
        gap /= max(rnd.chi2_now - full.delta_chi2, 1e-12) / dof
    return gap <= AKAIKE_PER_PARAMETER * max(full.dof - simple.dof, 1)


def _contains(d: Design, big: int, small: int) -> bool:
    """Whether option ``big``'s terms include all of option ``small``'s."""
    ob, os_ = d.options[big], d.options[small]
    return (isinstance(ob.candidate, TermsCandidate) and isinstance(os_.candidate,
                                                                    TermsCandidate)
            and set(os_.names) <= set(ob.names))


def _simpler(d: Design, rnd: _Round, chosen: Pick, significant: list[Pick],
             alpha: float) -> Pick:
    """``chosen``, or the best significant candidate with fewer parameters that is part of
    its terms while the rest is not significant, or that the data cannot tell from it and
    that explains as much."""
    best = None
    for other in significant:
        if other.option == chosen.option or other.dof >= chosen.dof:
            continue
        if _contains(d, chosen.option, other.option):
            rest = float(pvalues.chi2_logsf(chosen.delta_chi2 - other.delta_chi2,
                                            chosen.dof - other.dof))
            ok = rest + math.log(d.n_family) >= math.log(alpha)
        else:
            ok = signature_r(d, rnd, chosen.option, other.option) > DISTINGUISH_R \
                and _explains_as_much(d, rnd, other, chosen)
        if ok and (best is None or other.delta_chi2 > best.delta_chi2):
            best = other
    return chosen if best is None else best

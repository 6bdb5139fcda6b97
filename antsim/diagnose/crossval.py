"""The cross-validated stage: is the decision honest? Nested cross-validation, stability
under resampling, and the candidates the data cannot tell apart.

A decision (:func:`.decide.decide`) chooses findings by significance. Whether a model with
them predicts data it was not fitted to, and how often the same data would choose them, are
asked of the whole decision, repeated:

* **Kept (inner folds).** :func:`choose` repeats the decision inside ``K_INNER`` folds of the
  scans it is given and scores each number of findings k by the held-out losses of the
  folds' own first k findings; the j-th finding is kept while each of the first j lowers
  the held-out loss (squared residuals in units of the noise). A finding the repeated
  selection does not predict with is refused, and those after it with it.
* **Stable (resamples).** ``N_RESAMPLES`` bootstrap resamples of the scans (seeded) are
  decided again; a kept finding is chosen in a resample when its candidate, or one the data
  cannot tell from it, is among the resample's findings. Below ``STABLE_FRACTION`` it is
  reported as unstable, not as a finding.
* **Alternatives.** A candidate significant in the same round that the data cannot tell
  from a finding (their fitted signatures correlated above 0.95, or its model predicting
  every left-out scan as well: the paired difference of leave-one-scan-out losses within
  its standard error) is the same finding's alternative, and a resample that chooses it
  chooses the finding.
* **Held out (outer folds).** :func:`nested` repeats all of it (:func:`choose`: decision,
  inner folds, resamples) on the training scans of each of the outer folds and predicts
  the held-out ones with the first k findings of each, k = 0 (the base model) up to all:
  the held-out Sky RMS diagnose prints, before and after each finding.

Folds: without a noise prediction the noise may be correlated in time (the same source,
the same weather): contiguous blocks of the scans in time order (a TPOINT file's order,
which is the order they were taken), so that neighbours cannot vouch for a term that only
fits them; with a noise prediction the rows are decorrelated (:class:`.decide.Design`) and
the folds interleave the scans in time, or hold out whole nights when the data span more
than a day and a half (an effect of the time of day is then predicted from other days).

The closed-form leave-one-star-out statistics (each star's two rows together) serve the
benchmarks that cross-validate whole procedures (``benchmarks/real.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .candidates.base import DISTINGUISH_R
from .candidates.terms import TermsCandidate
from .decide import Design, Path, decide
from .linalg import heldout_lstsq, lstsq

__all__ = ["AT_SCALE", "FULL", "K_INNER", "K_OUTER", "N_RESAMPLES", "STABLE_FRACTION",
           "Choice", "Nested", "Plan", "TermSupport", "Validation", "base_support", "choose",
           "contiguous_folds", "heldout_losses", "loo_blocks", "loo_residuals", "loo_rms",
           "nested", "orthonormal", "outer_folds", "plan_for", "validate"]

#: outer folds (the printed held-out figures) at most
K_OUTER = 10
#: outer folds interleaved in time, with a noise prediction, within a day and a half
K_OUTER_INTERLEAVED = 5
#: inner folds (the number of findings kept): ten, the usual choice for selection on small
#: samples (each fold's training set nine tenths of the data it is given)
K_INNER = 10
#: bootstrap resamples of the stability check
N_RESAMPLES = 50
#: a kept finding is a finding when chosen in at least this fraction of the resamples (more
#: often than not)
STABLE_FRACTION = 0.5
#: the seed of the resamples (the same data give the same resamples)
SEED = 1990
#: designs of more scans than this are validated by :data:`AT_SCALE`
SCALE_SCANS = 1500


@dataclass(frozen=True)
class Plan:
    """How much the validation repeats the decision: inner folds, resamples, outer folds at
    most, and whether each outer fold repeats the whole of :func:`choose` (``whole``) or
    the decision alone (:func:`.decide.decide`: a cheap inner decision)."""

    k_inner: int
    n_resamples: int
    k_outer: int
    whole: bool


#: files of up to :data:`SCALE_SCANS` scans: everything repeated in every outer fold
FULL = Plan(K_INNER, N_RESAMPLES, K_OUTER, True)
#: larger ones (tens of thousands of scans: a decision costs 0.15 s on the design's 5,000):
#: three inner blocks, ten resamples, five outer blocks in time that repeat the decision
#: alone
AT_SCALE = Plan(3, 10, 5, False)


def plan_for(design: Design) -> Plan:
    """The plan a design is validated by."""
    return FULL if design.u <= SCALE_SCANS else AT_SCALE


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




def contiguous_folds(t_s: np.ndarray, k: int) -> np.ndarray:
    """Fold labels 0..k-1: ``k`` contiguous blocks of (nearly) equal size in time order."""
    n = t_s.size
    order = np.argsort(t_s, kind="stable")
    folds = np.empty(n, dtype=int)
    folds[order] = (np.arange(n) * k) // max(n, 1)
    return folds


# ---------------------------------------------------------------------------------------------
# Folds
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Folds:
    """Fold labels per design scan (-1: in no fold) and the design in words."""

    labels: np.ndarray
    words: str

    @property
    def k(self) -> int:
        return int(self.labels.max()) + 1 if self.labels.size else 0


def _in_order(design: Design, scans: np.ndarray, k: int, contiguous: bool) -> np.ndarray:
    """Labels 0..k-1 of the design scans ``scans`` (boolean), -1 elsewhere: contiguous blocks
    of them in time order, or their repeats (:attr:`.decide.Design.group`) interleaved."""
    labels = np.full(design.u, -1)
    order = design.order[scans[design.order]]
    n = order.size
    if contiguous:
        labels[order] = (np.arange(n) * k) // max(n, 1)
    else:
        _, rank = np.unique(design.group[order], return_inverse=True)
        labels[order] = rank % k
    return labels


def _contiguous(design: Design) -> bool:
    """Whether folds are contiguous blocks in time: data in time whose noise is estimated
    from them (its correlation in time unknown)."""
    return design.white and design.problem.obs.has_time


def outer_folds(design: Design, k_outer: int = K_OUTER) -> Folds:
    """The outer folds of :func:`nested` (the module docstring), ``k_outer`` at most."""
    everything = np.ones(design.u, dtype=bool)
    if _contiguous(design) or design.u > SCALE_SCANS:
        k = min(k_outer, design.u)
        return Folds(_in_order(design, everything, k, True),
                     f"{k} contiguous blocks in time held out in turn")
    if design.white:  # positions without times: the stars interleaved, repeats together
        k = min(k_outer, int(design.group.max()) + 1)
        return Folds(_in_order(design, everything, k, False),
                     f"{k} folds of the stars interleaved in the file's order held out in "
                     "turn (a star measured again in the same fold)")
    obs = design.problem.obs
    t = obs.t_s[design.scans]
    if obs.has_time and np.ptp(t) > 1.5 * 86400.0:
        lon = float(obs.meta.get("longitude_deg", 0.0))
        day = np.floor((t / 3600.0 + lon / 15.0 - 12.0) / 24.0)
        _, labels = np.unique(day, return_inverse=True)
        if labels.max() >= 1:
            return Folds(labels, f"{labels.max() + 1} nights held out in turn")
    k = min(K_OUTER_INTERLEAVED, k_outer, design.u)
    return Folds(_in_order(design, everything, k, False),
                 f"{k} folds interleaved in time held out in turn")


def _inner(design: Design, train: np.ndarray, k_inner: int) -> np.ndarray:
    """Inner fold labels of the training scans ``train`` (as the outer folds' design),
    ``k_inner`` at most."""
    k = min(k_inner, int(train.sum()))
    return _in_order(design, train, k, _contiguous(design) or design.u > SCALE_SCANS)


# ---------------------------------------------------------------------------------------------
# The decision, kept and stable
# ---------------------------------------------------------------------------------------------
@dataclass
class Alternative:
    """A candidate the data cannot tell from a finding: its option (index into the design's
    options), the correlation of their fitted signatures, the leave-one-scan-out losses of
    the two models (sums, units of the noise) and, without a noise prediction, their
    held-out Sky RMS (arcsec); its design columns (those its test kept)."""

    option: int
    correlation: float
    loss: float
    loss_finding: float
    sky_rms: float = float("nan")
    sky_rms_finding: float = float("nan")
    cols: tuple[int, ...] = ()


@dataclass
class Choice:
    """A decision on a set of scans, kept and checked for stability (the module
    docstring): ``inner[k]`` the inner folds' held-out loss with k findings; the first
    ``kept`` picks kept; per kept pick its alternatives and how often the resamples chose
    it (or one of them)."""

    path: Path
    inner: list[float]
    kept: int
    alternatives: list[list[Alternative]] = field(default_factory=list)
    stability: list[float] = field(default_factory=list)
    n_resamples: int = 0

    @property
    def stable(self) -> list[bool]:
        return [s >= STABLE_FRACTION for s in self.stability]

    @property
    def findings(self) -> list[int]:
        """The picks (indices into ``path.picks``) that are findings: kept and stable, up to
        the first that is not (the picks after it were chosen with it in the model)."""
        out = []
        for j in range(self.kept):
            if self.stability[j] < STABLE_FRACTION:
                break
            out.append(j)
        return out

    @property
    def options(self) -> list[int]:
        """The findings' options, in order: the model the decision proposes."""
        return [self.path.picks[j].option for j in self.findings]


def _prefix_losses(design: Design, counts: np.ndarray, path: Path, test: np.ndarray,
                   kmax: int) -> tuple[np.ndarray, np.ndarray]:
    """For k = 0..kmax, the held-out losses (summed, :meth:`Design.scan_losses`) and
    squared raw residuals per axis (summed, arcsec^2; (kmax + 1, 2)) over the scans
    ``test`` of the base and the first k of ``path``'s findings, fitted to ``counts`` as
    ``path`` left them."""
    loss, raw2 = np.zeros(kmax + 1), np.zeros((kmax + 1, 2))
    u = design.u
    done: dict[int, tuple[float, tuple[float, float]]] = {}
    for k in range(kmax + 1):
        j = min(k, len(path.picks))
        if j not in done:
            cols = path.cols(j)
            coef = design.fit(counts, path.active, path.scale, cols)
            w, r = design.residuals(coef, cols)
            done[j] = (float(design.scan_losses(w)[test].sum()),
                       (float((r[:u][test] ** 2).sum()), float((r[u:][test] ** 2).sum())))
        loss[k], raw2[k] = done[j]
    return loss, raw2


def _kept(inner: np.ndarray) -> int:
    """The number of findings kept: while each lowers the inner held-out loss."""
    k = 0
    while k + 1 < inner.size and inner[k + 1] < inner[k]:
        k += 1
    return k


def _loo(design: Design, counts: np.ndarray, path: Path, cols: list[int],
         base: list[int] | None = None) -> tuple[np.ndarray, np.ndarray] | None:
    """Leave-one-scan-out held-out residuals (each scan's two rows together) of the base
    (its columns ``base``, default all) and the design's columns ``cols`` over the scans
    ``path`` keeps (weights ``counts``): (whitened loss per scan, squared raw residual per
    scan, arcsec^2 without a noise prediction, else NaN); None where a scan alone
    determines a term."""
    sw = design.row_weights(counts, path.active, path.scale)
    scans = np.flatnonzero(path.active & (counts > 0))
    u = design.u
    rows = np.concatenate([scans, scans + u])
    a = design.a[rows] if base is None else design.a[rows][:, base]
    c = np.hstack([a, design.x[rows][:, cols]]) * sw[rows, None]
    q = orthonormal(c)
    if q is None:
        return None
    z = design.z[rows] * sw[rows]
    n = scans.size
    held = loo_residuals(loo_blocks(q, n), z - q @ (q.T @ z), n)
    if held is None:
        return None
    loss = held[0] ** 2 + held[1] ** 2
    raw2 = np.full(n, np.nan)
    if design.white:  # a row's residual is its weighted one over its weight and noise
        sx = design.sigma[scans] / sw[scans]
        se = design.sigma[scans + u] / sw[scans + u]
        raw2 = (held[0] * sx) ** 2 + (held[1] * se) ** 2
    return loss, raw2


def _alternatives(design: Design, counts: np.ndarray, path: Path, j: int
                  ) -> list[Alternative]:
    """The options significant in pick ``j``'s round that the data cannot tell from it:
    their fitted signatures correlated above DISTINGUISH_R with the pick's ("cannot
    reliably be distinguished", TPOINT's level), or their model (the first j findings and
    it) predicting each left-out scan as well as the pick's (the paired difference of the
    two models' losses within its standard error)."""
    pick = path.picks[j]
    before = path.cols(j)
    mine = _loo(design, counts, path, [*before, *pick.cols])
    if j >= len(path.rounds):
        return []
    out = []
    for other, r in path.rounds[j]:
        if other.option == pick.option:
            continue
        theirs = _loo(design, counts, path, [*before, *other.cols])
        equal = False
        if theirs is not None and mine is not None and theirs[0].size >= 3:
            d = theirs[0] - mine[0]
            se = float(np.std(d, ddof=1)) / math.sqrt(d.size)
            equal = float(np.mean(d)) <= se
        if equal or r > DISTINGUISH_R:
            out.append(Alternative(other.option, r,
                                   float(theirs[0].sum()) if theirs else math.nan,
                                   float(mine[0].sum()) if mine else math.nan,
                                   _rms(theirs[1]) if theirs else math.nan,
                                   _rms(mine[1]) if mine else math.nan, other.cols))
    return out


def _rms(raw2: np.ndarray) -> float:
    return math.sqrt(float(np.mean(raw2))) if raw2.size and np.isfinite(raw2).all() \
        else float("nan")


def choose(design: Design, counts: np.ndarray, plan: Plan = FULL, seed: int = SEED
           ) -> Choice:
    """The decision on the scans ``counts`` (0 or 1 each), kept by its inner folds, its
    alternatives found and its stability measured (the module docstring)."""
    counts = np.asarray(counts, dtype=float)
    path = decide(design, counts)
    train = counts > 0
    labels = _inner(design, train, plan.k_inner)
    kmax = len(path.picks)
    inner = np.zeros(kmax + 1)
    for f in range(int(labels.max()) + 1 if kmax else 0):
        fold = np.where(labels == f, 0.0, counts)
        inner += _prefix_losses(design, fold, decide(design, fold),
                                (labels == f) & design.kept0, kmax)[0]
    kept = _kept(inner)
    alternatives = [_alternatives(design, counts, path, j) for j in range(kept)]
    stability = _stability(design, counts, path, kept, alternatives, seed, plan.n_resamples)
    # said: a candidate the decision keeps as another finding, or part of one (its terms),
    # is not an alternative (the data told them apart by keeping both); a resample that
    # chooses it still chooses this finding's signature
    alternatives = [[a for a in alts if not _in_other(design, path, kept, j, a.option)]
                    for j, alts in enumerate(alternatives)]
    return Choice(path, [float(v) for v in inner], kept, alternatives, stability,
                  plan.n_resamples)


def _in_other(design: Design, path: Path, kept: int, j: int, option: int) -> bool:
    """Whether ``option``'s candidate, or a term of it, is that of a kept pick but the j-th."""
    o = design.options[option]
    for i, p in enumerate(path.picks[:kept]):
        other = design.options[p.option]
        if i != j and (other.candidate.name == o.candidate.name
                       or set(other.names) & set(o.names)):
            return True
    return False


def _stability(design: Design, counts: np.ndarray, path: Path, kept: int,
               alternatives: list[list[Alternative]], seed: int, n_resamples: int
               ) -> list[float]:
    """Per kept pick, the fraction of bootstrap resamples of the scans whose decision
    chooses it: its candidate, one of its alternatives', or a candidate that shares a
    TPOINT term with it (part of its terms: a runout once per turn where the pick is the
    runout once and twice per turn)."""
    if not kept:
        return []
    groups = []
    for j in range(kept):
        options = [path.picks[j].option, *(a.option for a in alternatives[j])]
        groups.append(({design.options[o].candidate.name for o in options},
                       {t for o in options for t in _terms(design, o)}))
    # the repeats of a star drawn together (a cluster bootstrap)
    live = counts > 0
    clusters, member = np.unique(design.group[live], return_inverse=True)
    scans = np.flatnonzero(live)
    rng = np.random.default_rng(seed)
    chosen = np.zeros(kept)
    for _ in range(n_resamples):
        times = np.bincount(rng.integers(0, clusters.size, clusters.size),
                            minlength=clusters.size)
        draw = np.zeros(design.u)
        draw[scans] = times[member]
        picked = decide(design, draw).options
        names = {design.options[o].candidate.name for o in picked}
        terms = {t for o in picked for t in _terms(design, o)}
        chosen += [bool(g & names or t & terms) for g, t in groups]
    return [float(v) / max(n_resamples, 1) for v in chosen]


@dataclass
class TermSupport:
    """Whether a base term predicts left-out scans: the leave-one-scan-out losses of the
    base model with and without it (sums, units of the noise), and their Sky RMS (arcsec;
    NaN with a noise prediction)."""

    term: str
    loss_with: float
    loss_without: float
    sky_rms_with: float
    sky_rms_without: float
    supported: bool


def base_support(design: Design) -> list[TermSupport]:
    """Each base term's support (the module docstring's rule for an alternative, turned
    round): a term is supported when the base model predicts each left-out scan better with
    it, the paired difference of the losses beyond its standard error."""
    path = Path([], "base", design.kept0, design.scale0)
    ones = np.ones(design.u)
    whole = _loo(design, ones, path, [])
    out: list[TermSupport] = []
    if whole is None:
        return out
    for i, term in enumerate(design.problem.base_terms):
        rest = [k for k in range(design.m) if k != i]
        without = _loo(design, ones, path, [], rest)
        if without is None:
            continue
        d = without[0] - whole[0]
        se = float(np.std(d, ddof=1)) / math.sqrt(d.size) if d.size > 2 else math.inf
        out.append(TermSupport(term, float(whole[0].sum()), float(without[0].sum()),
                               _rms(whole[1]), _rms(without[1]), float(np.mean(d)) > se))
    return out


def _terms(design: Design, option: int) -> set[str]:
    """The TPOINT terms of an option of a pointing-term candidate (none for others)."""
    o = design.options[option]
    return set(o.names) if isinstance(o.candidate, TermsCandidate) else set()


# ---------------------------------------------------------------------------------------------
# The held-out figures
# ---------------------------------------------------------------------------------------------
@dataclass
class Nested:
    """The decision repeated on each outer fold's training scans (:func:`choose`) and the
    held-out scans predicted with each fold's first k findings: ``loss[k]`` (summed, units
    of the noise) and ``sky_rms[k]`` (arcsec), k = 0 (the base model) to the most any fold
    found; ``choices`` the folds' decisions."""

    folds: Folds
    loss: np.ndarray
    sky_rms: np.ndarray
    choices: list[Choice]
    n_scans: int
    #: per k, the held-out rms of each axis (arcsec; (k, 2))
    axis_rms: np.ndarray = field(default_factory=lambda: np.zeros((1, 2)))

    def at(self, k: int) -> float:
        """The held-out Sky RMS (arcsec) with each fold's first k findings."""
        return float(self.sky_rms[min(k, self.sky_rms.size - 1)])

    @property
    def final(self) -> float:
        """The held-out Sky RMS of the procedure: each fold with all its findings."""
        return float(self.sky_rms[-1])


def nested(design: Design, plan: Plan = FULL, seed: int = SEED) -> Nested:
    """The outer folds of the module docstring (each repeats :func:`choose`, or the decision
    alone where ``plan`` says so)."""
    folds = outer_folds(design, plan.k_outer)
    choices, runs = [], []
    for f in range(folds.k):
        train = np.where(folds.labels == f, 0.0, 1.0)
        if plan.whole:
            choice = choose(design, train, plan, seed + f + 1)
        else:
            path = decide(design, train)
            choice = Choice(path, [], len(path.picks), [], [1.0] * len(path.picks), 0)
        choices.append(choice)
        # the fold's model: its findings in order, fitted as its decision left the scans
        path = choice.path
        runs.append((train, Path([path.picks[j] for j in choice.findings], path.stop,
                                 path.active, path.scale)))
    kmax = max((len(p.picks) for _, p in runs), default=0)
    loss, raw2 = np.zeros(kmax + 1), np.zeros((kmax + 1, 2))
    n = 0
    for f, (train, path) in enumerate(runs):
        test = (folds.labels == f) & design.kept0
        n += int(test.sum())
        a, b = _prefix_losses(design, train, path, test, kmax)
        loss += a
        raw2 += b
    return Nested(folds, loss, np.sqrt(raw2.sum(axis=1) / max(n, 1)), choices, n,
                  np.sqrt(raw2 / max(n, 1)))


@dataclass
class Validation:
    """The decision on the file (:func:`choose` on every design scan) and its held-out
    figures (:func:`nested`; None when not asked for)."""

    design: Design
    choice: Choice
    nested: Nested | None
    plan: Plan = FULL


def validate(design: Design, plan: Plan | None = None, held_out: bool = True
             ) -> Validation:
    """The file's decision and, with ``held_out``, its nested held-out figures (they measure
    the decision; they change nothing in it); ``plan``: :func:`plan_for` the design's by
    default."""
    plan = plan_for(design) if plan is None else plan
    return Validation(design, choose(design, np.ones(design.u), plan),
                      nested(design, plan) if held_out else None, plan)

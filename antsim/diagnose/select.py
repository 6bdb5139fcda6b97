"""Honest selection: forward addition of candidate effects, one at a time.

Each round every applicable candidate is tested against the current model by what the model
cannot absorb: its signature's component orthogonal to the fitted terms (an added-variable,
or partial, test: a chi^2 test when the simulation predicts the noise, an F test when the
noise is estimated from the data; a sin/cos pair is one joint test with 2 degrees of freedom;
nonlinear parameters pay for the look-elsewhere effect with an effective number of trials).
The family of candidates is corrected together (Bonferroni over the candidates tested in the
first round), so that data explained to the noise yield no finding with probability at least
1 - ``ALPHA``; with the library's 20-odd candidates the criterion is stricter than BIC
(``q ln N``) at every N here.

The most significant candidate is then

* refused when it does not lower the chi^2 of held-out data (another night when the data
  span several, else 5-fold cross-validation interleaved in time; nonlinear parameters are
  re-derived on each training set);
* otherwise accepted, however closely the model mimics it: its correlation with
  the model is reported in TPOINT's words ("X and Y cannot reliably be distinguished",
  r above 0.95; "strongly correlated", above 0.85) beside how many sigma the data separate
  it by (the local significance of its orthogonal part). A candidate the model mimics is
  refused only when that part is below detection (and said so when it shows a hint, 3 sigma
  locally);
* replaced by a simpler candidate (fewer parameters) that the data cannot distinguish from it
  (fitted signatures correlated above 0.95) when that one explains as much (the extra
  parameters add at most Akaike's 2 of chi^2 each: it predicts as well); the other is reported
  beside it, as are all near-degenerate alternatives (fitted signatures correlated above
  0.9, or within 2 of its BIC). A pair whose improvement one TPOINT term matches (by the
  same rule) is offered in that simplest form.

Selection stops when no candidate passes, or as soon as the residuals match the predicted
noise on both axes (p > 0.05), or after ``MAX_FINDINGS``. The polarization and beam-width
candidates test other recorded quantities and are decided once, in the same family.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from . import pvalues
from .candidates.base import DISTINGUISH_R, Candidate, TestResult, p_value
from .candidates.library import CANDIDATES
from .candidates.terms import HarmonicFamilyCandidate, TermsCandidate
from .crossval import MAX_FINDINGS_CV, cv_stage
from .problem import Problem, folds_for, term_columns

__all__ = ["ALPHA", "Selection", "Step", "correlation_words", "select", "sigma_from_p"]

#: family-wise false-alarm probability of the whole selection
ALPHA = 0.005
MAX_FINDINGS = 5
#: fitted signatures this correlated are "near-degenerate alternatives"
ALTERNATIVE_R = 0.9
#: TPOINT's lower level: coefficients this correlated are "strongly correlated"
STRONG_R = 0.85
#: a simpler form "explains as much" when each parameter it lacks would add at most this
#: much chi^2 (Akaike's 2)
AKAIKE_PER_PARAMETER = 2.0
#: term columns projected at a time when looking for a finding's simplest form
SIMPLEST_CHUNK = 8
#: a candidate the model mimics, not accepted, is reported as below detection when the part
#: the model cannot absorb reaches this local significance (sigma)
HINT_SIGMA = 3.0


def sigma_from_p(p: float, log_p: float | None = None) -> float:
    """One-sided Gaussian equivalent of a p-value (handles underflow through log p); 0 for
    p >= 0.5 (no evidence at all)."""
    if log_p is None:
        log_p = math.log(p) if p > 0 else -745.0
    if log_p > -700:
        return max(0.0, float(pvalues.norm_isf(math.exp(log_p))))
    x = -2.0 * log_p
    return float(math.sqrt(max(x - math.log(x) - math.log(2 * math.pi), 0.0)))


def log_p_family(problem: Problem, res: TestResult, n_family: int) -> float:
    """log of the family-corrected p-value (precise far in the tail)."""
    if res.p > 1e-250:
        return math.log(min(1.0, res.p * n_family))
    if problem.pred.known_noise or res.candidate.kind == "channel":
        base = float(pvalues.chi2_logsf(res.delta_chi2, max(res.dof, 1)))
    else:
        base = math.log(max(res.p, 1e-320))
    return min(0.0, base + math.log(max(res.trials, 1.0)) + math.log(n_family))


def local_sigma(problem: Problem, res: TestResult) -> float:
    """How many sigma the data separate a candidate from the model: the local significance
    (no look-elsewhere or family correction) of the part of its signature the model cannot
    absorb, as the two-sided Gaussian equivalent of its p-value (for one parameter with
    known noise, |value| / sigma of that part: sqrt(chi^2 decrease))."""
    if problem.pred.known_noise:
        log_p = float(pvalues.chi2_logsf(res.delta_chi2, max(res.dof, 1)))
    else:
        p = p_value(problem, res.delta_chi2, res.dof, res.chi2_now, res.mask)
        log_p = math.log(p) if p > 0 else -745.0
    half = log_p - math.log(2.0)
    return sigma_from_p(math.exp(half) if half > -700 else 0.0, half)


def correlation_words(name: str, r: float, partners: tuple[str, ...]) -> str:
    """TPOINT's words for how closely the model mimics a candidate ("" below 0.85)."""
    who = ", ".join(partners) or "the model"
    if r > DISTINGUISH_R:
        return f"{name} and {who} cannot reliably be distinguished (r = {r:.2f})"
    if r > STRONG_R:
        return f"{name} and {who} are strongly correlated (r = {r:.2f})"
    return ""


def explains_as_much(problem: Problem, simple_dchi2: float, simple_dof: int,
                     full: TestResult) -> bool:
    """Whether a form with fewer parameters explains as much as ``full``: the chi^2 the
    extra parameters add is at most 2 per parameter (Akaike's criterion: the simpler form
    then predicts new data as well, to first order as leave-one-out cross-validation
    judges). Without a noise prediction the chi^2 is in units of the fuller model's residual
    variance (the noise the data show once both are fitted)."""
    extra = max(full.dof - simple_dof, 1)
    gap = full.delta_chi2 - simple_dchi2
    if not problem.pred.known_noise:
        n_used = int((problem.used if full.mask is None else full.mask).sum())
        dof = 2 * n_used - problem.current_columns().shape[1] - full.dof
        if dof <= 0:
            return False
        gap /= max(full.chi2_now - full.delta_chi2, 1e-12) / dof
    return gap <= AKAIKE_PER_PARAMETER * extra


@dataclass
class Alternative:
    result: TestResult
    correlation: float
    reason: str
    #: another order of a harmonic family (said in one line with the family's others)
    sibling: bool = False


@dataclass
class Separation:
    """How closely the model mimics a finding, and how far the data separate them."""

    r: float
    partners: tuple[str, ...]
    sigma: float
    words: str


@dataclass
class SimplestForm:
    """One TPOINT term that explains as much as a finding's pair."""

    terms: tuple[str, ...]
    delta_chi2: float
    sky_rms_after: float
    words: str


@dataclass
class Step:
    """One accepted finding with its statistics."""

    result: TestResult
    p_family: float
    log_p: float
    sky_rms_before: float
    sky_rms_after: float
    cv_chi2_before: float = float("nan")
    cv_chi2_after: float = float("nan")
    alternatives: list[Alternative] = field(default_factory=list)
    gof_after: dict | None = None
    signal: np.ndarray | None = None  # fitted error of the finding (2n, arcsec)
    separation: Separation | None = None
    simplest: SimplestForm | None = None
    #: (before, after) held-out Sky RMS (arcsec) of a finding the cross-validated stage
    #: added (data without a noise prediction: :mod:`.crossval`), else None
    heldout: tuple[float, float] | None = None

    @property
    def significance(self) -> float:
        return sigma_from_p(self.p_family, self.log_p)


@dataclass
class Chosen:
    """The candidate a round chooses, with its family-corrected log p-value and the
    held-out chi^2 of the model without and with it (it predicts held-out data better)."""

    result: TestResult
    log_p: float
    cv_chi2_before: float
    cv_chi2_after: float


def _held_out(problem: Problem, r: TestResult, folds: np.ndarray, log_p: float
              ) -> Chosen | None:
    """``r`` chosen if the model with it predicts held-out data (``folds``, over ``r``'s
    scans) better than the model without it, its nonlinear parameters re-derived on each
    training set; None if not. Notes the figures in ``r.note``."""
    cur = problem.current_columns()
    cv_without = problem.cv_chi2(cur, folds, used=r.mask)
    refit = None
    if r.refit is not None:
        def refit(train, _r=r, _cur=cur):
            return np.column_stack([_cur, _r.refit(train)])
    cv_with = problem.cv_chi2((cur, r.columns), folds, refit, used=r.mask)
    r.note = f"held-out chi2 {cv_without:.1f} -> {cv_with:.1f}"
    if not cv_with < cv_without:
        return None
    return Chosen(r, log_p, cv_without, cv_with)


@dataclass
class Refusal:
    result: TestResult
    reason: str


@dataclass
class Selection:
    steps: list[Step]
    refused: list[Refusal]
    absorbed: list[TestResult]
    first_round: list[TestResult]
    not_applicable: list[str]
    n_family: int
    gof_before: dict
    gof_after: dict
    stop_reason: str


def _fitted_signal(problem: Problem, cols: np.ndarray, extra: np.ndarray) -> np.ndarray:
    """The fitted error (2n, arcsec) of a finding's raw columns ``extra`` just added to the
    model (the model's columns before it: ``cols``) in the joint fit, less the part the
    model's own terms can take (what the finding adds). The joint fit is the current
    model's (:meth:`Problem.fit_current`): the outlier update after the finding starts
    from it, not from a fit of the same design again."""
    f = problem.fit_current()
    signal = extra @ f.coef[cols.shape[1]:]
    beta, *_ = np.linalg.lstsq(problem.whiten(cols), problem.whiten(signal), rcond=None)
    return signal - cols @ beta


def _fitted_perp(perp, a: TestResult) -> np.ndarray | None:
    """A candidate's fitted signature with the model projected out (None without one)."""
    cols = a.columns  # read once: a result may make its columns again on each read
    if cols is None or a.coef.size == 0:
        return None
    return perp(cols) @ a.coef if a.coef.size == cols.shape[1] else perp(cols)[:, 0]


def _signal_corr(problem: Problem, perp, a: TestResult, b: TestResult,
                 sa: np.ndarray | None = None) -> float:
    """Correlation of two candidates' fitted signatures after removing the model (``sa``:
    :func:`_fitted_perp` of ``a`` when the caller has it)."""
    if a.coef.size == 0 or b.coef.size == 0:
        return 0.0
    sa = _fitted_perp(perp, a) if sa is None else sa
    cols_b = b.columns
    if sa is None or cols_b is None:
        return 0.0
    xb = perp(cols_b)
    # how much of a's fitted signature b's span reproduces
    beta, *_ = np.linalg.lstsq(xb, sa, rcond=None)
    num = float(np.linalg.norm(xb @ beta))
    den = float(np.linalg.norm(sa))
    return num / den if den > 0 else 0.0


class _Correlations:
    """:func:`_signal_corr` over one round's projector ``perp``, each candidate's projected
    fitted signature and each pair's correlation made once: the simpler-equivalent check
    and the alternatives ask for the same pairs (each a projection of 2 n_used rows and a
    least-squares fit)."""

    def __init__(self, problem: Problem, perp):
        self.problem, self.perp = problem, perp
        self._sa: dict[int, tuple[TestResult, np.ndarray | None]] = {}
        self._r: dict[tuple[int, int], tuple[TestResult, TestResult, float]] = {}

    def __call__(self, a: TestResult, b: TestResult) -> float:
        """:func:`_signal_corr` of ``a`` and ``b``."""
        key = (id(a), id(b))  # the results are held beside their ids: no id reused
        if key not in self._r:
            if a.coef.size and b.coef.size and id(a) not in self._sa:
                self._sa[id(a)] = (a, _fitted_perp(self.perp, a))
            sa = self._sa.get(id(a), (a, None))[1]
            self._r[key] = (a, b, _signal_corr(self.problem, self.perp, a, b, sa))
        return self._r[key][2]


def _model_terms(problem: Problem) -> set[str]:
    """The TPOINT terms the current model holds (base terms and accepted term findings)."""
    return set(problem.base_terms) | {n.split(":", 1)[1] for n in problem.extra_names}


def _single_terms(candidates: tuple[Candidate, ...]) -> list[str]:
    """Every TPOINT term the library's linear candidates are made of (each order of the
    harmonic families), in library order: the vocabulary of one-term forms."""
    out: list[str] = []
    for c in candidates:
        if isinstance(c, HarmonicFamilyCandidate):
            names = [t for n in c.orders for t in c.order_terms(n)]
        elif isinstance(c, TermsCandidate):
            names = list(c.terms)
        else:
            continue
        out += [t for t in names if t not in out]
    return out


def _simplest_form(problem: Problem, res: TestResult, vocabulary: list[str]
                   ) -> SimplestForm | None:
    """One TPOINT term that explains as much as the finding's terms (None if none does, or
    the finding is one term already)."""
    if not isinstance(res.candidate, TermsCandidate) or len(res.comp_names) < 2:
        return None
    names = [t for t in vocabulary if t not in _model_terms(problem)]
    if not names:
        return None
    perp, z_perp = problem.perp_for(res.mask)
    # a few terms at a time: the whole vocabulary's columns over 200,000 scans are 0.5 GB
    # per copy, and each column's numbers are its own
    norm2, xz = np.zeros(len(names)), np.zeros(len(names))
    for start in range(0, len(names), SIMPLEST_CHUNK):
        part = slice(start, start + SIMPLEST_CHUNK)
        xp = perp(problem.cand(term_columns(names[part], problem.obs)))
        norm2[part], xz[part] = np.einsum("ij,ij->j", xp, xp), xp.T @ z_perp
    with np.errstate(invalid="ignore", divide="ignore"):
        gain = np.where(norm2 > 1e-9 * max(float(norm2.max()), 1e-300), xz ** 2 / norm2, 0.0)
    best = int(np.argmax(gain))
    if not explains_as_much(problem, float(gain[best]), 1, res):
        return None
    term = names[best]
    col = problem.cand(term_columns([term], problem.obs))
    rms = problem.sky_rms(np.column_stack([problem.current_columns(), col]))
    pair = problem.sky_rms_added(res.columns)  # the Sky RMS after the finding: kept for it
    return SimplestForm((term,), float(gain[best]), rms,
                        f"{term} alone explains as much as {' '.join(res.comp_names)} "
                        f"(Sky RMS {rms:.3f}\" against {pair:.3f}\"; chi2 decrease "
                        f"{gain[best]:.1f} against {res.delta_chi2:.1f})")


def _label(r: TestResult) -> str:
    return r.candidate.label(r.theta)


def _alternatives(problem: Problem, corr_of: _Correlations, r: TestResult,
                  ranked: list[TestResult], n_family: int, alpha: float) -> list[Alternative]:
    """The significant candidates the data cannot distinguish from ``r`` or that fit almost
    as well, and the other orders of a harmonic family (``TestResult.siblings``, of ``r``'s
    own or of another candidate's) that the data cannot distinguish from it."""
    out = []
    n_obs = 2 * int(problem.used.sum())
    siblings = [s for o in ranked for s in o.siblings]
    for other in [*ranked, *siblings]:
        if other is r or log_p_family(problem, other, n_family) >= math.log(alpha) \
                or _contains(other, r):
            continue
        corr = corr_of(r, other)
        bic_gap = (r.delta_chi2 - r.dof * math.log(n_obs)) \
            - (other.delta_chi2 - other.dof * math.log(n_obs))
        if corr > DISTINGUISH_R:
            out.append(Alternative(other, corr, f"{_label(r)} and {_label(other)} cannot "
                                                f"reliably be distinguished (r = {corr:.2f})",
                                   sibling=other in siblings))
        elif other in siblings:
            continue
        elif corr > ALTERNATIVE_R or bic_gap < 2.0:
            out.append(Alternative(other, corr, f"{_label(other)} fits almost as well (chi2 "
                                                f"decrease {other.delta_chi2:.1f} against "
                                                f"{r.delta_chi2:.1f}; r = {corr:.2f})"))
    return out


def _contains(big: TestResult, small: TestResult) -> bool:
    """Whether ``big``'s terms include all of ``small``'s (a fuller form of the same
    terms, not an alternative to them)."""
    return (isinstance(big.candidate, TermsCandidate) and isinstance(small.candidate,
                                                                     TermsCandidate)
            and set(small.comp_names) <= set(big.comp_names))


def _simpler_equivalent(problem: Problem, corr_of: _Correlations, r: TestResult,
                        ranked: list[TestResult], n_family: int, alpha: float
                        ) -> TestResult | None:
    """A significant candidate with fewer parameters to choose instead of ``r`` (the best
    such), else None: one made of part of ``r``'s terms when the rest of ``r`` is not
    significant on its own (at the family's level: a fuller form must earn its extra terms
    as a finding would), or one the data cannot distinguish from ``r`` that explains as
    much."""
    best = None
    for other in ranked:
        if other is r or other.dof >= r.dof \
                or log_p_family(problem, other, n_family) >= math.log(alpha):
            continue
        if _contains(r, other):
            rest = float(pvalues.chi2_logsf(r.delta_chi2 - other.delta_chi2, r.dof - other.dof))
            ok = rest + math.log(n_family) >= math.log(alpha)
        else:
            ok = corr_of(r, other) > DISTINGUISH_R \
                and explains_as_much(problem, other.delta_chi2, other.dof, r)
        if ok and (best is None or other.delta_chi2 > best.delta_chi2):
            best = other
    return best


def select(problem: Problem, candidates: tuple[Candidate, ...] = CANDIDATES,
           alpha: float = ALPHA, max_findings: int = MAX_FINDINGS) -> Selection:
    """Forward selection on ``problem`` (modified in place: accepted columns are added), in
    rounds (the module docstring): each tests the candidates against the current model
    (:func:`_test_round`), chooses one (:func:`_choose`) and adds it (:func:`_accept`)."""
    obs = problem.obs
    known = problem.pred.known_noise
    problem.update_outliers()
    gof_before = problem.gof()
    usable = [c for c in candidates if c.applicable(obs, known)]
    not_applicable = [c.name for c in candidates if c not in usable]
    vocabulary = _single_terms(tuple(usable))
    folds = folds_for(obs)
    steps: list[Step] = []
    refused: list[Refusal] = []
    absorbed: list[TestResult] = []
    accepted: set[str] = set()
    n_family = 0
    first_round: list[TestResult] = []
    stop = "no further candidate is significant"
    channel_results: list[TestResult] = []
    offsets: list[TestResult] = []
    for round_no in range(max_findings + 1):
        perp, z_perp = problem.perp_for(problem.used)
        results = _test_round(problem, usable, accepted, refused, round_no, perp, z_perp)
        if round_no == 0:
            absorbed = [r for r in results if not r.testable]
        results = [r for r in results if r.testable]
        if round_no == 0:
            n_family = max(len(results), 1)
            first_round = list(results)
            channel_results = [r for r in results if r.candidate.kind == "channel"]
        offsets = [r for r in results if r.candidate.kind == "offsets"]
        for r in offsets:
            r.note = ""
        ranked = sorted(offsets, key=lambda r: (log_p_family(problem, r, n_family),
                                                -r.delta_chi2))
        corr_of = _Correlations(problem, perp)
        chosen = _choose(problem, corr_of, ranked, n_family, alpha, folds, refused)
        if chosen is None:
            break
        steps.append(_accept(problem, corr_of, chosen, ranked, n_family, alpha, vocabulary))
        accepted.add(chosen.result.name)
        if len(steps) >= max_findings:
            stop = f"the limit of {max_findings} findings"
            break
        if problem.matches_noise():
            stop = "the residuals match the predicted noise"
            break
    if stop == "no further candidate is significant":
        refused += _below_detection(problem, offsets, n_family, alpha)
    if not known and steps and len(steps) < MAX_FINDINGS_CV:
        added = _cross_validated(problem, usable, accepted, n_family,
                                 MAX_FINDINGS_CV - len(steps))
        steps += added
        kept = {s.result.name for s in added}
        refused = [r for r in refused if r.result.name not in kept]
        if added:
            stop = (f"the limit of {MAX_FINDINGS_CV} findings" if len(steps) >= MAX_FINDINGS_CV
                    else "no further candidate lowers the held-out Sky RMS")
    # channel candidates (other recorded quantities): decided once, in the same family
    sky = problem.sky_rms()
    for r in channel_results:
        lp = log_p_family(problem, r, n_family)
        if lp < math.log(alpha):
            steps.append(Step(r, min(1.0, math.exp(lp)), lp, sky, sky))
    # best first; the cross-validated findings after the significant ones, in the order
    # they were added (each one's held-out figures continue the previous one's)
    steps.sort(key=lambda s: (s.heldout is not None, s.log_p if s.heldout is None else 0.0))
    return Selection(steps, refused, absorbed, first_round, not_applicable, n_family,
                     gof_before, problem.gof(), stop)


def _test_round(problem: Problem, usable: list[Candidate], accepted: set[str],
                refused: list[Refusal], round_no: int, perp, z_perp: np.ndarray
                ) -> list[TestResult]:
    """Each candidate's test against the current model (``perp``, ``z_perp``: its projector
    over the used scans), but those accepted or refused already, and the channel candidates
    after the first round (decided once)."""
    chi2_now = float(z_perp @ z_perp)
    results = []
    for c in usable:
        if c.name in accepted or (c.kind == "channel" and round_no > 0):
            continue
        if any(r.result.name == c.name for r in refused):
            continue
        results.append(c.test(problem, perp, z_perp, chi2_now))
    return results


def _choose(problem: Problem, corr_of: _Correlations, ranked: list[TestResult],
            n_family: int, alpha: float, folds: np.ndarray, refused: list[Refusal]
            ) -> Chosen | None:
    """The round's finding: the first of ``ranked`` (by family p-value) below ``alpha`` that
    predicts held-out data better (those that do not are added to ``refused``), or its
    simpler equivalent where that one does too; None where none passes."""
    def confirmed(r: TestResult) -> Chosen | None:
        chosen = _held_out(problem, r, folds, log_p_family(problem, r, n_family))
        if chosen is None:
            refused.append(Refusal(r, f"{r.name} is significant in-sample but does not "
                                      f"predict held-out data ({r.note})"))
        return chosen

    chosen = None
    for r in ranked:
        if log_p_family(problem, r, n_family) >= math.log(alpha):
            break
        chosen = confirmed(r)
        if chosen is not None:
            break
    if chosen is None:
        return None
    simpler = _simpler_equivalent(problem, corr_of, chosen.result, ranked, n_family, alpha)
    if simpler is not None:
        chosen = confirmed(simpler) or chosen
    return chosen


def _accept(problem: Problem, corr_of: _Correlations, chosen: Chosen,
            ranked: list[TestResult], n_family: int, alpha: float, vocabulary: list[str]
            ) -> Step:
    """Add the chosen finding to the model (outliers rejected again) and say it: its
    alternatives, its separation from the model, its simplest form, the Sky RMS before and
    after, its fitted signal."""
    r, lp = chosen.result, chosen.log_p
    alternatives = _alternatives(problem, corr_of, r, ranked, n_family, alpha)
    separation = Separation(r.r_model, r.partners, local_sigma(problem, r),
                            correlation_words(r.name, r.r_model, r.partners))
    simplest = _simplest_form(problem, r, vocabulary)
    before = problem.sky_rms()
    extra = r.columns  # read once (a result may make its columns again when read)
    after = problem.sky_rms_added(extra)
    signal = _fitted_signal(problem, problem.add(r.name, extra, r.comp_names), extra)
    problem.update_outliers()
    return Step(r, min(1.0, math.exp(lp)), lp, before, after, chosen.cv_chi2_before,
                chosen.cv_chi2_after, alternatives, problem.gof(), signal, separation,
                simplest)


def _cross_validated(problem: Problem, usable: list[Candidate], accepted: set[str],
                     n_family: int, room: int) -> list[Step]:
    """The cross-validated stage (:mod:`.crossval`) as findings, with their statistics (the
    family-corrected p-value of each, every option tried counted as a trial)."""
    out = []
    for added in cv_stage(problem, usable, accepted, _model_terms(problem), room,
                          _fitted_signal):
        res = added.result
        lp = math.log(max(min(1.0, res.p * n_family), 1e-300))
        separation = Separation(res.r_model, res.partners, local_sigma(problem, res),
                                correlation_words(res.name, res.r_model, res.partners))
        out.append(Step(res, math.exp(lp), lp, added.sky_rms_before, added.sky_rms_after,
                        gof_after=problem.gof(), signal=added.signal,
                        separation=separation,
                        heldout=(added.heldout_sky_rms_before, added.heldout_sky_rms_after)))
    return out


def _below_detection(problem: Problem, results: list[TestResult], n_family: int,
                     alpha: float) -> list[Refusal]:
    """Candidates the final model mimics (r > 0.95) whose orthogonal part shows a hint
    (``HINT_SIGMA`` locally) but stays below detection: said in words."""
    out = []
    for r in results:
        if r.r_model <= DISTINGUISH_R or log_p_family(problem, r, n_family) < math.log(alpha):
            continue
        sigma = local_sigma(problem, r)
        if sigma < HINT_SIGMA:
            continue
        needed = sigma_from_p(alpha / (2.0 * n_family * max(r.trials, 1.0)))
        out.append(Refusal(r, f"{correlation_words(r.name, r.r_model, r.partners)}: the part "
                              f"they cannot absorb is {sigma:.1f} sigma, below detection "
                              f"({needed:.1f} sigma here)"))
    return out

"""Honest selection: forward addition of candidate effects, one at a time.

Each round every applicable candidate is tested against the current model (a chi^2 test when
the simulation predicts the noise, an F test when the noise is estimated from the data; a
sin/cos pair is one joint test with 2 degrees of freedom; nonlinear parameters pay for the
look-elsewhere effect with an effective number of trials). The family of candidates is
corrected together (Bonferroni over the candidates tested in the first round), so that data
explained to the noise yield no finding with probability at least 1 - ``ALPHA``; with the
library's 20-odd candidates the criterion is stricter than BIC (``q ln N``) at every N here.

The most significant candidate is then

* refused when its signature correlates with the model above 0.95 (TPOINT's level): "X and Y
  cannot reliably be distinguished";
* refused when it does not lower the chi^2 of held-out data (another night when the data
  span several, else 5-fold cross-validation interleaved in time; nonlinear parameters are
  re-derived on each training set);
* otherwise accepted, and its near-degenerate alternatives (candidates whose fitted
  signatures correlate with it above 0.9, or that fit within 2 of its BIC) are reported
  beside it.

Selection stops when no candidate passes, or as soon as the residuals match the predicted
noise on both axes (p > 0.05), or after ``MAX_FINDINGS``. The polarization and beam-width
candidates test other recorded quantities and are decided once, in the same family.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from . import pvalues
from .candidates.base import DISTINGUISH_R, Candidate, TestResult
from .candidates.library import CANDIDATES
from .problem import Problem, folds_for

__all__ = ["ALPHA", "Selection", "Step", "select", "sigma_from_p"]

#: family-wise false-alarm probability of the whole selection
ALPHA = 0.005
MAX_FINDINGS = 5
#: fitted signatures this correlated are "near-degenerate alternatives"
ALTERNATIVE_R = 0.9


def sigma_from_p(p: float, log_p: float | None = None) -> float:
    """One-sided Gaussian equivalent of a p-value (handles underflow through log p)."""
    if log_p is None:
        log_p = math.log(p) if p > 0 else -745.0
    if log_p > -700:
        return float(pvalues.norm_isf(math.exp(log_p)))
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


@dataclass
class Alternative:
    result: TestResult
    correlation: float
    reason: str


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

    @property
    def significance(self) -> float:
        return sigma_from_p(self.p_family, self.log_p)


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


def _fitted_signal(problem: Problem, res: TestResult) -> np.ndarray:
    """The candidate's fitted error (2n, arcsec) in a joint fit with the current model, less
    the part the model's own terms can take (what the candidate adds)."""
    cols = problem.current_columns()
    full = np.column_stack([cols, res.columns])
    f = problem.fit(full)
    signal = res.columns @ f.coef[cols.shape[1]:]
    beta, *_ = np.linalg.lstsq(problem.T(cols), problem.T(signal), rcond=None)
    return signal - cols @ beta


def _signal_corr(problem: Problem, perp, a: TestResult, b: TestResult) -> float:
    """Correlation of two candidates' fitted signatures after removing the model."""
    if a.columns is None or b.columns is None or a.coef.size == 0 or b.coef.size == 0:
        return 0.0
    sa = perp(a.columns) @ a.coef if a.coef.size == a.columns.shape[1] \
        else perp(a.columns)[:, 0]
    xb = perp(b.columns)
    # how much of a's fitted signature b's span reproduces
    beta, *_ = np.linalg.lstsq(xb, sa, rcond=None)
    num = float(np.linalg.norm(xb @ beta))
    den = float(np.linalg.norm(sa))
    return num / den if den > 0 else 0.0


def select(problem: Problem, candidates: tuple[Candidate, ...] = CANDIDATES,
           alpha: float = ALPHA, max_findings: int = MAX_FINDINGS) -> Selection:
    """Forward selection on ``problem`` (modified in place: accepted columns are added)."""
    obs = problem.obs
    known = problem.pred.known_noise
    problem.update_outliers()
    gof_before = problem.gof()
    usable = [c for c in candidates if c.applicable(obs, known)]
    not_applicable = [c.name for c in candidates if c not in usable]
    folds = folds_for(obs)
    steps: list[Step] = []
    refused: list[Refusal] = []
    absorbed: list[TestResult] = []
    accepted: set[str] = set()
    n_family = 0
    first_round: list[TestResult] = []
    stop = "no further candidate is significant"
    channel_results: list[TestResult] = []
    for round_no in range(max_findings + 1):
        perp, z_perp = problem.perp_for(problem.used)
        chi2_now = float(z_perp @ z_perp)
        results = []
        for c in usable:
            if c.name in accepted or (c.kind == "channel" and round_no > 0):
                continue
            if any(r.result.name == c.name for r in refused):
                continue
            res = c.test(problem, perp, z_perp, chi2_now)
            if not res.testable:
                if round_no == 0:
                    absorbed.append(res)
                continue
            results.append(res)
        if round_no == 0:
            n_family = max(len(results), 1)
            first_round = list(results)
            channel_results = [r for r in results if r.candidate.kind == "channel"]
        offsets = [r for r in results if r.candidate.kind == "offsets"]
        for r in offsets:
            r.note = ""
        ranked = sorted(offsets, key=lambda r: (log_p_family(problem, r, n_family),
                                                -r.delta_chi2))
        chosen = None
        for r in ranked:
            lp = log_p_family(problem, r, n_family)
            if lp >= math.log(alpha):
                break
            if r.r_model > DISTINGUISH_R:
                partners = ", ".join(r.partners) or "the model"
                refused.append(Refusal(r, f"{r.name} and {partners} cannot reliably be "
                                          f"distinguished (r = {r.r_model:.2f})"))
                continue
            cv_without = problem.cv_chi2(problem.current_columns(), folds, used=r.mask)
            cur = problem.current_columns()
            refit = None
            if r.refit is not None:
                def refit(train, _r=r, _cur=cur):
                    return np.column_stack([_cur, _r.refit(train)])
            cv_with = problem.cv_chi2(np.column_stack([cur, r.columns]), folds, refit,
                                      used=r.mask)
            r.note = f"held-out chi2 {cv_without:.1f} -> {cv_with:.1f}"
            if not cv_with < cv_without:
                refused.append(Refusal(r, f"{r.name} is significant in-sample but does not "
                                          f"predict held-out data ({r.note})"))
                continue
            chosen = (r, lp, cv_without, cv_with)
            break
        if chosen is None:
            break
        r, lp, cv0, cv1 = chosen
        alternatives = []
        for other in ranked:
            if other is r or log_p_family(problem, other, n_family) >= math.log(alpha):
                continue
            corr = _signal_corr(problem, perp, r, other)
            n_obs = 2 * int(problem.used.sum())
            bic_gap = (r.delta_chi2 - r.dof * math.log(n_obs)) \
                - (other.delta_chi2 - other.dof * math.log(n_obs))
            if corr > DISTINGUISH_R:
                alternatives.append(Alternative(other, corr, f"{r.name} and {other.name} "
                                                f"cannot reliably be distinguished "
                                                f"(r = {corr:.2f})"))
            elif corr > ALTERNATIVE_R or bic_gap < 2.0:
                alternatives.append(Alternative(other, corr, f"{other.name} fits almost as well "
                                                f"(chi2 decrease {other.delta_chi2:.1f} against "
                                                f"{r.delta_chi2:.1f}; r = {corr:.2f})"))
        before = problem.sky_rms()
        signal = _fitted_signal(problem, r)
        after = problem.sky_rms(np.column_stack([problem.current_columns(), r.columns]))
        problem.extra.append(r.columns)
        problem.extra_names.extend(f"{r.name}:{n}" for n in r.comp_names)
        accepted.add(r.name)
        problem.update_outliers()
        step = Step(r, min(1.0, math.exp(lp)), lp, before, after, cv0, cv1, alternatives,
                    problem.gof(), signal)
        steps.append(step)
        if len(steps) >= max_findings:
            stop = f"the limit of {max_findings} findings"
            break
        if problem.matches_noise():
            stop = "the residuals match the predicted noise"
            break
    # channel candidates (other recorded quantities): decided once, in the same family
    sky = problem.sky_rms()
    for r in channel_results:
        lp = log_p_family(problem, r, n_family)
        if lp < math.log(alpha):
            steps.append(Step(r, min(1.0, math.exp(lp)), lp, sky, sky))
    steps.sort(key=lambda s: s.log_p)
    return Selection(steps, refused, absorbed, first_round, not_applicable, n_family,
                     gof_before, problem.gof(), stop)

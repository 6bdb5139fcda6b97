"""Findings: the decision (:mod:`.decide`), validated (:mod:`.crossval`), then each
finding tested again on every scan for its parameters and its words.

The decision chooses, the cross-validated stage keeps what the repeated decision predicts
held-out data with and what resamples of the data choose again; this module then says it,
in named steps:

* :func:`_test_round`: every candidate tested against the current model on every scan
  (``Candidate.test``: its shapes searched and refined, its parameters fitted), for the
  family (round 0: the candidates tested, ``n_family``) and the words;
* :func:`_result_for`: the finding's own test at the shape the decision chose (a time
  constant or a change time refined around it);
* :func:`_accept`: the finding added to the model (outliers rejected again), with the
  candidates the data cannot tell from it (:class:`Alternative`: each with its physics and
  what observation would tell them apart), how closely the model mimics it
  (:class:`Separation`) and its simplest form (one TPOINT term that explains as much,
  reported).

What the decision refused is said in words (:class:`Refusal`): a significant candidate the
repeated selection does not predict held-out data with, an unstable one, one the model
mimics whose own part stays below detection. The polarization and beam-width candidates test
other recorded quantities and are decided once, at the family's level.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from . import pvalues
from .candidates.base import DISTINGUISH_R, Candidate, TestResult, p_value
from .candidates.library import CANDIDATES
from .candidates.terms import HarmonicFamilyCandidate, TermsCandidate
from .crossval import STABLE_FRACTION, Choice, Plan, Validation, validate
from .decide import ALPHA, MAX_FINDINGS, Design, Option, Pick, parameter_bound, sigma_from_p
from .physics import signature_words, tell_apart
from .problem import Problem, term_columns

__all__ = ["ALPHA", "Selection", "Step", "correlation_words", "select", "sigma_from_p"]

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


def log_p_family(problem: Problem, res: TestResult, n_family: int) -> float:
    """log of a test result's family-corrected p-value (precise far in the tail)."""
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
    return _two_sided(log_p)


def _two_sided(log_p: float) -> float:
    """The two-sided Gaussian equivalent of a p-value given as its log."""
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
    extra parameters add is at most 2 per parameter (Akaike's criterion). Without a noise
    prediction the chi^2 is in units of the fuller model's residual variance."""
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
    """A candidate the data cannot tell from a finding (it predicts each left-out scan as
    well): its test on every scan, how closely their fitted signatures correlate, the words
    (its signature and physics), and what observation would tell the two apart."""

    result: TestResult
    correlation: float
    reason: str
    #: another shape of the finding's own candidate (a harmonic family's other order)
    sibling: bool = False
    tell_apart: str = ""
    #: leave-one-scan-out Sky RMS (arcsec) with it and with the finding (no noise
    #: prediction), else NaN
    heldout: tuple[float, float] = (float("nan"), float("nan"))


@dataclass
class Separation:
    """How closely the model mimics a finding, and how far the data separate them."""

    r: float
    partners: tuple[str, ...]
    sigma: float
    words: str


@dataclass
class SimplestForm:
    """One TPOINT term that explains as much as a finding's pair (reported: the model keeps
    the finding's terms, which the decision chose)."""

    terms: tuple[str, ...]
    delta_chi2: float
    sky_rms_after: float
    words: str


@dataclass
class Step:
    """One finding with its statistics: the decision's (``pick``: its family-corrected
    significance; ``stability``: the fraction of resamples that chose it), its test on every
    scan (``result``: parameters), the in-sample and held-out Sky RMS before and after it
    (arcsec; set by :mod:`.core` from the final model's scans, one figure each)."""

    result: TestResult
    p_family: float
    log_p: float
    sky_rms_before: float
    sky_rms_after: float
    alternatives: list[Alternative] = field(default_factory=list)
    gof_after: dict | None = None
    signal: np.ndarray | None = None  # fitted error of the finding (2n, arcsec)
    separation: Separation | None = None
    simplest: SimplestForm | None = None
    #: (before, after) held-out Sky RMS (arcsec): the nested validation's, with the first
    #: k - 1 and k findings of each fold's own decision
    heldout: tuple[float, float] | None = None
    stability: float | None = None
    n_resamples: int = 0
    #: the finding's signature in words (a harmonic's own, else the candidate's)
    signature: str = ""

    @property
    def significance(self) -> float:
        return sigma_from_p(self.p_family, self.log_p)


@dataclass
class Refusal:
    result: TestResult | None
    reason: str
    #: the candidate refused (its name; the result's where there is one)
    name: str = ""

    def __post_init__(self):
        if not self.name and self.result is not None:
            self.name = self.result.name


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
    #: the decision, validated (None where nothing was decided: no offsets candidate)
    validation: Validation | None = None


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


def select(problem: Problem, candidates: tuple[Candidate, ...] = CANDIDATES,
           alpha: float = ALPHA, max_findings: int = MAX_FINDINGS,
           plan: Plan | None = None, held_out: bool = True) -> Selection:
    """The findings on ``problem`` (modified in place: their columns are added): round 0's
    tests set the family, the decision is made and validated (:func:`.crossval.validate`,
    by ``plan`` or the design's own; ``held_out``: with its nested held-out figures, which
    change nothing in it), and each
    finding is tested again and added in the decision's order (the module docstring)."""
    obs = problem.obs
    known = problem.pred.known_noise
    problem.update_outliers()
    gof_before = problem.gof()
    usable = [c for c in candidates if c.applicable(obs, known)]
    not_applicable = [c.name for c in candidates if c not in usable]
    vocabulary = _single_terms(tuple(usable))
    perp, z_perp = problem.perp_for(problem.used)
    tested = _test_round(problem, usable, set(), [], 0, perp, z_perp)
    absorbed = [r for r in tested if not r.testable]
    results = [r for r in tested if r.testable]
    n_family = max(len(results), 1)
    first_round = list(results)
    channel_results = [r for r in results if r.candidate.kind == "channel"]
    design = Design(problem, usable, n_family)
    validation = validate(design, plan, held_out) \
        if design.options else None
    choice = validation.choice if validation is not None else None
    steps: list[Step] = []
    accepted: set[str] = set()
    offsets = [r for r in results if r.candidate.kind == "offsets"]
    for k, j in enumerate(choice.findings if choice is not None else []):
        if k > 0:  # the words of a round against the model with the findings so far
            perp, z_perp = problem.perp_for(problem.used)
            offsets = [r for r in _test_round(problem, usable, accepted, [], k, perp, z_perp)
                       if r.testable and r.candidate.kind == "offsets"]
        pick = choice.path.picks[j]
        option = design.options[pick.option]
        r = _result_for(problem, option, offsets, perp, z_perp)
        if r is None:
            continue
        alternatives = _alternatives(problem, design, choice, j, r, offsets, perp, z_perp)
        step = _accept(problem, perp, r, pick, alternatives, vocabulary)
        step.stability = choice.stability[j]
        step.n_resamples = choice.n_resamples
        step.signature = signature_words(option.candidate, option.names)
        steps.append(step)
        accepted.add(r.name)
    refused = _refusals(problem, design, choice, alpha) if choice is not None else []
    stop = _stop_words(choice) if choice is not None else "no candidate could be tested"
    # channel candidates (other recorded quantities): decided once, in the same family
    sky = problem.sky_rms()
    for r in channel_results:
        lp = log_p_family(problem, r, n_family)
        if lp < math.log(alpha):
            steps.append(Step(r, min(1.0, math.exp(lp)), lp, sky, sky,
                              signature=r.candidate.signature))
    return Selection(steps, refused, absorbed, first_round, not_applicable, n_family,
                     gof_before, problem.gof(), stop, validation)


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




def _result_for(problem: Problem, option: Option, results: list[TestResult], perp,
                z_perp: np.ndarray) -> TestResult | None:
    """The test on every scan of the decided candidate at the decided shape: the round's
    result where it is at that shape, or refined from it (a time constant, a change time,
    the nonlinear tilt); a family's other order or source tested at the decided one."""
    c = option.candidate
    r = next((r for r in results if r.candidate is c), None)
    if c.look_elsewhere in ("count", "none") and c.linear_signature and (
            r is None or r.theta != option.theta):
        r = next((s for s in (r.siblings if r is not None else [])
                  if s.theta == option.theta), None)
        if r is None:
            cols, names = c.columns(problem.obs, option.theta)
            r = c.linear_test(problem, perp, z_perp, cols, names, option.theta)
        if not r.testable:
            return None
        r.trials = float(len(c.thetas(problem.obs))) if c.look_elsewhere == "count" else 1.0
        c.finish(problem, r)
    return r if r is not None and r.testable else None


def _accept(problem: Problem, perp, r: TestResult, pick: Pick,
            alternatives: list[Alternative], vocabulary: list[str]) -> Step:
    """Add the finding ``r`` to the model (outliers rejected again) and say it: its
    separation from the model, its simplest form, its fitted signal."""
    separation = Separation(r.r_model, r.partners, local_sigma(problem, r),
                            correlation_words(r.name, r.r_model, r.partners))
    simplest = _simplest_form(problem, r, vocabulary)
    before = problem.sky_rms()
    extra = r.columns  # read once (a result may make its columns again when read)
    after = problem.sky_rms_added(extra)
    signal = _fitted_signal(problem, problem.add(r.name, extra, r.comp_names), extra)
    problem.update_outliers()
    return Step(r, min(1.0, math.exp(pick.log_p)), pick.log_p, before, after, alternatives,
                problem.gof(), signal, separation, simplest)


def _alternatives(problem: Problem, design: Design, choice: Choice, j: int, r: TestResult,
                  results: list[TestResult], perp, z_perp: np.ndarray) -> list[Alternative]:
    """The decision's alternatives of pick ``j`` (:func:`.crossval._alternatives`: the data
    cannot tell them from it), each tested on every scan, with its physics and what would
    tell it from the finding."""
    out = []
    path = choice.path
    pick = path.picks[j]
    before = path.cols(j)
    mine = [*before, *pick.cols]
    ones = np.ones(design.u)
    for a in choice.alternatives[j] if j < len(choice.alternatives) else []:
        option = design.options[a.option]
        res = _result_for(problem, option, results, perp, z_perp)
        if res is None:
            continue
        models = [[(design.options[p.option].candidate, design.options[p.option].theta,
                    design.positions(p.option, p.cols)) for p in path.picks[:j]]
                  for _ in range(2)]
        models[0].append((design.options[pick.option].candidate,
                          design.options[pick.option].theta,
                          design.positions(pick.option, pick.cols)))
        models[1].append((option.candidate, option.theta, design.positions(a.option, a.cols)))
        coefs = [design.fit(ones, path.active, path.scale, cols)
                 for cols in (mine, [*before, *a.cols])]
        apart = tell_apart(problem.obs, problem.base_terms, models, coefs)
        held = ""
        if math.isfinite(a.sky_rms):
            held = (f" (left-out scans' Sky RMS {a.sky_rms:.3f}\" against "
                    f"{a.sky_rms_finding:.3f}\")")
        sibling = option.candidate is r.candidate
        what = signature_words(option.candidate, option.names)
        if not sibling:
            what += (", consistent with " + "; ".join(option.candidate.mechanisms)
                     if option.candidate.harmonic else f": {option.candidate.title}")
        how = ("cannot reliably be distinguished from it (r = "
               f"{a.correlation:.2f})" if a.correlation > DISTINGUISH_R else
               "predicts the left-out scans as well")
        reason = (f"{option.label} [{' '.join(option.names)}] ({what}) {how}{held}; to tell "
                  f"them apart: {apart}")
        out.append(Alternative(res, a.correlation, reason, sibling=sibling, tell_apart=apart,
                               heldout=(a.sky_rms, a.sky_rms_finding)))
    return out


def _refusals(problem: Problem, design: Design, choice: Choice, alpha: float
              ) -> list[Refusal]:
    """What the decision chose and did not keep, and what the final model mimics that shows
    a hint (said against the one threshold every finding meets)."""
    out = []
    path = choice.path
    need = sigma_from_p(alpha)
    for j, pick in enumerate(path.picks):
        o = design.options[pick.option]
        if j >= choice.kept:
            before, after = choice.inner[j], choice.inner[j + 1]
            out.append(Refusal(None, f"{o.label} ({pick.significance:.1f} sigma) does not "
                                     f"predict held-out data: the selection repeated on "
                                     f"held-out folds predicts them worse with it "
                                     f"(held-out loss {before:.1f} -> {after:.1f}, units "
                                     "of the noise)" if j == choice.kept else
                                     f"{o.label} ({pick.significance:.1f} sigma) follows "
                                     "a refused finding", o.candidate.name))
        elif j not in choice.findings:
            stable = choice.stability[j] >= STABLE_FRACTION
            out.append(Refusal(None, f"{o.label} ({pick.significance:.1f} sigma) follows an "
                                     "unstable finding" if stable else
                                     f"{o.label} ({pick.significance:.1f} sigma) is "
                                     f"unstable: chosen in {100 * choice.stability[j]:.0f}% "
                                     f"of {choice.n_resamples} bootstrap resamples of the "
                                     f"scans (a finding needs "
                                     f"{100 * STABLE_FRACTION:.0f}%)", o.candidate.name))
    chosen = {design.options[p.option].candidate.name for p in path.picks}
    room = parameter_bound(design.u) - design.m \
        - sum(len(p.cols) for p in path.picks)
    for pick in path.last:
        o = design.options[pick.option]
        if o.candidate.name in chosen or pick.r_model <= DISTINGUISH_R \
                or pick.log_p < math.log(alpha) or pick.dof > room:
            continue
        alone = _two_sided(math.log(max(pick.p_local, 1e-320)))
        if alone < HINT_SIGMA:
            continue
        tried = f" and {pick.trials:.0f} shapes" if pick.trials > 1.0 else ""
        out.append(Refusal(None, f"{o.label} is mimicked by the model (r = "
                                 f"{pick.r_model:.2f}): the part it cannot absorb is "
                                 f"{alone:.1f} sigma alone, {pick.significance:.1f} sigma "
                                 f"corrected for the {design.n_family} candidates{tried} "
                                 f"tried; below detection (every finding needs "
                                 f"{need:.2f} sigma)", o.candidate.name))
    return out


def _stop_words(choice: Choice) -> str:
    """Why the decision stopped, in words."""
    path = choice.path
    if choice.kept < len(path.picks):
        return "the next finding did not predict held-out data"
    return path.stop



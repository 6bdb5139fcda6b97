"""The blind proof: hide a random effect in simulated recordings, diagnose, score.

For each case a random effect is drawn from the library (or none: a null case), with random
shape parameters (phase, time constant, time of a step, source, direction, ...) and an
amplitude between 3 and 10 times its **detection threshold**: the amplitude at which the
expected chi^2 decrease of its test equals the critical value the selection uses (the
family-corrected level ALPHA, the candidate's degrees of freedom and look-elsewhere
trials), computed from the baseline's predicted noise on the scenario's own schedule and
from the part of the signature the baseline terms cannot absorb (the orthogonal part: what
the selection tests). For the exact tilt, whose signature is quadratic in the
tilt, the factor applies to the signature.

An effect that depends on the direction only (a pointing-model term: harmonics, the
elevation eccentricities the ten terms nearly mimic) is hidden as an observatory that had
fitted its model would carry it: the part the baseline terms take (their least-squares fit
to it over the scenario's scans) is in the controller's model in use, so that the scans
measure what the model leaves; the recordings' total errors hold the whole effect. Near-
degenerate effects are thus drawn at 3-10 times their orthogonal threshold whatever their
total size (effects of elevation alone, sin/cos pairs the model nearly mimics),
as are steps at an unknown time and transients after sunset (70" over 1.4 h is only about
4 sigma on the 1990 campaign: weak for its size).

Recordings are simulated with the effect hidden (the diagnosis sees only the recordings and
the original scenario), diagnosed, and scored: a confusion table by effect, the
correct-identification rate on non-null cases, the false-alarm rate on the null cases and
the parameter recovery (the fitted amplitude within 3 sigma of the hidden one).

Effects are drawn only where the data can show them. Not drawn: candidates the library marks
(``blind_exclusion``: e.g. backlash, invisible to five-point scans that always approach the
source from the same side; the exact tilt, whose signature at 3-10 times its threshold
exceeds what the scans measure), candidates whose signature the baseline terms absorb
completely, shapes of which less than 1% survives the baseline's projection (r > 0.99995:
absorbed for every purpose), and shapes whose largest error the model in use leaves at 10
times the threshold would exceed 300" (what a five-point scan with 7' steps measures
faithfully); the report lists them with the reason. Identification is scored strictly (the
first finding names the hidden effect) and group-aware (the first finding reports the
hidden effect as one it "cannot reliably be distinguished" from).
"""

from __future__ import annotations

import math
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from antsim.simulate.runner import recording_meta, simulate
from antsim.world.effects import EFFECTS
from antsim.world.effects.optics import ExactTiltCollimation
from controller.pointing.model import PointingModel

from ..scenario import EffectSpec
from .baseline import SimulatedBaseline
from .candidates.base import DISTINGUISH_R, Candidate
from .candidates.library import CANDIDATES
from .candidates.terms import TermsCandidate
from .core import Diagnosis, diagnose
from .data import Observations, from_rows
from .linalg import lstsq
from .problem import term_columns
from .select import ALPHA

__all__ = ["BlindCase", "BlindReport", "Harness", "absorb_linear", "run_blindtest"]

NULL = "none"
#: shapes of which less survives the baseline's projection (r > 0.99995) are not drawn
MIN_DETECTABLE_FRACTION = 0.01
#: at 10 times its threshold an effect's largest pointing error must stay within what a
#: five-point scan with 7' steps measures faithfully (arcsec)
MAX_ERROR_ARCSEC = 300.0
CASE_SEED_BASE = 50_000_000


@dataclass
class BlindCase:
    index: int
    hidden: str
    params: dict[str, Any]
    factor: float
    threshold: float
    named: str = NULL
    group_ok: bool = False
    findings: list[str] = field(default_factory=list)
    recovered: bool | None = None
    fitted_amplitude: float = float("nan")
    fitted_sigma: float = float("nan")
    hidden_amplitude: float = float("nan")
    seconds: float = 0.0

    @property
    def correct(self) -> bool:
        return self.named == self.hidden

    def to_json(self) -> dict[str, Any]:
        return {"case": self.index, "hidden": self.hidden, "params": self.params,
                "factor": round(self.factor, 3), "threshold": self.threshold,
                "named": self.named, "findings": self.findings, "correct": self.correct,
                "group_correct": self.correct or self.group_ok, "recovered": self.recovered,
                "hidden_amplitude": self.hidden_amplitude,
                "fitted_amplitude": self.fitted_amplitude, "fitted_sigma": self.fitted_sigma}


@dataclass
class BlindReport:
    cases: list[BlindCase]
    excluded: dict[str, str]
    thresholds: dict[str, float]
    seconds: float
    capped: dict[str, str] = field(default_factory=dict)

    def rates(self) -> dict[str, Any]:
        effect = [c for c in self.cases if c.hidden != NULL]
        null = [c for c in self.cases if c.hidden == NULL]
        rec = [c for c in effect if c.recovered is not None]
        return {
            "cases": len(self.cases), "effect_cases": len(effect), "null_cases": len(null),
            "correct": sum(c.correct for c in effect),
            "correct_rate": _rate(sum(c.correct for c in effect), len(effect)),
            "group_correct_rate": _rate(sum(c.correct or c.group_ok for c in effect),
                                        len(effect)),
            "false_alarms": sum(c.named != NULL for c in null),
            "false_alarm_rate": _rate(sum(c.named != NULL for c in null), len(null)),
            "extra_findings_rate": _rate(sum(len(c.findings) > 1 for c in effect), len(effect)),
            "recovered": sum(bool(c.recovered) for c in rec),
            "recovery_rate": _rate(sum(bool(c.recovered) for c in rec), len(rec)),
            "recovery_cases": len(rec),
        }

    def confusion(self) -> dict[str, Counter]:
        table: dict[str, Counter] = {}
        for c in self.cases:
            table.setdefault(c.hidden, Counter())[c.named] += 1
        return table

    def text(self) -> str:
        r = self.rates()
        fam = {c.hidden: _family(c.hidden) for c in self.cases}
        fam.update({c.named: _family(c.named) for c in self.cases})
        names = sorted(set(fam.values()), key=lambda s: (s == NULL, s))
        code = {n: f"{i + 1:>2}" if n != NULL else " 0" for i, n in enumerate(names)}
        width = max(len(n) for n in names) + 6
        lines = ["confusion table by effect (rows: hidden, columns: first finding; families "
                 "of periodic errors pooled over their order n; every case named wrongly is "
                 "listed below it)"]
        lines.append(" " * width + " ".join(f"{code[n]:>3}" for n in names))
        table: dict[str, Counter] = {}
        for c in self.cases:
            table.setdefault(fam[c.hidden], Counter())[fam[c.named]] += 1
        for h in names:
            if h not in table:
                continue
            row = table[h]
            lines.append(f"{code[h]} {h:<{width - 3}}" + " ".join(f"{row.get(n, 0) or '.':>3}"
                                                             for n in names))
        for c in self.cases:
            if c.hidden == c.named:
                continue
            how = ("order missed" if fam[c.hidden] == fam[c.named] else
                   "false alarm" if c.hidden == NULL else "missed")
            said = " (reported as one it cannot be distinguished from)" if c.group_ok else ""
            lines.append(f"   {how}: case {c.index}, hidden {c.hidden}, named {c.named}{said}")
        lines += [
            "",
            f"cases {r['cases']} ({r['effect_cases']} with a hidden effect, {r['null_cases']} "
            "null)",
            f"correct identification {r['correct']}/{r['effect_cases']} = "
            f"{100 * r['correct_rate']:.1f}% (group-aware {100 * r['group_correct_rate']:.1f}%)",
            f"false alarms {r['false_alarms']}/{r['null_cases']} = "
            f"{100 * r['false_alarm_rate']:.1f}%",
            f"amplitude within 3 sigma {r['recovered']}/{r['recovery_cases']} = "
            f"{100 * r['recovery_rate']:.1f}%",
            f"cases with more than one finding {100 * r['extra_findings_rate']:.1f}%",
            f"wall time {self.seconds:.0f} s",
        ]
        if self.capped:
            lines.append("drawn below 10 times their threshold:")
            lines += [f"  {k}: {v}" for k, v in sorted(self.capped.items())]
        if self.excluded:
            lines.append("not drawn (the data cannot show them):")
            lines += [f"  {k}: {v}" for k, v in sorted(self.excluded.items())]
        return "\n".join(lines)

    def to_json(self) -> dict[str, Any]:
        return {"rates": self.rates(),
                "confusion": {h: dict(c) for h, c in self.confusion().items()},
                "excluded": self.excluded, "capped": self.capped,
                "thresholds": self.thresholds,
                "cases": [c.to_json() for c in self.cases], "seconds": self.seconds}


def _family(label: str) -> str:
    return label.split("[")[0]


def _rate(k: int, n: int) -> float:
    return k / n if n else float("nan")


class Harness:
    """Draws, hides and scores; holds the scenario's baseline simulations (cached)."""

    def __init__(self, scenario, n_sims: int = 8, cache_dir=None, use_cache: bool = True,
                 jobs: int = 1, null_fraction: float = 0.2):
        self.scenario = scenario
        self.terms = tuple(scenario.controller.fit_terms or scenario.controller.model.names)
        self.baseline = SimulatedBaseline(scenario, self.terms, n_sims, cache_dir=cache_dir,
                                          use_cache=use_cache, jobs=jobs)
        self.null_fraction = null_fraction
        self.jobs = jobs
        self._reference()

    # ------------------------------------------------------------------ reference geometry
    def _reference(self) -> None:
        """A null recording of the scenario: its scans, predicted noise and the tests'
        degrees of freedom and trials set the thresholds."""
        seed = CASE_SEED_BASE - 1
        res = simulate(self.scenario, seed)
        obs = from_rows(res.rows, recording_meta(self.scenario, seed, res.model))
        self.ref = diagnose(obs, self.scenario, sim_baseline=self.baseline)
        prob = self.ref.problem
        self.n_family = self.ref.selection.n_family
        self.tests = {r.name: r for r in self.ref.selection.first_round}
        self.excluded: dict[str, str] = {}
        #: candidates drawn below 10 times their threshold (their errors would exceed what
        #: a five-point scan measures), with the reason
        self.capped: dict[str, str] = {}
        self.drawable: list[Candidate] = []
        for c in CANDIDATES:
            if c.blind_exclusion:
                self.excluded[c.name] = c.blind_exclusion
            elif not c.applicable(prob.obs, True):
                self.excluded[c.name] = "not applicable to these recordings"
            elif c.name not in self.tests:
                absorbed = [r for r in self.ref.selection.absorbed if r.name == c.name]
                self.excluded[c.name] = ("absorbed completely by the baseline terms"
                                         if absorbed else "not testable on these recordings")
            else:
                self.drawable.append(c)
        self._perp = prob.projector()
        # a candidate none of whose shapes the baseline leaves distinguishable is not drawn
        rng = np.random.default_rng(12345)
        for c in list(self.drawable):
            if c.kind != "offsets":
                continue
            shapes = [c.draw_shape(rng, prob.obs) for _ in range(20)]
            fracs = [self.threshold(c, sh)[1] for sh in shapes]
            best = max(fracs)
            top = [self.top_factor(c, sh) for sh in shapes]
            if best >= MIN_DETECTABLE_FRACTION and max(top) < 3.0:
                self.excluded[c.name] = (f"at 3 times its detection threshold its errors "
                                         f"exceed {MAX_ERROR_ARCSEC:.0f}\", beyond what the "
                                         "five-point scan measures faithfully, for every shape")
                self.drawable.remove(c)
                continue
            if best >= MIN_DETECTABLE_FRACTION and max(top) < 10.0:
                self.capped[c.name] = (f"drawn at 3 to {max(top):.1f} times its threshold at "
                                       f"most: beyond, its errors exceed "
                                       f"{MAX_ERROR_ARCSEC:.0f}\" for every shape")
            if best < MIN_DETECTABLE_FRACTION:
                t = self.tests[c.name]
                r = math.sqrt(max(0.0, 1.0 - best**2))
                self.excluded[c.name] = (f"the baseline terms {', '.join(t.partners) or '(all)'}"
                                         f" absorb it all but 1% (r >= {r:.5f} for every "
                                         "shape)")
                self.drawable.remove(c)

    def critical(self, c: Candidate) -> float:
        return self.tests[c.name].critical_chi2(ALPHA / self.n_family)

    def threshold(self, c: Candidate, shape: dict[str, Any]) -> tuple[float, float]:
        """(detection threshold of the amplitude, detectable fraction of the signature)."""
        prob = self.ref.problem
        crit = self.critical(c)
        if c.kind == "channel":
            sig = c.threshold_sigma(prob.pred, prob.used)
            return math.sqrt(crit) * sig, 1.0
        s = prob.cand(c.nonlinear_part(prob.obs, c.unit_signal(prob.obs, shape)))
        full = float(np.linalg.norm(prob.whiten(s)))
        left = float(np.linalg.norm(self._perp(s[:, None])))
        if left <= 0:
            return float("inf"), 0.0
        lam = left**2
        if c.signal_power(2.0) == 4.0:  # quadratic signature: unit signal at 30'
            return 30.0 * (crit / lam) ** 0.25, left / full
        return math.sqrt(crit / lam), left / full

    def peak(self, c: Candidate, shape: dict[str, Any], amplitude: float) -> float:
        """The largest pointing error (arcsec) of the effect at ``amplitude`` that the model
        in use leaves (:meth:`absorbed` taken off a static effect)."""
        if c.kind == "channel":
            return 0.0
        obs = self.ref.problem.obs
        s = c.nonlinear_part(obs, c.unit_signal(obs, shape))
        if c.static:
            s = s - self.absorbed(s)
        return float(np.max(np.abs(s[np.concatenate([self.ref.problem.valid] * 2)]))) \
            * amplitude

    def top_factor(self, c: Candidate, shape: dict[str, Any]) -> float:
        """The largest factor on the detection threshold (at most 10) at which the effect's
        errors stay within ``MAX_ERROR_ARCSEC``."""
        thr = self.threshold(c, shape)[0]
        if not math.isfinite(thr) or thr <= 0:
            return 0.0
        peak = self.peak(c, shape, thr)
        if c.signal_power(2.0) == 4.0:  # quadratic: the error grows as the factor
            return 10.0 if self.peak(c, shape, 10.0 * thr) <= MAX_ERROR_ARCSEC else 0.0
        return 10.0 if peak <= 0 else min(10.0, MAX_ERROR_ARCSEC / peak)

    def absorbed(self, error: np.ndarray) -> np.ndarray:
        """The part of an error (2n,) on the reference scans that the baseline terms take:
        their unweighted least-squares fit over the valid scans, evaluated everywhere."""
        return self.ref.problem.base @ self.absorbed_terms(error)

    def absorbed_terms(self, error: np.ndarray) -> np.ndarray:
        """The baseline terms' coefficients (arcsec) of :meth:`absorbed`."""
        prob = self.ref.problem
        rows = np.concatenate([prob.valid, prob.valid])
        coef, _ = lstsq(prob.base[rows], error[rows])
        return coef

    # ------------------------------------------------------------------ cases
    def draw(self, index: int, seed: int) -> tuple[Candidate | None, dict, float, float]:
        rng = np.random.default_rng([seed, index])
        if rng.uniform() < self.null_fraction or not self.drawable:
            return None, {}, 0.0, 0.0
        c = self.drawable[int(rng.integers(len(self.drawable)))]
        need = 3.0 if c.name in self.capped else 10.0
        for _ in range(50):
            shape = c.draw_shape(rng, self.ref.problem.obs)
            thr, frac = self.threshold(c, shape)
            top = self.top_factor(c, shape)
            if math.isfinite(thr) and frac >= MIN_DETECTABLE_FRACTION and top >= need:
                break
        factor = float(rng.uniform(3.0, top if c.name in self.capped else 10.0))
        amp = thr * (math.sqrt(factor) if c.signal_power(2.0) == 4.0 else factor)
        params = c.effect_params(shape, amp)
        if c.effect == "source_structure":  # keep the source's catalogue size: only its
            sizes = {s.name: s.size_arcmin for s in self.scenario.sources}  # centroid moves
            params["size_arcmin"] = float(sizes.get(params["source"], 0.0))
        return c, params, factor, thr

    def run_case(self, index: int, seed: int) -> BlindCase:
        t0 = time.perf_counter()
        c, params, factor, thr = self.draw(index, seed)
        scenario = self.scenario
        hidden = NULL if c is None else c.hidden_label(params)
        if c is not None:
            scenario = scenario.with_effects((*scenario.effects, EffectSpec(c.effect, params)))
            if c.name == "exact_tilt_collimation":
                scenario = scenario.with_controller_model(absorb_linear(scenario, params))
            elif c.static:
                scenario = scenario.with_controller_model(self.model_with(c, params))
        case_seed = CASE_SEED_BASE + seed * 10_000 + index
        res = simulate(scenario, case_seed)
        obs = from_rows(res.rows, recording_meta(scenario, case_seed, res.model))
        diag = diagnose(obs, self.scenario, sim_baseline=self.baseline)
        case = BlindCase(index, hidden, _jsonable(params), factor, thr)
        score(case, c, params, diag)
        case.seconds = time.perf_counter() - t0
        return case


    def model_with(self, c: Candidate, params: dict[str, Any]):
        """The controller's model in use with the part of a static effect the baseline
        terms take (:meth:`absorbed`) added to their values."""
        coeffs = hidden_components(c, params)
        obs = self.ref.problem.obs
        error = term_columns(list(coeffs), obs) @ np.array(list(coeffs.values()))
        model = self.scenario.controller.model
        extra = dict(zip(self.ref.problem.base_terms, self.absorbed_terms(error), strict=True))
        values = [v + extra.get(t, 0.0) for t, v in zip(model.names, model.values_arcsec,
                                                        strict=True)]
        missing = [t for t in extra if t not in model.names]
        return PointingModel([*model.names, *missing], [*values, *(extra[t] for t in missing)],
                             model.name)


def absorb_linear(scenario, params: dict[str, Any]):
    """The controller's model in use with the linear part of a large exact tilt added (an
    observatory would already have fitted it; without it the scans miss the source)."""
    model = scenario.controller.model
    az, el = np.meshgrid(np.radians(np.arange(0.0, 360.0, 10.0)),
                         np.radians(np.arange(8.0, 88.0, 4.0)))
    az, el = az.ravel(), el.ravel()
    eff = ExactTiltCollimation(**params)
    a_enc, e_enc = eff.encoder_from_true(az, el)
    d_az = (a_enc - az + math.pi) % (2 * math.pi) - math.pi
    geo = Observations(t_s=np.zeros(az.size), az_rad=az, el_rad=el, xel_arcsec=az * 0,
                       el_arcsec=az * 0, good=np.ones(az.size, bool))
    err = np.concatenate([d_az * np.cos(el), e_enc - el]) * 206264.80624709636
    cols = term_columns(model.names, geo)
    coef, _ = lstsq(cols, err)
    return PointingModel(model.terms, model.values_arcsec + coef, model.name)


def _jsonable(params: dict[str, Any]) -> dict[str, Any]:
    out = {}
    for k, v in params.items():
        if isinstance(v, dict):
            out[k] = _jsonable(v)
        elif isinstance(v, float | np.floating):
            out[k] = round(float(v), 6)
        else:
            out[k] = v
    return out


def hidden_components(c: Candidate, params: dict[str, Any]) -> dict[str, float]:
    """TPOINT coefficients of a hidden harmonic effect."""
    if c.effect and c.effect != "terms":
        eff = EFFECTS[c.effect](**params)
        if hasattr(eff, "coefficients"):
            return eff.coefficients()
    return dict(params.get("terms_arcsec", {}))


def score(case: BlindCase, c: Candidate | None, params: dict[str, Any],
          diag: Diagnosis) -> None:
    """Fill in what was named, whether it was right and how well the amplitude came back."""
    case.findings = [f.result.candidate.label(f.result.theta) for f in diag.findings]
    case.named = case.findings[0] if case.findings else NULL
    if c is None or not diag.findings:
        return
    first = diag.findings[0]
    case.group_ok = any(a.result.candidate.label(a.result.theta) == case.hidden
                        and a.correlation > DISTINGUISH_R for a in first.step.alternatives)
    match = [f for f in diag.findings
             if f.result.candidate.label(f.result.theta) == case.hidden]
    if not match:
        return
    r = match[0].result
    if isinstance(c, TermsCandidate):
        hidden = hidden_components(c, params)
        kept = list(r.comp_names)
        h = np.array([hidden.get(k, 0.0) for k in kept])
        fit = np.array([r.params["terms_arcsec"][k] for k in kept])
        cov = r.cov
        diff = fit - h
        amp_h = float(np.hypot.reduce(h)) if h.size else 0.0
        case.hidden_amplitude = amp_h
        case.fitted_amplitude = float(np.hypot.reduce(fit))
        g = fit / case.fitted_amplitude if case.fitted_amplitude > 0 else np.zeros_like(fit)
        case.fitted_sigma = float(np.sqrt(g @ cov[: len(g), : len(g)] @ g))
        case.recovered = bool(abs(case.fitted_amplitude - amp_h) <= 3 * case.fitted_sigma) \
            if np.all(np.isfinite(diff)) else False
        return
    amp_h = c.hidden_amplitude(params)
    case.hidden_amplitude = float(amp_h)
    case.fitted_amplitude = float(r.amplitude)
    case.fitted_sigma = float(r.amplitude_sigma)
    case.recovered = bool(np.isfinite(r.amplitude_sigma)
                          and abs(r.amplitude - amp_h) <= 3 * r.amplitude_sigma)


_HARNESS: Harness | None = None


def _init_worker(scenario, n_sims: int, cache_dir, use_cache: bool,
                 null_fraction: float) -> None:
    global _HARNESS
    _HARNESS = Harness(scenario, n_sims, cache_dir, use_cache, jobs=1,
                       null_fraction=null_fraction)


def _worker(args):
    index, seed = args
    assert _HARNESS is not None
    return _HARNESS.run_case(index, seed)


def run_blindtest(scenario, n: int = 100, seed: int = 1, n_sims: int = 8, cache_dir=None,
                  use_cache: bool = True, jobs: int = 1, progress=None,
                  harness: Harness | None = None, null_fraction: float = 0.2) -> BlindReport:
    """Run ``n`` blind cases (see the module docstring); ``null_fraction`` of them, on
    average, hide nothing (1: a false-alarm study)."""
    t0 = time.perf_counter()
    harness = harness or Harness(scenario, n_sims, cache_dir, use_cache, jobs,
                                 null_fraction=null_fraction)
    cases: list[BlindCase] = []
    if jobs > 1:
        with ProcessPoolExecutor(max_workers=jobs, initializer=_init_worker,
                                 initargs=(scenario, n_sims, cache_dir, use_cache,
                                           harness.null_fraction)) as pool:
            for case in pool.map(_worker, [(i, seed) for i in range(n)]):
                cases.append(case)
                if progress:
                    progress(case)
    else:
        for i in range(n):
            case = harness.run_case(i, seed)
            cases.append(case)
            if progress:
                progress(case)
    thresholds = {c.name: round(harness.threshold(c, c.draw_shape(
        np.random.default_rng(0), harness.ref.problem.obs))[0], 4) for c in harness.drawable}
    return BlindReport(cases, harness.excluded, thresholds, time.perf_counter() - t0,
                       harness.capped)

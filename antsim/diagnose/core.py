"""``diagnose``: baseline -> locate -> explain -> select, and the report (JSON and words)."""

from __future__ import annotations

import datetime
import math
import time
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from astropy.time import Time

from antsim.world.weather import WeatherModel
from controller.astro.sun import DAY_SUN_MIN_DEG, NIGHT_SUN_MAX_DEG
from controller.pointing.data import PointingData
from controller.pointing.fitting import fit_model
from controller.pointing.model import PointingModel
from controller.pointing.robust import fit_terms_before_after

from ..blas import one_blas_thread
from .baseline import (
    CORRELATED_SCANS,
    BaselineSpec,
    SimulatedBaseline,
    offset_scale,
    residual_correlation,
    resolve_baseline,
    white_prediction,
)
from .candidates.terms import TermsCandidate
from .crossval import STABLE_FRACTION, TermSupport, base_support
from .data import Observations
from .decide import ALPHA, NUMBERS_PER_PARAMETER, parameter_bound, sigma_from_p
from .linalg import lstsq
from .locate import Location, locate, where_signal
from .problem import Prediction, Problem, sky_of, term_columns
from .select import Selection, Step, select

__all__ = ["Diagnosis", "Finding", "diagnose", "plain"]

#: the simulations predict the systematic residual and the noise scan by scan, from their
#: scans of the same source at the same time; a recorded scan without one gets a noise level
#: interpolated in time from the others, which understates it where the schedules diverged
#: (searches, lost scans: the 140-ft at 10500 MHz matches 60-180 of 150-180 scans depending
#: on the seed, and its unmatched scans' declination residuals came out 1.5 times their
#: predicted noise, with findings on 3 of 4 seeds). Below this fraction of scans matched the
#: noise is estimated from the data instead (then no findings on 12 seeds of 12;
#: benchmarks/crane1981_diagnose.py)
MIN_MATCHED_FRACTION = 0.9
#: the lag (s) at which the noise's correlation in time is said in words: successive scans
SUCCESSIVE_S = 300.0


@dataclass
class Finding:
    """One finding, as the JSON of docs/contract.md reports it (plus the selection step)."""

    step: Step
    where: str

    @property
    def result(self):
        return self.step.result

    @property
    def effect(self) -> str:
        c = self.result.candidate
        return c.effect if c.effect and c.effect != "terms" else c.name

    @property
    def terms(self) -> list[str]:
        c = self.result.candidate
        if isinstance(c, TermsCandidate):
            return list(self.result.comp_names)
        return list(c.terms)

    @property
    def params(self) -> dict[str, Any]:
        return plain(self.result.params)

    @property
    def harmonic(self) -> bool:
        """A pure harmonic: named by its signature, its mechanisms not asserted."""
        return bool(self.result.candidate.harmonic)

    def explanation(self) -> str:
        c = self.result.candidate
        if self.harmonic:
            text = (f"{self.step.signature}: a harmonic, consistent with "
                    + "; ".join(c.mechanisms) + ". None of them is asserted: nothing beyond "
                    "the harmonic tells them apart here (a second axis in a fixed relation, "
                    "its phase, a dependence on time or a sensor would).")
        else:
            text = f"{c.title}: {c.explanation}."
        if self.result.absorbed:
            text += (f" Its component(s) {', '.join(self.result.absorbed)} are absorbed by the "
                     "baseline model.")
        return text

    def to_json(self) -> dict[str, Any]:
        s = self.step
        c = self.result.candidate
        out = {
            "effect": self.effect,
            "terms": self.terms,
            "explanation": self.explanation(),
            "where": self.where,
            "params": self.params,
            "significance": round(float(s.significance), 3),
            "sky_rms_before_arcsec": round(float(s.sky_rms_before), 4),
            "sky_rms_after_arcsec": round(float(s.sky_rms_after), 4),
            "signature": s.signature or c.signature,
            "mechanisms": list(c.mechanisms) if self.harmonic else [c.title],
            "mechanism_asserted": not self.harmonic,
            "alternatives": [{"effect": a.result.candidate.name,
                              "label": a.result.candidate.label(a.result.theta),
                              "terms": list(a.result.comp_names),
                              "words": a.reason, "tell_apart": a.tell_apart,
                              "correlation": round(a.correlation, 3)}
                             for a in s.alternatives],
        }
        if s.stability is not None:
            out["stability"] = {"fraction": round(float(s.stability), 3),
                                "resamples": s.n_resamples, "stable": True}
        if s.heldout is not None:
            out["heldout_sky_rms_before_arcsec"] = round(float(s.heldout[0]), 4)
            out["heldout_sky_rms_after_arcsec"] = round(float(s.heldout[1]), 4)
        return out

    def headline(self) -> str:
        """The finding in one line: what it is, its parameters, and its figures."""
        j = self.to_json()
        s = self.step
        shown = {k: v for k, v in j["params"].items() if not isinstance(v, dict)}
        if "amplitude_arcsec" not in shown:  # single terms: their coefficients
            shown = {**j["params"].get("terms_arcsec", {}), **shown}
        params = ", ".join(f"{k} = {_fmt(v)}" for k, v in shown.items())
        terms = f" [{' '.join(j['terms'])}]" if j["terms"] else ""
        name = f"{s.signature}{terms} ({self.label})" if self.harmonic else \
            f"{self.label}{terms}"
        how = [f"{j['significance']:.1f} sigma"]
        if s.stability is not None:
            how.append(f"chosen in {100 * s.stability:.0f}% of {s.n_resamples} resamples")
        how.append(f"Sky RMS {j['sky_rms_before_arcsec']:.2f}\" -> "
                   f"{j['sky_rms_after_arcsec']:.2f}\"")
        if s.heldout is not None:
            how.append(f"held out {s.heldout[0]:.2f}\" -> {s.heldout[1]:.2f}\"")
        return f"{name}: {params} ({'; '.join(how)})"

    @property
    def label(self) -> str:
        return self.result.candidate.label(self.result.theta)


def plain(value: Any) -> Any:
    """``value`` as JSON writes it: numpy scalars as Python numbers, floats rounded to 6
    digits (None where not finite), tuples as lists, keys as strings."""
    if isinstance(value, dict):
        return {str(k): plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [plain(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float):
        return round(value, 6) if math.isfinite(value) else None
    return value


@dataclass
class Diagnosis:
    """Everything diagnosis found, with the report in JSON and in words."""

    obs: Observations
    baseline: BaselineSpec
    prediction: Prediction
    problem: Problem
    location: Location
    selection: Selection
    findings: list[Finding]
    summary: dict[str, Any]
    variants: dict[str, Any] = field(default_factory=dict)
    runtime_s: float = 0.0
    sim_baseline: SimulatedBaseline | None = None
    #: whether each base term predicts left-out scans (:func:`.crossval.base_support`)
    support: list[TermSupport] = field(default_factory=list)

    @property
    def mismatch(self) -> bool:
        return bool(self.findings)

    def updated_model(self) -> PointingModel:
        """The baseline terms refitted together with the findings, plus the findings' TPOINT
        terms (an unweighted least-squares fit of the raw total errors, as TPOINT does): the
        model the decision validated."""
        p = self.problem
        cols = [p.base]
        term_names: list[tuple[str, ...] | None] = []
        for f in self.findings:
            r = f.result
            if r.candidate.kind != "offsets":
                continue
            if isinstance(r.candidate, TermsCandidate):
                terms = tuple(r.comp_names)
                cols.append(p.cand(term_columns(terms, p.obs)))
                term_names.append(terms)
            else:
                cols.append(r.columns)
                term_names.append(None)
        x = np.column_stack(cols)
        rows = p.rows()
        coef, _ = lstsq(x[rows], p.y_raw[rows])
        names = list(p.base_terms)
        values = list(coef[: len(names)])
        k = len(names)
        for terms, block in zip(term_names, cols[1:], strict=True):
            q = block.shape[1]
            for name, v in zip(terms or (), coef[k:k + q], strict=False):
                if name not in names:
                    names.append(name)
                    values.append(float(v))
            k += q
        return PointingModel(p.obs.terms(names), values,
                             name=f"{self.baseline_name()}+diagnose")

    def baseline_name(self) -> str:
        return "baseline"

    def tested(self) -> list[str]:
        """The candidate effects tested against the baseline (the first round's)."""
        return [r.name for r in self.selection.first_round]

    def nothing_found_words(self) -> str:
        """Why nothing was found, and what was tested (the text and the figures say it)."""
        m = len(self.baseline.terms)
        head = (f"nothing beyond the {m} base terms is supported by these data"
                + (": the model explains them to the noise" if self.prediction.known_noise
                   and self.selection.stop_reason.startswith("the residuals match") else ""))
        tested = self.tested()
        return (f"{head}; tested {len(tested)} candidate effects against the baseline "
                f"{' '.join(self.baseline.terms)}: {', '.join(tested)}")

    def rule(self) -> dict[str, Any]:
        """The one rule every finding meets, with this file's numbers."""
        sel = self.selection
        n = self.summary["n_decided"]
        v = sel.validation
        return {"alpha": ALPHA, "sigma": round(sigma_from_p(ALPHA), 2),
                "candidates": sel.n_family,
                "inner_folds": v.plan.k_inner if v is not None else 0,
                "stable_fraction": STABLE_FRACTION,
                "resamples": self.summary["n_resamples"],
                "max_parameters": parameter_bound(n), "numbers": 2 * n,
                "numbers_per_parameter": NUMBERS_PER_PARAMETER}

    def rule_words(self) -> str:
        """:meth:`rule` in words."""
        r = self.rule()
        decided = self.summary.get("decided_on", "every scan")
        where = "" if decided == "every scan" else f"decided on {decided}: "
        return (f"{where}a finding needs {r['sigma']:.2f} sigma once corrected for the "
                f"{r['candidates']} candidates tested (a false alarm in {r['alpha']} of files "
                f"without one), a lower held-out loss with it when the selection is repeated "
                f"on {r['inner_folds']} folds of the data, and to be chosen again in at least "
                f"{100 * r['stable_fraction']:.0f}% of {r['resamples']} bootstrap resamples; "
                f"the model stays within {r['max_parameters']} parameters (a fifth of the "
                f"{r['numbers']} numbers fitted)")

    def support_words(self) -> list[str]:
        """The base terms these data do not support, and why (each stays in the model: it is
        the baseline's), and a baseline larger than the data carry."""
        out = []
        m = len(self.baseline.terms)
        bound = parameter_bound(self.summary["n_decided"])
        if m > bound:
            out.append(f"the {m} base terms exceed the {bound} parameters these "
                       f"{self.summary['n_decided']} scans carry (a fifth of the numbers "
                       "fitted): nothing can be added")
        corr = self._base_correlations()
        el = np.degrees(self.obs.el_rad[self.problem.used])
        span = (f"elevations {el.min():.0f} to {el.max():.0f} deg" if el.size else "")
        for t in self.support:
            if t.supported:
                continue
            rms = (f" ({t.sky_rms_without:.3f}\" without it, {t.sky_rms_with:.3f}\" with it)"
                   if math.isfinite(t.sky_rms_with) else "")
            partners = corr.get(t.term, "")
            out.append(f"{t.term} is not supported by these data: the base model predicts "
                       f"each left-out scan as well without it{rms}"
                       + (f"; {partners}" if partners else "") + f" ({span})")
        return out

    def _base_correlations(self) -> dict[str, str]:
        """Per base term, the base terms its coefficient is confused with (|r| > 0.95 in an
        unweighted fit of the base), in TPOINT's words."""
        p = self.problem
        names = list(p.base_terms)
        rows = p.rows()
        x = term_columns(names, p.obs)[rows]
        _, cov = lstsq(x, p.y_raw[rows])
        sd = np.sqrt(np.clip(np.diag(cov), 0.0, None))
        with np.errstate(invalid="ignore", divide="ignore"):
            corr = cov / np.outer(sd, sd)
        out = {}
        for i, name in enumerate(names):
            near = [f"{names[j]} (r = {corr[i, j]:+.2f})" for j in range(len(names))
                    if j != i and np.isfinite(corr[i, j]) and abs(corr[i, j]) > 0.95]
            if near:
                out[name] = "it cannot reliably be distinguished from " + ", ".join(near)
        return out

    def axes_label(self) -> str:
        """The two offsets in words: "xel/el", or on an equatorial mount "RA/Dec" (the
        cross-declination error is the right-ascension error on the sky)."""
        return "RA/Dec" if self.obs.mount == "equatorial" else "xel/el"

    def degeneracies(self) -> list[str]:
        """TPOINT-style warnings for the final model (coefficient correlations over 0.95:
        "cannot reliably be distinguished"; 0.85-0.95: "strongly correlated"), and the
        refused candidates (held-out data not predicted; mimicked by the model and below
        detection)."""
        p = self.problem
        cols = p.current_columns()
        names = list(p.current_names)
        f = p.fit(cols)
        sd = np.sqrt(np.clip(np.diag(f.cov), 0.0, None))
        out = []
        with np.errstate(invalid="ignore", divide="ignore"):
            corr = f.cov / np.outer(sd, sd)
        for i in range(len(names)):
            for j in range(i + 1, len(names)):
                r = corr[i, j]
                if not np.isfinite(r):
                    continue
                if abs(r) > 0.95:
                    out.append(f"{names[i]} and {names[j]} cannot reliably be distinguished "
                               f"(r = {r:+.2f})")
                elif abs(r) > 0.85:
                    out.append(f"{names[i]} and {names[j]} are strongly correlated "
                               f"(r = {r:+.2f})")
        out += [r.reason for r in self.selection.refused]
        return out

    def to_json(self) -> dict[str, Any]:
        """``antsim diagnose --json`` (docs/contract.md), extended with the rule, the
        baseline and its terms' support, the located mismatch, the refusals and the summary
        statistics."""
        sel = self.selection
        return {
            "mismatch": self.mismatch,
            "findings": [f.to_json() for f in self.findings],
            "rule": self.rule(),
            "baseline": {"terms": list(self.baseline.terms), "origin": self.baseline.origin,
                         "noise": self.prediction.description,
                         "support": [{"term": t.term, "supported": t.supported,
                                      "loss_with": round(t.loss_with, 3),
                                      "loss_without": round(t.loss_without, 3)}
                                     for t in self.support],
                         "words": self.support_words()},
            "located": {"words": self.location.words,
                        "ratio_to_noise": plain(self.location.ratio),
                        "p": plain(self.location.p)},
            "alternatives": [{"finding": f.effect,
                              "alternative": a.result.candidate.label(a.result.theta),
                              "correlation": round(a.correlation, 3), "words": a.reason,
                              "tell_apart": a.tell_apart}
                             for f in self.findings for a in f.step.alternatives],
            "separations": [{"finding": f.effect, "r": round(float(sp.r), 4),
                             "with": list(sp.partners), "sigma": round(float(sp.sigma), 2),
                             "words": sp.words}
                            for f in self.findings if (sp := f.step.separation) is not None],
            "simplest_forms": [{"finding": f.effect, "terms": list(sf.terms),
                                "sky_rms_after_arcsec": round(float(sf.sky_rms_after), 4),
                                "words": sf.words}
                               for f in self.findings if (sf := f.step.simplest) is not None],
            "refused": [{"effect": r.name, "words": r.reason} for r in sel.refused],
            "tested": self.tested(),
            "degeneracies": self.degeneracies(),
            "absorbed": [{"effect": r.name, "components": list(r.absorbed)}
                         for r in sel.absorbed],
            "summary": plain(self.summary),
            "variants": plain(self.variants),
            "stop": sel.stop_reason,
        }

    def text(self) -> str:
        """The report in words."""
        s = self.summary
        lines = [f"{self.obs.path}: {s['n_used']} of {self.obs.n} scans used; baseline "
                 f"{' '.join(self.baseline.terms)} ({self.baseline.origin})",
                 f"noise: {self.prediction.description}",
                 f"rule: {self.rule_words()}",
                 f"located: {self.location.words}"]
        if not self.findings:
            lines.append(self.nothing_found_words())
        for i, f in enumerate(self.findings, 1):
            lines.append(f"{i}. {f.headline()}")
            lines.append(f"   where: {f.where}")
            lines.append(f"   why: {f.explanation()}")
            sp = f.step.separation
            if sp is not None and sp.words:
                lines.append(f"   correlated: {sp.words}; the data separate it by "
                             f"{sp.sigma:.1f} sigma")
            if f.step.simplest is not None:
                lines.append(f"   simplest form: {f.step.simplest.words}")
            lines += [f"   alternative: {w}" for w in _alternative_lines(f.step)]
        for r in self.selection.refused:
            lines.append(f"refused: {r.reason}")
        lines += [f"base: {w}" for w in self.support_words()]
        for w in self.degeneracies():
            if not any(w == r.reason for r in self.selection.refused):
                lines.append(f"model: {w}")
        lines.append(
            f"Sky RMS in-sample {s['sky_rms_before_arcsec']:.2f}\" -> "
            f"{s['sky_rms_after_arcsec']:.2f}\"; held out {s['cv_sky_rms_before_arcsec']:.2f}\" "
            f"-> {s['cv_sky_rms_after_arcsec']:.2f}\" ({s['held_out']})")
        axes = self.axes_label()
        ib, ia = s["axis_rms_before_arcsec"], s["axis_rms_after_arcsec"]
        hb, ha = s["cv_axis_rms_before_arcsec"], s["cv_axis_rms_after_arcsec"]
        lines.append(f"{axes} rms in-sample {ib[0]:.1f}/{ib[1]:.1f}\" -> {ia[0]:.1f}/"
                     f"{ia[1]:.1f}\"; held out {hb[0]:.1f}/{hb[1]:.1f}\" -> {ha[0]:.1f}/"
                     f"{ha[1]:.1f}\"")
        for name, v in self.variants.items():
            if name == "E-D":
                b, a = v["before"], v["after"]
                lines.append(f"Fit E - Fit D ({v['window']}): {b['difference']:+.1f} +- "
                             f"{b['sigma']:.1f}\" -> {a['difference']:+.1f} +- {a['sigma']:.1f}\"")
                continue
            lines.append(f"Fit {name} ({v['window']}): N {v['n']}, {self.axes_label()} rms "
                         f"{v['before']['xel']:.1f}/{v['before']['el']:.1f}\" -> "
                         f"{v['after']['xel']:.1f}/{v['after']['el']:.1f}\"")
        lines.append(f"stopped: {self.selection.stop_reason}")
        return "\n".join(lines)


def _fmt(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def diagnose(obs: Observations, scenario=None, model: str | None = None,
             n_sims: int = 8, cache_dir=None, use_cache: bool = True, jobs: int = 1,
             sim_baseline: SimulatedBaseline | None = None,
             prediction: Prediction | None = None, held_out: bool = True) -> Diagnosis:
    """Diagnose ``obs`` against the baseline (see :mod:`.baseline` for the rules);
    ``held_out``: with the nested held-out figures (:func:`.crossval.nested`: they measure
    the decision and change nothing in it; a procedure repeated inside folds of its own
    needs no more)."""
    # one BLAS thread: diagnose's products are thin (see antsim.blas; 200,000 scans: 43.1 s
    # with two threads against 36.0 s with one on an idle machine)
    with one_blas_thread():
        return _diagnose(obs, scenario, model, n_sims, cache_dir, use_cache, jobs,
                         sim_baseline, prediction, held_out)


def _diagnose(obs: Observations, scenario, model: str | None, n_sims: int, cache_dir,
              use_cache: bool, jobs: int, sim_baseline: SimulatedBaseline | None,
              prediction: Prediction | None, held_out: bool) -> Diagnosis:
    t0 = time.perf_counter()
    if scenario is not None and obs.air_daily_c is None:
        obs = replace(obs, air_daily_c=daily_air_curve(scenario))
    spec = resolve_baseline(obs, scenario, model)
    n_good = int(np.count_nonzero(obs.good))
    if n_good < len(spec.terms):  # antsim fit's rule (controller.pointing.robust)
        raise ValueError(f"{n_good} observations cannot determine {len(spec.terms)} terms; "
                         "observe more positions")
    if prediction is None:
        if scenario is not None:
            if sim_baseline is None:
                seed = obs.meta.get("seed")
                sim_baseline = SimulatedBaseline(scenario, spec.terms, n_sims,
                                                 avoid_seeds=[] if seed is None else [int(seed)],
                                                 cache_dir=cache_dir, use_cache=use_cache,
                                                 jobs=jobs)
            prediction = sim_baseline.predict(obs)
            matched = int(np.sum(prediction.matched)) if prediction.matched is not None \
                else obs.n
            if matched < MIN_MATCHED_FRACTION * obs.n:
                prediction = white_prediction(
                    obs, f"the scenario's simulations do not follow the recorded schedule: "
                         f"{matched} of {obs.n} scans matched")
        else:
            prediction = white_prediction(obs)
    problem = Problem(obs, prediction, spec.terms, offset_scale=offset_scale(obs, scenario))
    problem.update_outliers()
    if not prediction.known_noise and obs.has_time and not prediction.corr_xel \
            and not prediction.corr_el and problem.used.sum() <= CORRELATED_SCANS:
        problem = _correlated(problem, spec.terms, offset_scale(obs, scenario))
        prediction = problem.pred
    location = locate(problem)
    selection = select(problem, held_out=held_out)
    findings = []
    for step in selection.steps:
        if step.signal is not None:
            where = where_signal(obs, step.signal, problem.used)
            special = _special_where(step, obs)
            if special:
                where = f"{special}; {where}"
        else:
            where = _channel_where(step)
        findings.append(Finding(step, where))
    summary = _figures(problem, selection)
    diag = Diagnosis(obs, spec, prediction, problem, location, selection, findings, summary,
                     sim_baseline=sim_baseline)
    if selection.validation is not None:
        diag.support = base_support(selection.validation.design)
    diag.variants = fit_variants_before_after(diag)
    diag.runtime_s = time.perf_counter() - t0
    return diag


def _correlated(problem: Problem, terms, scale: np.ndarray) -> Problem:
    """Recordings in time without a noise prediction: the correlation of their noise in
    time estimated from the base model's residuals (:func:`.baseline.residual_correlation`)
    and the problem made again with it, so that every test and fold treats successive scans
    as the correlated measurements they are (the heat of a day, the weather of an hour);
    the problem as it was where the residuals show none."""
    used = problem.used
    z = problem.fit_current().resid.reshape(2, -1)[:, used] / problem.scale[:, None]
    corr = residual_correlation(problem.obs.t_s[used], z)
    if not any(corr):
        return problem
    at = [sum(w * math.exp(-SUCCESSIVE_S / tau) for w, tau in model) for model in corr]
    pred = replace(problem.pred, corr_xel=corr[0], corr_el=corr[1],
                   description=f"{problem.pred.description}, correlated in time as its "
                               f"residuals show (successive scans {at[0]:.2f} xel, "
                               f"{at[1]:.2f} el)")
    out = Problem(problem.obs, pred, terms, offset_scale=scale)
    out.update_outliers()
    return out


def _figures(problem: Problem, selection: Selection) -> dict[str, Any]:
    """The summary's figures, and each finding's, one truth each: in sample, unweighted fits
    (TPOINT's Sky RMS) of the base and its first k findings over the final model's scans
    (a finding's "after" is the next one's "before", the first's "before" and the last's
    "after" the summary's); held out, the nested validation's (:class:`.crossval.Nested`:
    the first k findings of each fold's own decision, the last finding's and the summary's
    "after" each fold with all its findings)."""
    p = problem
    offsets = [s for s in selection.steps if s.signal is not None]
    k_base = len(p.base_terms)
    cols = p.current_columns()
    widths = [e.shape[1] for e in p.extra]
    raw = []
    for k in range(len(widths) + 1):
        raw.append(p.raw_residuals(np.ascontiguousarray(cols[:, :k_base + sum(widths[:k])])))
    for k, step in enumerate(offsets):
        step.sky_rms_before, step.sky_rms_after = sky_of(raw[k]), sky_of(raw[k + 1])

    def axis_rms(r: np.ndarray) -> list[float]:  # (2, n) residuals -> rms per axis
        return [float(np.sqrt(np.mean(r[a] ** 2))) if r.shape[1] else float("nan")
                for a in range(2)]

    v = selection.validation
    summary: dict[str, Any] = {
        "n_used": int(p.used.sum()),
        "sky_rms_before_arcsec": sky_of(raw[0]),
        "sky_rms_after_arcsec": sky_of(raw[-1]),
        # per axis (cross-axis, then elevation or declination): in-sample and held out
        "axis_rms_before_arcsec": axis_rms(raw[0]),
        "axis_rms_after_arcsec": axis_rms(raw[-1]),
        "gof_before": selection.gof_before, "gof_after": selection.gof_after,
        "n_candidates_tested": selection.n_family,
        "n_decided": int(v.design.u) if v is not None else int(p.used.sum()),
        "decided_on": (f"{v.design.u} of {v.design.n_file} scans (every "
                       f"{-(-v.design.n_file // v.design.u)}th in time)"
                       if v is not None and v.design.u < v.design.n_file else "every scan"),
        "n_resamples": v.choice.n_resamples if v is not None else 0,
    }
    if v is None or v.nested is None:
        nan = float("nan")
        summary.update({"cv_sky_rms_before_arcsec": nan, "cv_sky_rms_after_arcsec": nan,
                        "cv_axis_rms_before_arcsec": [nan, nan],
                        "cv_axis_rms_after_arcsec": [nan, nan], "held_out": "none"})
        return summary
    nst = v.nested
    last = nst.sky_rms.size - 1
    for k, step in enumerate(offsets):
        step.heldout = (nst.at(k), nst.final if k + 1 == len(offsets) else nst.at(k + 1))
    found = sum(bool(c.findings) for c in nst.choices)
    summary.update({
        "cv_sky_rms_before_arcsec": nst.at(0),
        "cv_sky_rms_after_arcsec": nst.final,
        "cv_axis_rms_before_arcsec": [float(x) for x in nst.axis_rms[0]],
        "cv_axis_rms_after_arcsec": [float(x) for x in nst.axis_rms[last]],
        "held_out": (("the whole selection repeated on each fold's training scans, "
                      if v.plan.whole else "the decision repeated on each fold's training "
                      "scans (its significance tests alone at this size), ")
                     + f"{nst.folds.words}; it found something on {found} of {nst.folds.k}"),
        "cv_folds": nst.folds.k, "cv_folds_with_findings": found,
        "cv_sky_rms_by_findings_arcsec": [float(x) for x in nst.sky_rms],
    })
    return summary


def daily_air_curve(scenario):
    """The scenario's deterministic daily air-temperature curve (C) at campaign times (s)."""
    hours = (Time(scenario.epoch_utc, scale="utc").mjd % 1.0) * 24.0
    model = WeatherModel(scenario.weather, hours, scenario.site.longitude_deg,
                         scenario.duration_s, np.random.default_rng(0))
    return model.daily_curve_c


def _special_where(step: Step, obs: Observations) -> str:
    """Words for the time-like effects, whose signature is best said in time."""
    r = step.result
    p = r.params
    if r.name == "sunset_drift":
        tau_h = p["tau_s"] / 3600.0
        return (f"elevation changes by {p['amplitude_arcsec']:+.0f}\" after sunset, "
                f"{100 * (1 - math.exp(-4.0 / tau_h)):.0f}% of it in the first 4 hours "
                f"(time constant {tau_h:.1f} h), and relaxes back after sunrise")
    if r.name == "sunset_transient":
        tau_h = p["tau_s"] / 3600.0
        return (f"elevation changes by {p['amplitude_arcsec']:+.0f}\" at sunset and dies away "
                f"with time constant {tau_h:.1f} h (95% of it gone {3 * tau_h:.1f} h later)")
    if r.name == "step":
        zero = "azimuth" if p["axis"] == "az" else "elevation"
        return (f"the {zero} zero point changes by {p['step_arcsec']:+.1f}\" at "
                f"{_clock(obs, p['t_s'])} and stays changed (95% interval "
                f"{_clock(obs, p['t_low_s'])} to {_clock(obs, p['t_high_s'])}): a step, "
                "not a drift")
    if r.name == "temperature_drift":
        return (f"elevation follows the air temperature, {p['arcsec_per_k']:+.2f}\"/K, "
                f"lagging it by {p['tau_s'] / 3600.0:.1f} h")
    if r.name == "clock_error":
        return (f"along each source's apparent motion, growing as the clock drifts "
                f"({p['drift_s_per_day']:+.2f} s/day)")
    if r.name == "source_structure":
        return f"on {p['source']} only"
    return ""


def _alternative_lines(step: Step) -> list[str]:
    """One line per candidate among a finding's alternatives: a harmonic family's orders
    said together (each is an alternative of its own in the JSON)."""
    by: dict[str, list] = {}
    for a in step.alternatives:
        by.setdefault(a.result.candidate.name, []).append(a)
    out = []
    for alts in by.values():
        if len(alts) == 1:
            out.append(alts[0].reason)
            continue
        c = alts[0].result.candidate
        alts.sort(key=lambda a: a.result.theta)
        shapes = ", ".join(str(a.result.theta) for a in alts)
        held = [a.heldout[0] for a in alts if math.isfinite(a.heldout[0])]
        rms = (f" (left-out scans' Sky RMS {min(held):.3f}-{max(held):.3f}\" against "
               f"{alts[0].heldout[1]:.3f}\")" if held else "")
        what = (", consistent with " + "; ".join(c.mechanisms) if c.harmonic
                else f": {c.title}")
        apart = alts[0].tell_apart + (f" (for n = {alts[0].result.theta})"
                                      if c.harmonic else "")
        out.append(f"{c.name} with {'n' if c.harmonic else 'shape'} = {shapes} ({c.signature}"
                   f"{what}) predict the left-out scans as well{rms}; to tell them apart: "
                   f"{apart}")
    return out


def _clock(obs: Observations, t_s: float) -> str:
    """A campaign time (s) in words: UTC when the recordings name their epoch, and hours
    after the start."""
    epoch = obs.meta.get("epoch_utc")
    hours = f"{t_s / 3600.0:.2f} h after the start"
    if not epoch:
        return hours
    try:
        start = datetime.datetime.fromisoformat(str(epoch))
    except ValueError:
        return hours
    return f"{(start + datetime.timedelta(seconds=float(t_s))):%H:%M} UTC ({hours})"


def _channel_where(step: Step) -> str:
    r = step.result
    if r.name == "polarization_squint":
        p = r.params
        return (f"XR minus XL offsets: {p['xr_minus_xl_xel_arcsec']:+.1f}\" cross-elevation, "
                f"{p['xr_minus_xl_el_arcsec']:+.1f}\" elevation, on every scan; the "
                "polarization average is unaffected")
    if r.name == "beam_width":
        return (f"measured beam widths on every scan, {100 * (r.params['scale'] - 1):+.1f}% "
                "from the predicted ones")
    return "recorded quantities other than the offsets"


def fit_variants_before_after(diag: Diagnosis) -> dict[str, Any]:
    """Fit D (day, Sun above 0 deg) and E (night, Sun below -12 deg) of the 1990 report on
    the baseline terms, before and after removing the findings' fitted signatures."""
    obs = diag.obs
    if obs.sun_el_deg is None:
        return {}
    p = diag.problem
    cols = p.current_columns()
    rows = p.rows()
    coef, _ = lstsq(cols[rows], p.y_raw[rows])
    k = len(p.base_terms)
    signal = cols[:, k:] @ coef[k:] if cols.shape[1] > k else np.zeros(2 * obs.n)
    n = obs.n
    zero = _el_zero_term(p)
    out = {}
    fit_a: dict[str, Any] = {}  # Fit A (every good scan) by label: the split below reuses it
    good = obs.good
    windows = {"D": ("day, Sun above 0 deg", obs.sun_el_deg > DAY_SUN_MIN_DEG),
               "E": ("night, Sun below -12 deg", obs.sun_el_deg < NIGHT_SUN_MAX_DEG),
               "A": ("all", np.ones(n, dtype=bool))}
    fitted = [name for name, (_, mask) in windows.items()
              if (mask & good).sum() >= 2 * len(p.base_terms)]
    # the windows are subsets of Fit A's scans: its data and design once (a window's are
    # their rows), and its LAD where the windows' start
    fits: dict[str, Any] = {}
    if "A" in fitted:
        order = ["A", *(name for name in fitted if name != "A")]
        fits = dict(zip(order, fit_terms_before_after(
            PointingData(obs.az_rad[good], obs.el_rad[good], obs.xel_arcsec[good],
                         obs.el_arcsec[good]),
            PointingModel(obs.terms(p.base_terms)), signal[:n][good], signal[n:][good],
            [windows[name][1][good] for name in order[1:]]), strict=True))
    for name in fitted:
        if isinstance(fits.get(name, ValueError()), ValueError):
            continue
        res = {}
        for label, f in zip(("before", "after"), fits[name], strict=True):
            if name == "A":
                fit_a[label] = f
            res[label] = {"xel": f.xel_rms_arcsec, "el": f.el_rms_arcsec,
                          "sky": f.sky_rms_arcsec, "n_used": f.n_used}
            if zero is not None:
                j = f.names.index(zero)
                res[label]["el_zero"] = float(f.values_arcsec[j])
                res[label]["el_zero_sigma"] = float(f.sigma_arcsec[j])
        out[name] = {"window": windows[name][0], "n": int((windows[name][1] & good).sum()),
                     **res}
    # the common fit (Fit A) seen in the day and night windows: a drift the separate fits
    # absorb into their zero points shows here
    m = obs.good
    split = {}
    for label, sx, se in (("before", 0.0, 0.0), ("after", signal[:n], signal[n:])):
        data = PointingData(obs.az_rad[m], obs.el_rad[m], (obs.xel_arcsec - sx)[m],
                            (obs.el_arcsec - se)[m])
        try:
            f = fit_a[label] if label in fit_a else fit_model(data, obs.terms(p.base_terms),
                                                              robust=True)
        except ValueError:
            split = {}
            break
        used = np.asarray(f.used)
        sun = obs.sun_el_deg[m]
        rx = np.asarray(f.residual_xel_arcsec)
        re_ = np.asarray(f.residual_el_arcsec)
        for key, win in (("D", sun > DAY_SUN_MIN_DEG), ("E", sun < NIGHT_SUN_MAX_DEG)):
            sel = used & win
            if sel.sum() < 3:
                continue
            split.setdefault(key, {})[label] = {
                "xel": float(np.sqrt(np.mean(rx[sel] ** 2))),
                "el": float(np.sqrt(np.mean(re_[sel] ** 2))), "n_used": int(sel.sum())}
    for key, v in split.items():
        if len(v) == 2:
            out[f"A:{key}"] = {"window": ("day" if key == "D" else "night")
                               + " scans of the common fit (Fit A)", "n": v["before"]["n_used"],
                               **v}
    if zero is not None and "D" in out and "E" in out:
        for label in ("before", "after"):
            d, e = out["D"][label], out["E"][label]
            out.setdefault("E-D", {"window": f"night minus day {zero}", "term": zero})[label] = {
                "difference": e["el_zero"] - d["el_zero"],
                "sigma": math.hypot(e["el_zero_sigma"], d["el_zero_sigma"])}
    return out


def _el_zero_term(p: Problem) -> str | None:
    """The baseline term that is a constant elevation offset (IE, W1), if any."""
    cols = p.base
    n = p.n
    for j, name in enumerate(p.base_terms):
        x, e = cols[:n, j], cols[n:, j]
        if np.allclose(x, 0.0) and np.ptp(e) < 1e-9 * max(1.0, float(np.abs(e).max())):
            return name
    return None

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
    BaselineSpec,
    SimulatedBaseline,
    offset_scale,
    resolve_baseline,
    white_prediction,
)
from .candidates.terms import TermsCandidate
from .data import Observations
from .linalg import lstsq
from .locate import Location, locate, where_signal
from .problem import (
    Prediction,
    Problem,
    folds_for,
    folds_words,
    heldout_sky_rms,
    sky_of,
    term_columns,
)
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

    def explanation(self) -> str:
        c = self.result.candidate
        text = f"{c.title}: {c.explanation}."
        if self.result.absorbed:
            text += (f" Its component(s) {', '.join(self.result.absorbed)} are absorbed by the "
                     "baseline model.")
        return text

    def to_json(self) -> dict[str, Any]:
        s = self.step
        return {
            "effect": self.effect,
            "terms": self.terms,
            "explanation": self.explanation(),
            "where": self.where,
            "params": self.params,
            "significance": round(float(s.significance), 3),
            "sky_rms_before_arcsec": round(float(s.sky_rms_before), 4),
            "sky_rms_after_arcsec": round(float(s.sky_rms_after), 4),
        }


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

    @property
    def mismatch(self) -> bool:
        return bool(self.findings)

    def updated_model(self) -> PointingModel:
        """The baseline terms refitted together with the findings, plus the findings' TPOINT
        terms (an unweighted least-squares fit of the raw total errors, as TPOINT does); a
        finding with a simplest form (one term explaining as much as its pair) enters in
        that form."""
        p = self.problem
        cols = [p.base]
        term_names: list[tuple[str, ...] | None] = []
        for f in self.findings:
            r = f.result
            if r.candidate.kind != "offsets":
                continue
            if isinstance(r.candidate, TermsCandidate):
                terms = f.step.simplest.terms if f.step.simplest else tuple(r.comp_names)
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
        head = ("no mismatch: the model explains the data to the noise"
                if self.prediction.known_noise else
                "nothing beyond the baseline terms is warranted by these data")
        tested = self.tested()
        return (f"{head}; tested {len(tested)} candidate effects against the baseline "
                f"{' '.join(self.baseline.terms)}: {', '.join(tested)}")

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
        """``antsim diagnose --json`` (docs/contract.md), extended with the baseline, the
        located mismatch, the refusals and the summary statistics."""
        sel = self.selection
        return {
            "mismatch": self.mismatch,
            "findings": [f.to_json() for f in self.findings],
            "baseline": {"terms": list(self.baseline.terms), "origin": self.baseline.origin,
                         "noise": self.prediction.description},
            "located": {"words": self.location.words,
                        "ratio_to_noise": plain(self.location.ratio),
                        "p": plain(self.location.p)},
            "alternatives": [{"finding": f.effect,
                              "alternative": a.result.candidate.label(a.result.theta),
                              "correlation": round(a.correlation, 3), "words": a.reason}
                             for f in self.findings for a in f.step.alternatives],
            "separations": [{"finding": f.effect, "r": round(float(sp.r), 4),
                             "with": list(sp.partners), "sigma": round(float(sp.sigma), 2),
                             "words": sp.words}
                            for f in self.findings if (sp := f.step.separation) is not None],
            "simplest_forms": [{"finding": f.effect, "terms": list(sf.terms),
                                "sky_rms_after_arcsec": round(float(sf.sky_rms_after), 4),
                                "words": sf.words}
                               for f in self.findings if (sf := f.step.simplest) is not None],
            "refused": [{"effect": r.result.name, "words": r.reason} for r in sel.refused],
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
                 f"located: {self.location.words}"]
        if not self.findings:
            lines.append(self.nothing_found_words())
        for i, f in enumerate(self.findings, 1):
            j = f.to_json()
            shown = {k: v for k, v in j["params"].items() if not isinstance(v, dict)}
            if "amplitude_arcsec" not in shown:  # single terms: their coefficients
                shown = {**j["params"].get("terms_arcsec", {}), **shown}
            params = ", ".join(f"{k} = {_fmt(v)}" for k, v in shown.items())
            terms = f" [{' '.join(j['terms'])}]" if j["terms"] else ""
            how = (f"{j['significance']:.1f} sigma" if f.step.heldout is None else
                   f"kept by cross-validation: held-out Sky RMS {f.step.heldout[0]:.2f}\" -> "
                   f"{f.step.heldout[1]:.2f}\", {j['significance']:.1f} sigma alone")
            lines.append(f"{i}. {f.effect}{terms}: {params} ({how}; Sky RMS "
                         f"{j['sky_rms_before_arcsec']:.2f}\" -> "
                         f"{j['sky_rms_after_arcsec']:.2f}\")")
            lines.append(f"   where: {j['where']}")
            lines.append(f"   why: {j['explanation']}")
            sp = f.step.separation
            if sp is not None and sp.words:
                lines.append(f"   correlated: {sp.words}; the data separate it by "
                             f"{sp.sigma:.1f} sigma")
            if f.step.simplest is not None:
                lines.append(f"   simplest form: {f.step.simplest.words}")
            lines += [f"   alternative: {a.reason}" for a in f.step.alternatives
                      if not a.sibling]
            lines += _orders_line(f)
        for r in self.selection.refused:
            lines.append(f"refused: {r.reason}")
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
             prediction: Prediction | None = None) -> Diagnosis:
    """Diagnose ``obs`` against the baseline (see :mod:`.baseline` for the rules)."""
    # one BLAS thread: diagnose's products are thin (see antsim.blas; 200,000 scans: 43.1 s
    # with two threads against 36.0 s with one on an idle machine)
    with one_blas_thread():
        return _diagnose(obs, scenario, model, n_sims, cache_dir, use_cache, jobs,
                         sim_baseline, prediction)


def _diagnose(obs: Observations, scenario, model: str | None, n_sims: int, cache_dir,
              use_cache: bool, jobs: int, sim_baseline: SimulatedBaseline | None,
              prediction: Prediction | None) -> Diagnosis:
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
    location = locate(problem)
    selection = select(problem)
    base_cols = problem.base  # now a view of the final model's columns
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
    folds = folds_for(obs)
    final = problem.current_columns()

    def axis_rms(r: np.ndarray) -> list[float]:  # (2, n) residuals -> rms per axis
        return [float(np.sqrt(np.mean(r[a] ** 2))) if r.shape[1] else float("nan")
                for a in range(2)]

    # each model's held-out residuals once (a QR of the whole and a pass per night), and
    # its in-sample ones once (the Sky RMS and the axes' rms from the same fit)
    held = [problem.heldout_residuals(c, folds) for c in (base_cols, final)]
    raw = [problem.raw_residuals(c) for c in (base_cols, final)]
    summary = {
        "n_used": int(problem.used.sum()),
        "sky_rms_before_arcsec": sky_of(raw[0]),
        "sky_rms_after_arcsec": sky_of(raw[1]),
        "cv_sky_rms_before_arcsec": heldout_sky_rms(held[0]),
        "cv_sky_rms_after_arcsec": heldout_sky_rms(held[1]),
        # per axis (cross-axis, then elevation or declination): in-sample and held out
        "axis_rms_before_arcsec": axis_rms(raw[0]),
        "axis_rms_after_arcsec": axis_rms(raw[1]),
        "cv_axis_rms_before_arcsec": axis_rms(held[0]),
        "cv_axis_rms_after_arcsec": axis_rms(held[1]),
        "held_out": folds_words(obs),
        "gof_before": selection.gof_before, "gof_after": selection.gof_after,
        "n_candidates_tested": selection.n_family,
    }
    diag = Diagnosis(obs, spec, prediction, problem, location, selection, findings, summary,
                     sim_baseline=sim_baseline)
    diag.variants = fit_variants_before_after(diag)
    diag.runtime_s = time.perf_counter() - t0
    return diag


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


def _orders_line(f: Finding) -> list[str]:
    """One line per harmonic family for its orders the data cannot tell from the finding
    (each is an alternative of its own in the JSON)."""
    by: dict[str, list] = {}
    for a in f.step.alternatives:
        if a.sibling:
            by.setdefault(a.result.candidate.name, []).append(a)
    r = f.result
    out = []
    for name, alts in by.items():
        alts.sort(key=lambda a: int(a.result.theta))
        orders = ", ".join(str(int(a.result.theta)) for a in alts)
        lo, hi = min(a.correlation for a in alts), max(a.correlation for a in alts)
        out.append(f"   alternative: {r.candidate.label(r.theta)} and {name} with n = "
                   f"{orders} cannot reliably be distinguished (r = "
                   + (f"{lo:.2f})" if f"{lo:.2f}" == f"{hi:.2f}" else f"{lo:.2f}-{hi:.2f})"))
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

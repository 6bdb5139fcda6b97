"""Answers, not only tables: how long, which sources, and which terms a plan cannot separate.

* How long (:func:`duration_answer`): the smallest duration (hours, days or nights) of a
  variant's plan that brings the predicted sigma of chosen terms to a target. The variant is
  simulated once (deterministically) for ``max_days``; the scheduler is causal, so the first
  N hours of that schedule are the N-hour campaign, and the prediction is evaluated on every
  prefix (:func:`antsim.plan.fisher.predict_prefixes`: the sandwich of each prefix, and one
  simulation of the robust fit's rejections for all of them). The systematic bias of the
  terms (the same in every campaign) is reported beside: it does not shrink with time.
* Coverage (:func:`coverage_answer`): from the same long run when a duration question asks
  for it too (one simulation answers both).
* Which sources (:func:`sources_shortlist`, :func:`sources_answer`): every subset of the
  catalogue is ranked by a D-optimal proxy (each of the variant's scan slots shared among
  the subset's sources visible then, within the revisit limit, weighted by the predicted
  noise of scans of that source); the best few, and the list as planned, are then predicted
  exactly from their own deterministic schedules. Criterion: the determinant of the
  predicted covariance of the fitted terms, or the largest sigma of the chosen terms.
* Separation: pairs of terms with |correlation| above the plan's level, per variant.

Each deterministic run the answers need is a chain of tasks (:mod:`antsim.simulate.flow`) on
the executor of the plan's members: its schedule, its noise model, the rejections' draws in
parts. :class:`Questions` starts them (those that need no variant beside the members) and
assembles the answers; every number is the same whatever the workers.
"""

from __future__ import annotations

import itertools
import math
import uuid
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from antsim.figures.html import format_number
from antsim.simulate.ensemble import Executor, Job, task_record
from antsim.simulate.flow import Chain, Flow, Handle, Task
from antsim.simulate.runner import check_scenario
from antsim.simulate.vectorized import SharedSchedule, quiet_scenario
from controller.astro.sun import DAY_SUN_MIN_DEG, NIGHT_SUN_MAX_DEG
from controller.errors import InputError
from controller.pointing.model import PointingModel
from controller.program.campaign import plan_targets

from ..progress import span_words
from .fisher import (
    COMPONENTS,
    REJECTION_DRAWS,
    NoiseModel,
    Prediction,
    RejectionDraws,
    predict_prefixes,
    rejection_design,
    rejection_draws,
    task_noise,
    task_thermal,
    truth_vector,
    with_thermal,
)
from .planfile import CoverageQuestion, DurationQuestion, Plan, SourcesQuestion

__all__ = ["Questions", "answers_text", "coverage_answer", "duration_answer",
           "duration_points", "reachable_cells", "sources_answer", "sources_shortlist"]

#: thermal draws for the noise models of the answers' (longer) schedules
N_THERMAL_ANSWERS = 128
#: scans further apart than this start a new day or night period (s)
PERIOD_GAP_S = 3 * 3600.0
#: largest catalogue whose subsets are all ranked (else greedy forward selection)
MAX_EXHAUSTIVE = 12
#: parts (tasks) the rejections' draws of a duration question are cut into: fixed, so that
#: the answer is the same for any number of workers
REJECTION_PARTS = 8
#: the answers' long runs first: they are the longest chains of the plan
LONG_RUN_PRIORITY = 2


@dataclass
class Predicted:
    """A deterministic run of an answer: its schedule, noise model, fitted terms, and the
    predictions of the prefixes asked for (a list per entry of :func:`predicted_run`'s
    ``ends_of``, a prediction per prefix)."""

    scenario: Any
    shared: SharedSchedule
    noise: NoiseModel | None = None
    terms: tuple[str, ...] = ()
    predictions: list[list[Prediction]] = field(default_factory=list)


def predicted_run(scenario, plan: Plan, executor: Executor, ends_of: list[Callable],
                  parts: int, priority: int = 0) -> Chain:
    """The chain of one deterministic run of ``scenario``: its schedule; when ``ends_of``
    asks for predictions, its noise model (its thermal draws a task of their own beside
    it) and, per entry, the predictions of the prefixes ``ends_of[i](scenario, shared,
    noise)`` (the schedule's scan counts; None: all), the rejections' draws of each entry
    in ``parts`` tasks. Three steps and ``parts`` per entry in all (one without
    predictions)."""
    span = span_words(scenario.duration_s)
    quiet = quiet_scenario(scenario)
    shared = yield Task(task_record, (quiet,), "answer", f"schedule{{s}} of {span}", priority)
    run = Predicted(scenario, shared)
    if not ends_of:
        return run
    terms, fit_name = scenario.controller.fit_spec()
    job = executor.share(Job(f"answer:{uuid.uuid4().hex}", scenario, quiet, shared,
                             tuple(terms), fit_name, plan.seed))
    # the noise model and its thermal draws at once, two tasks (the longest of the plan)
    (noise, _), thermal = yield [
        Task(task_noise, (job, 0), "answer", f"noise model{{s}} of {span}", priority),
        Task(task_thermal, (job, N_THERMAL_ANSWERS), "answer",
             f"sampling{{s}} of the slow errors over {span}", priority)]
    noise = with_thermal(noise, shared, thermal)
    ends = [f(scenario, shared, noise) for f in ends_of]
    designs = [rejection_design(shared, terms, noise, e) for e in ends]
    cuts = np.array_split(np.arange(REJECTION_DRAWS), parts)
    done = yield [Task(rejection_draws, (design, tuple(int(j) for j in cut)), "answer",
                       "part{s} of the rejections' draws", priority)
                  for design in designs for cut in cuts]
    truth = truth_vector(scenario, terms)
    for i, e in enumerate(ends):
        draws = RejectionDraws.concat(done[i * parts:(i + 1) * parts])
        run.predictions.append(predict_prefixes(shared, terms, noise, e, truth, draws))
    run.noise, run.terms = noise, tuple(terms)
    return run


class Questions:
    """The questions of ``plan`` as chains on a :class:`~antsim.simulate.flow.Flow` (the
    long runs of the durations and coverage with :meth:`start`, the source lists, which need
    their variant, with :meth:`start_after`); :meth:`answers` once the flow has run them.
    ``steps``: the tasks of the chains started, for the progress."""

    def __init__(self, plan: Plan, executor: Executor,
                 log: Callable[[str], None] | None = None):
        self.plan = plan
        self.executor = executor
        self.log = log or (lambda _message: None)
        self.steps = 0
        self._long: dict[tuple[int, float], tuple[Handle, list[DurationQuestion]]] = {}
        self._sources: list[tuple[SourcesQuestion, dict[str, Any], list[Handle | None]]] = []

    @property
    def n_questions(self) -> int:
        p = self.plan
        return len(p.durations) + len(p.sources) + len(p.coverage)

    def start(self, flow: Flow) -> None:
        """The long deterministic runs: one per variant and length asked for, whichever
        questions (how long, coverage) ask it."""
        p = self.plan
        runs: dict[tuple[int, float], list[DurationQuestion]] = {}
        for q in [*p.durations, *p.coverage]:
            runs.setdefault(_long_key(q, p), [])
        for q in p.durations:
            goal = (f"{q.target_arcsec:g}\"" if q.target_arcsec is not None
                    else "their targets")
            self.log(f"answering {q.key}: {', '.join(q.terms)} to {goal} "
                     f"({q.based_on}, up to {q.max_days:g} days)")
            runs[_long_key(q, p)].append(q)
        for q in p.coverage:
            self.log(f"answering {q.key}: coverage below dec {q.dec_max_deg:g} deg "
                     f"({q.based_on}, up to {q.max_days:g} days)")
        for key, durations in runs.items():
            q0 = next(q for q in [*p.durations, *p.coverage] if _long_key(q, p) == key)
            ends_of = [_ends_of(q) for q in durations]
            chain = predicted_run(duration_scenario(q0, p), p, self.executor, ends_of,
                                  REJECTION_PARTS, LONG_RUN_PRIORITY)
            self._long[key] = (flow.start(chain), durations)
            self.steps += 1 + (2 + REJECTION_PARTS * len(durations) if durations else 0)

    def start_after(self, flow: Flow, variants: list) -> None:
        """The candidate source lists of each sources question: each one's deterministic
        run, noise model and prediction."""
        for q in self.plan.sources:
            self.log(f"answering {q.key}: the best source list for {q.based_on}")
            short = sources_shortlist(q, variants[self.plan.variant_index(q.based_on)])
            handles: list[Handle | None] = []
            for item in short["candidates"]:
                if item["scenario"] is None:
                    handles.append(None)
                    continue
                handles.append(flow.start(predicted_run(item["scenario"], self.plan,
                                                        self.executor, [_all_scans], 1)))
                self.steps += 4
            self._sources.append((q, short, handles))

    def answers(self, variants: list) -> dict[str, list]:
        """Every question of the plan, answered (the flow has run every chain)."""
        p = self.plan
        out: dict[str, list] = {"duration": [], "sources": [], "coverage": [],
                                "separation": []}
        for q in p.durations:
            handle, durations = self._long[_long_key(q, p)]
            run = handle.result
            out["duration"].append(duration_answer(
                q, run.scenario, run.shared, run.noise, run.terms,
                run.predictions[durations.index(q)]))
        for q in p.coverage:
            run = self._long[_long_key(q, p)][0].result
            out["coverage"].append(coverage_answer(q, run.scenario, run.shared))
        for q, short, handles in self._sources:
            out["sources"].append(sources_answer(q, short, [
                None if h is None else h.result for h in handles]))
        for v in variants:
            out["separation"].append({"variant": v.spec.name, "level": p.separation_level,
                                      "pairs": v.cannot_separate()})
        return out


def _long_key(q: DurationQuestion | CoverageQuestion, plan: Plan) -> tuple[int, float]:
    return plan.variant_index(q.based_on), float(q.max_days)


def _all_scans(scenario, shared: SharedSchedule, noise: NoiseModel) -> list[int | None]:
    return [None]


def _ends_of(q: DurationQuestion) -> Callable:
    """The prefixes (scan counts) of a duration question's long run, from its schedule."""
    return lambda long, shared, noise: [end for _, end in
                                        duration_points(q, long, shared, noise)]


# ---------------------------------------------------------------------------------------------
def _periods(t_s: np.ndarray, sun_el_deg: np.ndarray, unit: str,
             night_sun_max_deg: float = NIGHT_SUN_MAX_DEG) -> list[int]:
    """Indices (exclusive ends, in scan order) of the prefixes ending each day or night (the
    Sun below ``night_sun_max_deg``)."""
    label = sun_el_deg > DAY_SUN_MIN_DEG if unit == "day" else sun_el_deg < night_sun_max_deg
    ends: list[int] = []
    inside, last = False, -1
    for i in range(t_s.size):
        if label[i]:
            if inside and t_s[i] - t_s[last] > PERIOD_GAP_S:
                ends.append(last + 1)
            inside, last = True, i
        elif inside:
            ends.append(last + 1)
            inside = False
    if inside:
        ends.append(last + 1)
    return ends


def duration_scenario(q: DurationQuestion | CoverageQuestion, plan: Plan):
    """The variant of the question run for ``max_days``."""
    base = plan.scenarios[plan.variant_index(q.based_on)]
    span = q.max_days * 86400.0
    return replace(base, duration_s=span, controller=replace(base.controller, duration_s=span))


def duration_points(q: DurationQuestion, long, shared: SharedSchedule,
                    noise: NoiseModel) -> list[tuple[int, int]]:
    """(count, scans) of every prefix of the long run ``long`` that the question's curve
    shows: each hour, 24-hour day, day or night of the schedule whose design has more scans
    than the fit has terms."""
    t_s = shared.columns["t_s"].astype(float)
    if q.unit in ("hour", "run_day"):
        step = 3600.0 if q.unit == "hour" else 86400.0
        counts = list(range(1, math.floor(long.duration_s / step + 1e-9) + 1))
        ends = [int(np.searchsorted(t_s, k * step, side="right")) for k in counts]
    else:
        ends = _periods(t_s, shared.columns["sun_el_deg"].astype(float), q.unit,
                        long.controller.night_sun_max_deg)
        counts = list(range(1, len(ends) + 1))
    n_terms = len(long.controller.fit_spec()[0])
    return [(count, end) for count, end in zip(counts, ends, strict=True)
            if int(np.sum(noise.scans < end)) > n_terms]


def duration_answer(q: DurationQuestion, long, shared: SharedSchedule, noise: NoiseModel,
                    terms, predictions: list[Prediction]) -> dict[str, Any]:
    """The smallest duration of ``q.based_on``'s plan with sigma(terms) <= target, from the
    long run's schedule and the predictions of its prefixes (:func:`duration_points`): per
    count, the predicted sigma of each term and its sampling error; the first count at which
    every term reaches its target, and each term's own first count."""
    t_s = shared.columns["t_s"].astype(float)
    names = PointingModel(list(terms)).names
    idx = [names.index(n) for n in q.terms]
    target = np.array(q.targets_arcsec)
    curve = []
    answer = None
    first: dict[str, int | None] = dict.fromkeys(q.terms)
    points = duration_points(q, long, shared, noise)
    for (count, end), pred in zip(points, predictions, strict=True):
        sig = pred.sigma_arcsec[idx]
        point = {"count": int(count), "campaign_h": float(t_s[end - 1] / 3600.0),
                 "scan_time_h": float(shared.scan_spans_s[:end].sum() / 3600.0),
                 "n_scans": int(end),
                 "sigma_arcsec": {n: float(s) for n, s in zip(q.terms, sig, strict=True)},
                 "bias_predicted_arcsec": {n: float(pred.bias_arcsec[j])
                                           for n, j in zip(q.terms, idx, strict=True)},
                 "sigma_error_arcsec": {n: float(pred.sigma_error_arcsec[j])
                                        for n, j in zip(q.terms, idx, strict=True)},
                 "bias_error_arcsec": {n: float(pred.bias_error_arcsec[j])
                                       for n, j in zip(q.terms, idx, strict=True)}}
        curve.append(point)
        for n, s, g in zip(q.terms, sig, target, strict=True):
            if first[n] is None and s <= g:
                first[n] = int(count)
        if answer is None and bool(np.all(sig <= target)):
            answer = point
    out: dict[str, Any] = {"based_on": q.based_on, "terms": list(q.terms),
                           "target_arcsec": q.target_arcsec,
                           "targets_arcsec": dict(zip(q.terms, q.targets_arcsec, strict=True)),
                           "unit": q.unit, "max_days": q.max_days, "note": q.note,
                           "reached": answer is not None, "answer": answer,
                           "first_count": first, "curve": curve, "extrapolated": None}
    if answer is None and curve:
        last = curve[-1]
        worst = max(last["sigma_arcsec"][n] / g for n, g in zip(q.terms, target, strict=True))
        out["extrapolated"] = {"count": math.ceil(last["count"] * worst ** 2),
                               "method": "sigma proportional to 1/sqrt(duration) beyond "
                                         f"the {q.max_days:g} days simulated"}
    return out


# ---------------------------------------------------------------------------------------------
#: step of the hour angles at which a source's reach is tabulated (h)
REACH_STEP_H = 0.05


def _cell(ha_deg, dec_deg, q: CoverageQuestion) -> tuple[np.ndarray, np.ndarray]:
    """Cell indices: hour-angle bins of ``ha_step_h`` from 0 h, declination bins of
    ``dec_step_deg`` down from ``dec_max_deg``."""
    return (np.floor(np.asarray(ha_deg) / 15.0 / q.ha_step_h).astype(int),
            np.floor((q.dec_max_deg - np.asarray(dec_deg)) / q.dec_step_deg).astype(int))


def reachable_cells(q: CoverageQuestion, scenario) -> set[tuple[int, int]]:
    """The cells below ``q.dec_max_deg`` that a catalogue source passes through within the
    scheduler's limits (elevation window, hour-angle and declination limits) for at least
    half of the cell's hour angles, from each source's apparent declination at the start."""
    c = scenario.controller
    sched = c.scheduler
    observer, targets = plan_targets(c)
    _, dec = observer.ephemeris.hadec_rad(np.array([t.index for t in targets]),
                                          np.zeros(len(targets)))
    limit_h = (sched.hour_angle_limit_deg or 180.0) / 15.0
    ha_h = np.arange(-limit_h, limit_h + 1e-9, REACH_STEP_H)
    phi = math.radians(c.site_latitude_deg)
    counts: dict[tuple[int, int], int] = {}
    for d in np.atleast_1d(dec):
        dec_deg = math.degrees(d)
        if dec_deg >= q.dec_max_deg or (sched.declination_max_deg is not None
                                        and dec_deg > sched.declination_max_deg):
            continue
        el = np.degrees(np.arcsin(math.sin(phi) * math.sin(d)
                                  + math.cos(phi) * math.cos(d) * np.cos(np.radians(ha_h * 15))))
        seen = ha_h[(el >= sched.elevation_min_deg) & (el <= sched.elevation_max_deg)]
        ha_i, dec_i = _cell(seen * 15.0, np.full(seen.size, dec_deg), q)
        for i, span in zip(*np.unique(ha_i, return_counts=True), strict=True):
            cell = (int(i), int(dec_i[0]))
            counts[cell] = max(counts.get(cell, 0), int(span))
    half = 0.5 * q.ha_step_h / REACH_STEP_H
    return {cell for cell, n in counts.items() if n >= half}


def coverage_answer(q: CoverageQuestion, long, shared) -> dict[str, Any]:
    """:class:`~antsim.plan.planfile.CoverageQuestion` from the long run's schedule: after
    each 24-hour day, the share of the reachable cells holding ``min_scans`` scans; the first
    day at which all do."""
    cols = shared.columns
    good = cols["good"].astype(bool)
    t_s = cols["t_s"].astype(float)[good]
    ha_i, dec_i = _cell(cols["ha_deg"].astype(float)[good], cols["dec_deg"].astype(float)[good],
                        q)
    below = cols["dec_deg"].astype(float)[good] < q.dec_max_deg
    reach = reachable_cells(q, long)
    days = list(range(1, math.floor(long.duration_s / 86400.0 + 1e-9) + 1))
    curve, answer = [], None
    for day in days:
        seen: dict[tuple[int, int], int] = {}
        for cell in zip(ha_i[below & (t_s < day * 86400.0)],
                        dec_i[below & (t_s < day * 86400.0)], strict=True):
            seen[cell] = seen.get(cell, 0) + 1
        filled = sum(1 for cell in reach if seen.get(cell, 0) >= q.min_scans)
        curve.append({"day": day, "filled": filled, "cells": len(reach)})
        if answer is None and filled == len(reach):
            answer = day
    missing = sorted(cell for cell in reach if seen.get(cell, 0) < q.min_scans) if days else []
    return {"based_on": q.based_on, "dec_max_deg": q.dec_max_deg, "ha_step_h": q.ha_step_h,
            "dec_step_deg": q.dec_step_deg, "min_scans": q.min_scans, "max_days": q.max_days,
            "note": q.note, "cells": len(reach), "answer_days": answer, "curve": curve,
            "missing_at_max_days": [{"ha_h": [i * q.ha_step_h, (i + 1) * q.ha_step_h],
                                     "dec_deg": [q.dec_max_deg - (k + 1) * q.dec_step_deg,
                                                 q.dec_max_deg - k * q.dec_step_deg]}
                                    for i, k in missing]}


# ---------------------------------------------------------------------------------------------
def sources_shortlist(q: SourcesQuestion, vr) -> dict[str, Any]:
    """The source lists worth predicting exactly: the best ``q.candidates`` by the proxy,
    and the list as planned (each with its scenario, or None and why if infeasible)."""
    base = vr.scenario
    sched = base.controller.scheduler
    catalogue = list(sched.sources) or [s.name for s in base.sources]
    config = replace(base.controller, scheduler=replace(sched, sources=()))
    observer, targets = plan_targets(config)
    index = {t.name: t.index for t in targets}
    terms = vr.terms  # names; the model below is built from the fitted terms themselves
    shared = vr.shared
    slots = shared.columns["t_s"].astype(float)
    # per-source predicted offset variance (xel, el) from the variant's noise model
    var = sum(vr.noise.unit_variance(c) for c in COMPONENTS)  # (design scans, 2)
    src_of = np.array(shared.sources)[vr.noise.scans]
    default = np.median(var, axis=0)
    noise = {n: (var[src_of == n].mean(axis=0) if np.any(src_of == n) else default)
             for n in catalogue}
    el_min, el_max = np.radians(sched.elevation_min_deg), np.radians(sched.elevation_max_deg)
    model = PointingModel(list(base.controller.fit_spec()[0]))
    equatorial = base.mount.kind == "equatorial"
    rows = {}
    for name in catalogue:
        src = np.full(slots.size, index[name])
        az, el = observer.ephemeris.altaz_rad(src, slots)
        visible = (el >= el_min) & (el <= el_max)
        # the fit's axes: an equatorial mount's hour angle and declination
        lon, lat = observer.ephemeris.hadec_rad(src, slots) if equatorial else (az, el)
        bx, be = model.design_matrix(lon, lat)
        rows[name] = (visible, bx * np.cos(lat)[:, None], be)
    catalogue = [n for n in catalogue if rows[n][0].any()]  # visible at some slot
    spacing = float(np.median(np.diff(slots))) if slots.size > 1 else 600.0
    sel = [terms.index(n) for n in q.terms] if q.terms else None

    def proxy(subset: tuple[str, ...]) -> float:
        vis = np.stack([rows[n][0] for n in subset])  # (k, slots)
        k = vis.sum(axis=0)
        fill = np.where(k > 0, np.minimum(1.0, k * spacing / max(sched.min_revisit_s, 1e-9))
                        / np.maximum(k, 1), 0.0)
        info = np.zeros((len(terms), len(terms)))
        for j, n in enumerate(subset):
            w = vis[j] * fill
            vx, ve = noise[n]
            bx, be = rows[n][1], rows[n][2]
            info += (bx * (w / vx)[:, None]).T @ bx + (be * (w / ve)[:, None]).T @ be
        return _criterion(info, sel, inverse=True)

    candidates: list[tuple[float, tuple[str, ...]]] = []
    if len(catalogue) <= MAX_EXHAUSTIVE:
        for k in range(q.min_sources, len(catalogue) + 1):
            for subset in itertools.combinations(catalogue, k):
                candidates.append((proxy(subset), subset))
    else:  # greedy forward selection, keeping every step's list
        chosen: tuple[str, ...] = ()
        while len(chosen) < len(catalogue):
            best = max((proxy((*chosen, n)), (*chosen, n)) for n in catalogue
                       if n not in chosen)
            chosen = best[1]
            if len(chosen) >= q.min_sources:
                candidates.append(best)
    candidates.sort(key=lambda c: (-c[0], c[1]))
    shortlist = [c[1] for c in candidates[:q.candidates]]
    planned = tuple(catalogue)
    if planned not in shortlist:
        shortlist.append(planned)
    items = []
    for subset in shortlist:
        scenario = replace(base, controller=replace(
            base.controller, scheduler=replace(sched, sources=tuple(subset))))
        item = {"sources": subset, "scenario": scenario, "proxy_score": float(proxy(subset)),
                "why": ""}
        try:
            check_scenario(scenario)
        except InputError as err:
            item.update(scenario=None, why=err.problem)
        items.append(item)
    return {"based_on": q.based_on, "duration_h": base.duration_s / 3600.0, "terms": terms,
            "planned": planned, "candidates": items,
            "ranked": [{"sources": list(sub), "proxy_score": float(p)}
                       for p, sub in candidates[:10]]}


def sources_answer(q: SourcesQuestion, short: dict[str, Any],
                   runs: list[Predicted | None]) -> dict[str, Any]:
    """The best of the candidates of :func:`sources_shortlist`, from their deterministic
    runs' predictions (None: infeasible)."""
    terms = short["terms"]
    sel = [terms.index(n) for n in q.terms] if q.terms else None
    checked = []
    for item, run in zip(short["candidates"], runs, strict=True):
        if run is None:
            checked.append({"sources": list(item["sources"]), "feasible": False,
                            "why": item["why"]})
            continue
        pred = run.predictions[0][0]
        checked.append({"sources": list(item["sources"]), "feasible": True,
                        "n_scans": int(run.shared.n_scans),
                        "score": float(_criterion(pred.covariance, sel, inverse=False)),
                        "proxy_score": item["proxy_score"],
                        "sigma_arcsec": {n: float(s) for n, s in
                                         zip(terms, pred.sigma_arcsec, strict=True)},
                        "sigma_error_arcsec": {n: float(s) for n, s in
                                               zip(terms, pred.sigma_error_arcsec,
                                                   strict=True)}})

    feasible = [c for c in checked if c["feasible"]]
    best = max(feasible, key=lambda c: c["score"]) if feasible else None
    criterion = (f"smallest largest sigma of {', '.join(q.terms)}" if q.terms
                 else "D-optimal: smallest determinant of the predicted covariance of the "
                      "fitted terms")
    return {"based_on": q.based_on, "duration_h": short["duration_h"],
            "criterion": criterion, "terms": list(q.terms), "planned": list(short["planned"]),
            "best": best, "checked": checked, "ranked_by_proxy": short["ranked"]}


def _criterion(matrix: np.ndarray, sel: list[int] | None, inverse: bool) -> float:
    """Larger is better. ``matrix`` is an information matrix (``inverse``) or a covariance;
    with ``sel``: minus the largest variance of those terms; else minus log det of the
    covariance (D-optimal)."""
    try:
        cov = np.linalg.inv(matrix) if inverse else matrix
    except np.linalg.LinAlgError:
        return -math.inf
    if sel:
        d = np.diag(cov)[sel]
        return -float(np.max(d)) if np.all(d > 0) and np.all(np.isfinite(d)) else -math.inf
    sign, logdet = np.linalg.slogdet(cov)
    return -float(logdet) if sign > 0 else -math.inf


# ---------------------------------------------------------------------------------------------
def _unit(unit: str, count: int) -> str:
    """The unit's name for ``count`` of it ("run_day": 24-hour days from the start)."""
    name = {"run_day": "day"}.get(unit, unit) + ("s" if count != 1 else "")
    return f"{name} (24 h each)" if unit == "run_day" else name


def answers_text(answers: dict[str, list]) -> list[str]:
    """The answers as sentences with their numbers."""
    lines: list[str] = []
    for a in answers.get("duration", []):
        terms = ", ".join(a["terms"])
        unit = a["unit"]
        one = a["target_arcsec"]
        goal = f"{one:g}\"" if one is not None else "their targets (" + ", ".join(
            f"{n} {g:g}\"" for n, g in a["targets_arcsec"].items()) + ")"
        if a["reached"]:
            ans = a["answer"]
            sig = ", ".join(f"{n} {s:.1f}\"" for n, s in ans["sigma_arcsec"].items())
            bias = ", ".join(f"{n} {format_number(b, '+.1f')}\""
                             for n, b in ans["bias_predicted_arcsec"].items())
            lines.append(
                f"duration: {ans['count']} {_unit(unit, ans['count'])} of "
                f"'{a['based_on']}' bring {terms} to {goal} or better "
                f"(predicted {sig}; {ans['n_scans']} scans, {ans['scan_time_h']:.1f} h of "
                f"scanning in {ans['campaign_h']:.1f} h); the systematic bias ({bias}) does not "
                "shrink with time")
        else:
            ext = a["extrapolated"]
            more = (f"; about {ext['count']} {_unit(unit, 2)} by extrapolation "
                    f"({ext['method']})" if ext else "")
            lines.append(f"duration: {terms} to {goal} is not reached within "
                         f"{a['max_days']:g} days of '{a['based_on']}'{more}")
        if one is None:
            lines.append("  each term's first: " + ", ".join(
                f"{n} {c if c is not None else '-'}" for n, c in a["first_count"].items())
                + f" ({_unit(unit, 2)}; - not within {a['max_days']:g} days)")
        if a.get("note"):
            lines.append(f"  beside: {a['note']}")
    for a in answers.get("coverage", []):
        shares = ", ".join(f"day {c['day']} {c['filled']}/{c['cells']}" for c in a["curve"])
        cells = (f"{a['ha_step_h']:g} h x {a['dec_step_deg']:g} deg cells below dec "
                 f"{a['dec_max_deg']:g} deg")
        if a["answer_days"] is not None:
            lines.append(f"coverage: after {a['answer_days']} {_unit('run_day', a['answer_days'])}"
                         f" of '{a['based_on']}' each of the {a['cells']} {cells} the "
                         f"catalogue reaches holds {a['min_scans']} scan(s) ({shares})")
        else:
            lines.append(f"coverage: the {a['cells']} {cells} the catalogue reaches are not all "
                         f"observed within {a['max_days']:g} days of '{a['based_on']}' "
                         f"({shares})")
        if a.get("note"):
            lines.append(f"  beside: {a['note']}")
    for a in answers.get("sources", []):
        best = a["best"]
        if best is None:
            lines.append(f"sources: no feasible source list for '{a['based_on']}'")
            continue
        sig = ", ".join(f"{n} {best['sigma_arcsec'][n]:.1f}\""
                        for n in (a["terms"] or list(best["sigma_arcsec"])[:4]))
        planned = next((c for c in a["checked"] if c["sources"] == a["planned"]), None)
        versus = ""
        if planned and planned.get("feasible") and planned is not best:
            psig = ", ".join(f"{n} {planned['sigma_arcsec'][n]:.1f}\""
                             for n in (a["terms"] or list(planned["sigma_arcsec"])[:4]))
            versus = f" (the planned list: {psig})"
        lines.append(f"sources: for '{a['based_on']}' ({a['duration_h']:.1f} h) the best list "
                     f"is {', '.join(best['sources'])} by {a['criterion']}: {sig}{versus}")
    for s in answers.get("separation", []):
        if s["pairs"]:
            pairs = ", ".join(f"{p['terms'][0]}/{p['terms'][1]} "
                              f"({format_number(p['r_predicted'], '+.2f')})"
                              for p in s["pairs"])
            lines.append(f"separation: '{s['variant']}' cannot separate {pairs}")
    return lines + ([""] if lines else [])

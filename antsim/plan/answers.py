"""Answers, not only tables: how long, which sources, and which terms a plan cannot separate.

* :func:`answer_duration`: the smallest duration (hours, days or nights) of a variant's plan
  that brings the predicted sigma of chosen terms to a target. The variant is simulated once
  (deterministically) for ``max_days``; the scheduler is causal, so the first N hours of that
  schedule are the N-hour campaign, and the prediction is evaluated on every prefix. The
  systematic bias of the terms (the same in every campaign) is reported beside: it does not
  shrink with time.
* :func:`answer_sources`: the best source list for a variant's duration. Every subset of the
  catalogue is ranked by a D-optimal proxy (each of the variant's scan slots shared among the
  subset's sources visible then, within the revisit limit, weighted by the predicted noise of
  scans of that source); the best few, and the list as planned, are then predicted exactly
  from their own deterministic schedules. Criterion: the determinant of the predicted
  covariance of the fitted terms, or the largest sigma of the chosen terms.
* Separation: pairs of terms with |correlation| above the plan's level, per variant.
"""

from __future__ import annotations

import itertools
import math
import uuid
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from antsim.figures.html import format_number
from antsim.simulate.ensemble import Executor, Job, task_record
from antsim.simulate.vectorized import quiet_scenario
from controller.astro.sun import DAY_SUN_MIN_DEG, NIGHT_SUN_MAX_DEG
from controller.errors import InputError
from controller.pointing.model import PointingModel

from ..progress import Progress
from .fisher import predict, task_noise, truth_vector
from .planfile import CoverageQuestion, DurationQuestion, Plan, SourcesQuestion

__all__ = ["answer_duration", "answer_questions", "answer_sources", "answers_text",
           "coverage_answer", "reachable_cells"]

#: thermal draws for the noise models of the answers' (longer) schedules
N_THERMAL_ANSWERS = 128
#: scans further apart than this start a new day or night period (s)
PERIOD_GAP_S = 3 * 3600.0
#: largest catalogue whose subsets are all ranked (else greedy forward selection)
MAX_EXHAUSTIVE = 12


def answer_questions(plan: Plan, variants: list, executor: Executor,
                     log: Callable[[str], None] | None = None,
                     progress: Progress | None = None) -> dict[str, list]:
    """Every question of the plan, answered. The deterministic runs the answers need (the
    long campaigns of the duration questions, the candidate source lists) are all submitted
    at once, so they run in parallel; ``progress`` counts their steps (a schedule, then a
    noise model, per run)."""
    out: dict[str, list] = {"duration": [], "sources": [], "coverage": [], "separation": []}
    todo: list[Any] = []
    # the coverage questions need only the long deterministic runs, submitted first
    cover = [(q, duration_scenario(q, plan)) for q in plan.coverage]
    recorded = [executor.submit(task_record, quiet_scenario(sc)) for _, sc in cover]
    for q in plan.durations:
        if log:
            goal = (f"{q.target_arcsec:g}\"" if q.target_arcsec is not None
                    else "their targets")
            log(f"answering {q.key}: {', '.join(q.terms)} to {goal} "
                f"({q.based_on}, up to {q.max_days:g} days)")
        todo.append(("duration", q, [duration_scenario(q, plan)]))
    for q in plan.sources:
        if log:
            log(f"answering {q.key}: the best source list for {q.based_on}")
        vr = variants[plan.variant_index(q.based_on)]
        short = sources_shortlist(q, vr)
        todo.append(("sources", q, short))
    scenarios = [sc for _, _, items in todo for sc in _scenarios(items)]
    if progress is not None:
        progress.stage(f"answering {len(todo) + len(cover)} questions: "
                       f"{len(scenarios) + len(cover)} deterministic runs",
                       total=2 * len(scenarios) + len(cover), unit="step")
    prepared = iter(prepare(executor, scenarios, plan, progress))
    if progress is not None:
        progress.stage("answering: the predicted sigmas of every duration and source list")
    for kind, q, items in todo:
        if kind == "duration":
            out["duration"].append(duration_answer(q, items[0], *next(prepared)))
        else:
            done = [next(prepared) if item["scenario"] is not None else None
                    for item in items["candidates"]]
            out["sources"].append(sources_answer(q, items, done))
    for (q, sc), done in zip(cover, recorded, strict=True):
        if log:
            log(f"answering {q.key}: coverage below dec {q.dec_max_deg:g} deg ({q.based_on})")
        out["coverage"].append(coverage_answer(q, sc, done.result()))
        if progress is not None:
            progress.advance()
    for v in variants:
        out["separation"].append({"variant": v.spec.name, "level": plan.separation_level,
                                  "pairs": v.cannot_separate()})
    return out


def _scenarios(items: Any) -> list:
    if isinstance(items, dict):
        return [c["scenario"] for c in items["candidates"] if c["scenario"] is not None]
    return list(items)


def prepare(executor: Executor, scenarios: list, plan: Plan,
            progress: Progress | None = None) -> list[tuple]:
    """(shared schedule, noise model, fitted terms) of each scenario's deterministic run,
    computed in parallel on the executor; ``progress`` advances by one per step done."""
    pending: dict[Any, tuple[str, int]] = {}
    jobs: list[Any] = [None] * len(scenarios)
    out: list[Any] = [None] * len(scenarios)
    quiet = [quiet_scenario(sc) for sc in scenarios]
    for i, q in enumerate(quiet):
        pending[executor.submit(task_record, q)] = ("record", i)
    token = uuid.uuid4().hex
    while pending:
        if progress is not None:
            progress.detail(_running(pending.values(), scenarios))
        done = next(iter(executor.as_completed(list(pending))))
        kind, i = pending.pop(done)
        if progress is not None:
            progress.advance()
        if kind == "record":
            terms, fit_name = scenarios[i].controller.fit_spec()
            job = Job(f"answer:{token}:{i}", scenarios[i], quiet[i], done.result(),
                      tuple(terms), fit_name, plan.seed)
            jobs[i] = job
            pending[executor.submit(task_noise, executor.share(job), N_THERMAL_ANSWERS)] = \
                ("noise", i)
        else:
            out[i] = (jobs[i].shared, done.result()[0], jobs[i].terms)
    return out


def _span(duration_s: float) -> str:
    return (f"{duration_s / 86400.0:.3g}-day" if duration_s >= 2 * 86400.0
            else f"{duration_s / 3600.0:.3g}-hour")


def _running(pending, scenarios: list) -> str:
    """What :func:`prepare` still waits for, in words (the longest schedules first)."""
    steps = sorted(pending, key=lambda p: (p[0] != "record", -scenarios[p[1]].duration_s))
    words = [f"{_span(scenarios[i].duration_s)} schedule" if kind == "record"
             else "noise model" for kind, i in steps]
    shown = ", ".join(words[:3]) + (f" and {len(words) - 3} more" if len(words) > 3 else "")
    return f"running {shown}"


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


def answer_duration(q: DurationQuestion, plan: Plan, executor: Executor) -> dict[str, Any]:
    """The smallest duration of ``q.based_on``'s plan with sigma(terms) <= target."""
    long = duration_scenario(q, plan)
    return duration_answer(q, long, *prepare(executor, [long], plan)[0])


def duration_answer(q: DurationQuestion, long, shared, noise, terms) -> dict[str, Any]:
    """:func:`answer_duration` from the long run's schedule and noise model: per count, the
    predicted sigma of each term; the first count at which every term reaches its target,
    and each term's own first count."""
    span = long.duration_s
    t_s = shared.columns["t_s"].astype(float)
    sun = shared.columns["sun_el_deg"].astype(float)
    if q.unit in ("hour", "run_day"):
        step = 3600.0 if q.unit == "hour" else 86400.0
        counts = list(range(1, math.floor(span / step + 1e-9) + 1))
        ends = [int(np.searchsorted(t_s, k * step, side="right")) for k in counts]
    else:
        ends = _periods(t_s, sun, q.unit, long.controller.night_sun_max_deg)
        counts = list(range(1, len(ends) + 1))
    names = PointingModel(list(terms)).names
    truth = truth_vector(long, names)
    idx = [names.index(n) for n in q.terms]
    target = np.array(q.targets_arcsec)
    curve = []
    answer = None
    first: dict[str, int | None] = dict.fromkeys(q.terms)
    for count, end in zip(counts, ends, strict=True):
        n_design = int(np.sum(noise.scans < end))
        if n_design <= len(terms):
            continue
        pred = predict(shared, terms, noise, n_scans=end, truth=truth)
        sig = pred.sigma_arcsec[idx]
        point = {"count": int(count), "campaign_h": float(t_s[end - 1] / 3600.0),
                 "scan_time_h": float(shared.scan_spans_s[:end].sum() / 3600.0),
                 "n_scans": int(end),
                 "sigma_arcsec": {n: float(s) for n, s in zip(q.terms, sig, strict=True)},
                 "bias_predicted_arcsec": {n: float(pred.bias_arcsec[j])
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
    from controller.program.campaign import plan_targets

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
def answer_sources(q: SourcesQuestion, plan: Plan, vr, executor: Executor) -> dict[str, Any]:
    """The best source list for the duration of variant ``vr`` (see the module docstring)."""
    short = sources_shortlist(q, vr)
    scenarios = _scenarios(short)
    prepared = iter(prepare(executor, scenarios, plan))
    done = [next(prepared) if c["scenario"] is not None else None for c in short["candidates"]]
    return sources_answer(q, short, done)


def sources_shortlist(q: SourcesQuestion, vr) -> dict[str, Any]:
    """The source lists worth predicting exactly: the best ``q.candidates`` by the proxy,
    and the list as planned (each with its scenario, or None and why if infeasible)."""
    from controller.program.campaign import plan_targets

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
    from .fisher import COMPONENTS

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
    from antsim.simulate.runner import check_scenario

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


def sources_answer(q: SourcesQuestion, short: dict[str, Any], done: list) -> dict[str, Any]:
    """:func:`answer_sources` from the candidates' deterministic runs and noise models."""
    terms = short["terms"]
    sel = [terms.index(n) for n in q.terms] if q.terms else None
    checked = []
    for item, prep in zip(short["candidates"], done, strict=True):
        if prep is None:
            checked.append({"sources": list(item["sources"]), "feasible": False,
                            "why": item["why"]})
            continue
        sh, nm, _ = prep
        pred = predict(sh, terms, nm)
        checked.append({"sources": list(item["sources"]), "feasible": True,
                        "n_scans": int(sh.n_scans),
                        "score": float(_criterion(pred.covariance, sel, inverse=False)),
                        "proxy_score": item["proxy_score"],
                        "sigma_arcsec": {n: float(s) for n, s in
                                         zip(terms, pred.sigma_arcsec, strict=True)}})

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

"""Running a plan: the deterministic run, the prediction and the Monte Carlo of every variant.

:func:`run_plan` runs, per variant, the deterministic run; then its noise model and its
members in blocks; members whose schedule cannot be shared in full; then its prediction; and
the plan's questions (:mod:`antsim.plan.answers`), all as chains of tasks on one executor
(:mod:`antsim.simulate.flow`). It returns a :class:`PlanResult` whose
:meth:`~PlanResult.to_json` is the ``antsim plan --json`` document and
:meth:`~PlanResult.text` the printed tables.
"""

from __future__ import annotations

import math
import time
import uuid
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from antsim.figures.html import format_number
from antsim.simulate.ensemble import (
    Executor,
    Job,
    make_executor,
    task_block,
    task_full,
    task_record,
)
from antsim.simulate.flow import Chain, Flow, Task, running_words
from antsim.simulate.vectorized import MemberResults, SharedSchedule, quiet_scenario
from controller.errors import InputError
from controller.pointing.signs import UNITS, sign_convention

from ..progress import Progress, progress_for, span_words
from ..scenario import Scenario
from .answers import Questions, answers_text
from .fisher import (
    REJECTION_DRAWS,
    NoiseModel,
    Prediction,
    predict_prefixes,
    rejection_design,
    rejection_draws,
    task_noise,
    terms_without_lever_arm,
    truth_vector,
)
from .planfile import Plan, VariantSpec

__all__ = ["PlanResult", "VariantResult", "block_size", "run_plan"]

#: draws of the random slow errors for the thermal part of the noise model
N_THERMAL = 256
#: members per block for a one-day campaign: the loop over integrations costs the same for
#: any number of members, memory grows as members x duration (~3 MB per member-day)
BLOCK_MEMBERS_PER_DAY = 128


def block_size(duration_s: float, requested: int = 0) -> int:
    """Members per block: fixed by the plan (never by the machine), so that the results do
    not depend on the number of workers."""
    if requested:
        return requested
    return int(min(128, max(4, BLOCK_MEMBERS_PER_DAY * 86400.0 / duration_s)))


@dataclass
class VariantResult:
    """Prediction and Monte Carlo of one variant (arcsec)."""

    spec: VariantSpec
    scenario: Scenario
    shared: SharedSchedule
    noise: NoiseModel
    prediction: Prediction
    results: MemberResults
    truth: np.ndarray
    unshareable: list[str]
    n_requested: int
    level: float

    @property
    def terms(self) -> tuple[str, ...]:
        return self.prediction.names

    @property
    def ok(self) -> np.ndarray:
        return ~self.results.failed

    def sigma_mc(self) -> np.ndarray:
        v = self.results.values[self.ok]
        return v.std(axis=0, ddof=1) if len(v) > 1 else np.full(len(self.terms), np.nan)

    def bias_mc(self) -> np.ndarray:
        return self.results.values[self.ok].mean(axis=0) - self.truth

    def mc_correlation(self) -> np.ndarray:
        v = self.results.values[self.ok]
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.corrcoef(v, rowvar=False) if len(v) > 2 else np.full(
                (len(self.terms),) * 2, np.nan)

    def cannot_separate(self) -> list[dict[str, Any]]:
        """Term pairs whose predicted correlation exceeds the plan's level."""
        mc = self.mc_correlation()
        names = list(self.terms)
        out = []
        for a, b, r in self.prediction.cannot_separate(self.level):
            i, j = names.index(a), names.index(b)
            out.append({"terms": [a, b], "r_predicted": _num(r),
                        "r_design": _num(self.prediction.design_correlation[i, j]),
                        "r_monte_carlo": _num(mc[i, j])})
        return out

    def to_json(self) -> dict[str, Any]:
        n = int(self.ok.sum())
        sigma_mc = self.sigma_mc()
        bias = self.bias_mc()
        pred = self.prediction
        ok = self.ok
        terms = {}
        for j, name in enumerate(self.terms):
            terms[name] = {
                "sigma_fisher_arcsec": _num(pred.sigma_arcsec[j]),
                "sigma_fisher_error_arcsec": _num(pred.sigma_error_arcsec[j]),
                "sigma_mc_arcsec": _num(sigma_mc[j]),
                "bias_arcsec": _num(bias[j]),
                "sigma_mc_error_arcsec": _num(sigma_mc[j] / math.sqrt(2.0 * max(n - 1, 1))),
                "bias_error_arcsec": _num(sigma_mc[j] / math.sqrt(max(n, 1))),
                "bias_predicted_arcsec": _num(pred.bias_arcsec[j]),
                "bias_predicted_error_arcsec": _num(pred.bias_error_arcsec[j]),
                "truth_arcsec": _num(self.truth[j]),
                "mean_arcsec": _num(self.results.values[ok, j].mean() if n else math.nan),
                "sigma_tpoint_mean_arcsec": _num(np.mean(self.results.sigma_tpoint[ok, j])
                                                 if n else math.nan),
                "sigma_honest_mean_arcsec": _num(np.mean(self.results.sigma_honest[ok, j])
                                                 if n else math.nan),
                "sigma_fisher_components_arcsec": {
                    c: _num(math.sqrt(max(float(m[j, j]), 0.0)))
                    for c, m in pred.components.items()},
            }
        return {
            "name": self.spec.name,
            "description": self.spec.description,
            "settings": self.spec.settings(),
            "n_monte_carlo": n,
            "n_shared_schedule": int((ok & ~self.results.full).sum()),
            "n_full_simulation": int((ok & self.results.full).sum()),
            "n_failed": int(self.results.failed.sum()),
            "shared_schedule": not self.unshareable,
            "why_not_shared": list(self.unshareable),
            "duration_h": self.scenario.duration_s / 3600.0,
            "scan_time_h": self.shared.scan_span_s / 3600.0,
            "n_scans": int(self.shared.n_scans),
            "n_scans_in_design": int(pred.n_scans),
            "n_used_mean": _num(np.mean(self.results.n_used[ok]) if n else math.nan),
            "n_used_predicted": _num(pred.n_scans - pred.n_rejected),
            "terms": terms,
            "sky_rms_fisher_arcsec": _num(pred.sky_rms_arcsec),
            "sky_rms_mc_arcsec": _num(np.mean(self.results.sky_rms[ok]) if n else math.nan),
            "noise_budget_arcsec": self.noise.budget(),
            "cannot_separate": self.cannot_separate(),
            "notes": list(self.noise.notes),
        }

    def text(self) -> str:
        d = self.to_json()
        lines = [f"{self.spec.name}: {d['duration_h']:.1f} h campaign, {d['n_scans']} scans "
                 f"({d['scan_time_h']:.1f} h scanning), {d['n_monte_carlo']} members "
                 f"({d['n_shared_schedule']} on the shared schedule, "
                 f"{d['n_full_simulation']} simulated in full)"]
        if self.spec.description:
            lines.append(f"  {self.spec.description}")
        head = (f"  {'term':<6}{'truth':>9}{'sig_F':>8}{'sig_MC':>8}{'+-':>7}{'MC/F':>6}"
                f"{'bias_MC':>9}{'+-':>7}{'bias_F':>9}{'TPOINT':>8}{'honest':>8}")
        lines += [head]
        for name, t in d["terms"].items():
            ratio = _ratio(t["sigma_mc_arcsec"], t["sigma_fisher_arcsec"])
            lines.append(
                f"  {name:<6}{_f(t['truth_arcsec'], '+9.1f')}"
                f"{_f(t['sigma_fisher_arcsec'], '8.2f')}{_f(t['sigma_mc_arcsec'], '8.2f')}"
                f"{_f(t['sigma_mc_error_arcsec'], '7.2f')}{_f(ratio, '6.2f')}"
                f"{_f(t['bias_arcsec'], '+9.1f')}{_f(t['bias_error_arcsec'], '7.1f')}"
                f"{_f(t['bias_predicted_arcsec'], '+9.1f')}"
                f"{_f(t['sigma_tpoint_mean_arcsec'], '8.2f')}"
                f"{_f(t['sigma_honest_mean_arcsec'], '8.2f')}")
        lines.append(f"  Sky RMS: predicted {_f(d['sky_rms_fisher_arcsec'], '.1f')}\", Monte "
                     f"Carlo {_f(d['sky_rms_mc_arcsec'], '.1f')}\"; observations used: "
                     f"predicted {_f(d['n_used_predicted'], '.1f')}, Monte Carlo "
                     f"{_f(d['n_used_mean'], '.1f')}")
        budget = ", ".join(f"{c} {v['xel_arcsec']:.1f}/{v['el_arcsec']:.1f}"
                           for c, v in d["noise_budget_arcsec"].items())
        lines.append(f"  offset noise per scan (xel/el rms, arcsec): {budget}")
        if d["cannot_separate"]:
            pairs = ", ".join(f"{p['terms'][0]}-{p['terms'][1]} (r = "
                              f"{_f(p['r_predicted'], '+.3f')})" for p in d["cannot_separate"])
            lines.append(f"  cannot reliably be separated (|r| > {self.level:g}): {pairs}")
        else:
            lines.append(f"  every pair of terms separable (|r| <= {self.level:g})")
        for why in d["why_not_shared"]:
            lines.append(f"  members simulated in full: {why}")
        for note in d["notes"]:
            lines.append(f"  note: {note}")
        return "\n".join(lines)


@dataclass
class PlanResult:
    """All variants of a plan and the answers to its questions."""

    plan: Plan
    variants: list[VariantResult]
    answers: dict[str, list[dict[str, Any]]] = field(default_factory=dict)
    engine: str = ""
    wall_s: float = 0.0

    def to_json(self) -> dict[str, Any]:
        return {
            "plan": self.plan.name,
            "description": self.plan.description,
            "scenario": self.plan.scenario.name,
            "seed": self.plan.seed,
            "units": UNITS,
            "sign_convention": self.sign(),
            "plans": [v.to_json() for v in self.variants],
            "answers": self.answers,
        }

    def sign(self) -> str:
        """The sign convention of the variants' fitted terms, in words."""
        return sign_convention(dict.fromkeys(n for v in self.variants for n in v.terms))

    def text(self, timing: bool = True) -> str:
        """The printed tables and answers (``timing``: with the wall time and the engine,
        which make the text differ from run to run)."""
        p = self.plan
        lines = [f"plan {p.name}: {len(self.variants)} variants of scenario "
                 f"{p.scenario.name} (seed {p.seed})",
                 "sig_F: predicted from the design and the noise model (Fisher); sig_MC: "
                 "scatter of the Monte Carlo fits (+- its sampling error); bias_MC: mean fit "
                 "minus truth (+- its error), bias_F: predicted; TPOINT/honest: mean of the "
                 f"fitter's own sigmas; all {UNITS}; sign of the terms: {self.sign()}", ""]
        for v in self.variants:
            lines += [v.text(), ""]
        lines += answers_text(self.answers)
        if timing and self.engine:
            lines.append(f"computed in {self.wall_s:.1f} s on {self.engine}")
        return "\n".join(lines).rstrip() + "\n"


def _num(x: Any) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def _ratio(a: float | None, b: float | None) -> float | None:
    if a is None or b is None or b == 0:
        return None
    return a / b


def _f(x: float | None, spec: str) -> str:
    """``format(x, spec)`` without a negative zero, or a dash as wide for a missing value."""
    if x is None or not math.isfinite(x):
        width = "".join(ch for ch in spec.split(".")[0] if ch.isdigit())
        return f"{'-':>{int(width) if width else 1}}"
    return format_number(x, spec)


# ---------------------------------------------------------------------------------------------
def run_plan(plan: Plan, workers: int | None = None, scheduler: str | None = None,
             members: int | None = None, progress: Progress | bool | None = None,
             executor: Executor | None = None, answers: bool = True,
             log: Callable[[str], None] | None = None) -> PlanResult:
    """Predictions and Monte Carlo of every variant of ``plan`` (and its answers).
    ``progress``: the command's :class:`~antsim.progress.Progress`, or whether to show one
    (None: a bar on a terminal, lines off one).

    The variants' members and the answers' own runs share the executor: with two workers
    or more, the answers that need no variant (how long, coverage: long deterministic runs)
    start with the members, the source lists once the variants are done; the stage after
    the members counts the answers' steps."""
    t0 = time.perf_counter()
    shown, owned = progress_for(progress, "plan")
    own = executor is None
    try:
        if own:
            shown.stage(_starting(workers) if scheduler is None
                        else f"connecting to {scheduler}")
        executor = executor or make_executor(workers, scheduler)
        result = _run(plan, executor, members, shown, answers, log)
        result.engine = executor.description
    finally:
        if own and executor is not None:
            executor.close()
        if owned:
            shown.close()
    result.wall_s = time.perf_counter() - t0
    return result


def _starting(workers: int | None) -> str:
    if workers is None:
        return "starting the workers"
    if workers == 0:
        return "working in this process"
    return f"starting {workers} worker{'s' if workers != 1 else ''}"


class _Count:
    """What the flow's tasks done add to the progress: members (their blocks and members
    simulated in full) while the variants run, the answers' steps after."""

    def __init__(self, progress: Progress):
        self.progress = progress
        self.answer_steps = 0
        self.answering = False

    def __call__(self, task: Task, value: Any) -> None:
        if task.kind == "block":
            self.progress.advance(len(task.args[1]) - len(value[1]))
        elif task.kind == "full":
            self.progress.advance(1)
        elif task.kind == "answer":
            self.answer_steps += 1
            if self.answering:
                self.progress.advance(1)


def _run(plan: Plan, executor: Executor, members: int | None, progress: Progress,
         answers: bool, log: Callable[[str], None] | None) -> PlanResult:
    n_var = len(plan.variants)
    counts = [members or spec.members or plan.members for spec in plan.variants]
    count = _Count(progress)
    flow = Flow(executor, on_done=count)
    questions = None
    if answers and (plan.durations or plan.sources or plan.coverage):
        questions = Questions(plan, executor, log)
    # beside the members when there are workers to share (one worker gains nothing)
    early = questions is not None and executor.workers >= 2
    beside = " (and the answers' long runs)" if early else ""
    progress.stage(f"{n_var} variant{'s' if n_var != 1 else ''}: schedules, noise models and "
                   f"members{beside}", total=sum(counts), unit="members")
    if early:
        questions.start(flow)  # first: their long runs are the longest chains
    token = uuid.uuid4().hex
    handles = [flow.start(_variant(plan, v, counts[v], token, executor)) for v in range(n_var)]

    def tick() -> None:
        progress.detail(running_words(flow.running()))

    flow.run(until=handles, tick=tick)
    result = PlanResult(plan, [h.result for h in handles])
    if questions is not None:
        if not early:
            questions.start(flow)
        questions.start_after(flow, result.variants)
        n_q = questions.n_questions
        progress.stage(f"answering {n_q} question{'s' if n_q != 1 else ''}",
                       total=questions.steps, unit="steps")
        count.answering = True
        progress.set(count.answer_steps)
        flow.run(tick=tick)
        result.answers = questions.answers(result.variants)
    return result


def _named(err: InputError, plan: Plan, v: int) -> InputError:
    """A variant's scenario refused while it runs, named as the plan's variant (the base
    scenario's file and key alone would not say which variant)."""
    return InputError(plan.path, f"variants[{v}]", plan.variants[v].name,
                      f"{err.field} = {err.value!r}: {err.problem}", err.hint)


def _refuse_undetermined(plan: Plan, v: int, shared: SharedSchedule,
                         terms: Sequence[str]) -> None:
    """One line for a fitted term the variant's schedule leaves without a lever arm (see
    :func:`antsim.plan.fisher.terms_without_lever_arm`), naming where its fit comes from."""
    dead = terms_without_lever_arm(shared, terms)
    if not dead:
        return
    problem = (f"{', '.join(dead)} {'is' if len(dead) == 1 else 'are'} zero at every scan of "
               "this variant's noise-free run: the plan cannot determine "
               f"{'it' if len(dead) == 1 else 'them'}")
    spec = plan.variants[v]
    if spec.fit_model is not None:
        raise InputError(plan.path, f"variants[{v}].fit_model", spec.fit_model, problem,
                         "leave it out of fit_model, or give the variant what drives it")
    raise InputError(plan.path, f"variants[{v}]", spec.name, f"the scenario's fit: {problem}",
                     "give the variant a fit_model without it")


def _variant(plan: Plan, v: int, count: int, token: str, executor: Executor) -> Chain:
    """The chain of variant ``v``: its deterministic run; its noise model and its members in
    blocks; members whose schedule cannot be shared in full; its prediction."""
    scenario = plan.scenarios[v]
    span = span_words(scenario.duration_s)
    quiet = quiet_scenario(scenario)
    try:
        shared = yield Task(task_record, (quiet,), "variant", f"schedule{{s}} of {span}", 1)
    except InputError as err:
        raise _named(err, plan, v) from None
    if shared.n_scans == 0:
        raise InputError(plan.path, f"variants[{v}]", plan.variants[v].name,
                         "the controller schedules no scan in this variant",
                         "lengthen it, widen its window or elevation limits, or "
                         "give it sources that are up")
    terms, fit_name = scenario.controller.fit_spec()
    _refuse_undetermined(plan, v, shared, terms)
    job = executor.share(Job(f"{token}:{v}", scenario, quiet, shared, tuple(terms), fit_name,
                             plan.seed))
    size = block_size(scenario.duration_s, plan.block_members)
    blocks = [tuple(range(start, min(count, start + size))) for start in range(0, count, size)]
    try:
        done = yield [Task(task_noise, (job, N_THERMAL), "variant",
                           f"noise model{{s}} of {span}", 1),
                      *(Task(task_block, (job, b), "block", "block{s} of members")
                        for b in blocks)]
        (noise, unshareable), blocks_done = done[0], done[1:]
        parts = [results for results, _ in blocks_done]
        diverged = [m for _, members_out in blocks_done for m in members_out]
        parts += yield [Task(task_full, (job, m), "full", "member{s} simulated in full")
                        for m in diverged]
    except InputError as err:
        raise _named(err, plan, v) from None
    truth = truth_vector(scenario, terms)
    design = rejection_design(shared, terms, noise, [None])
    draws = yield Task(rejection_draws, (design, range(REJECTION_DRAWS)), "variant",
                       "simulation{s} of the robust fit's rejections")
    pred = predict_prefixes(shared, terms, noise, [None], truth, draws)[0]
    return VariantResult(spec=plan.variants[v], scenario=scenario, shared=shared, noise=noise,
                         prediction=pred, results=MemberResults.concat(parts), truth=truth,
                         unshareable=unshareable, n_requested=count,
                         level=plan.separation_level)

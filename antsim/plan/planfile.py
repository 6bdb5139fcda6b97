"""Plan files: a base scenario, what-if variants of it, and the questions to answer.

A plan is TOML (see ``scenarios/plans/ghigo1990_whatif.toml``)::

    name = "ghigo1990_whatif"
    scenario = "ghigo1990"             # a scenario's name, or a path relative to the plan file
    seed = 1990                        # plan seed: member seeds derive from it
    members = 200                      # Monte Carlo members per variant

    [[variants]]
    name = "night only"
    window = "night"                   # all | day | night
    # duration_h or duration_days, start_utc, sources = [...], elevation_min_deg,
    # elevation_max_deg, step_arcmin, integration_s, estimator (clark | lsq),
    # model (scenario | none | truth | a .mod/.json file), fit_model, members,
    # scenario (another base scenario for this variant, as the plan's scenario),
    # tipping = false (no tipping scans; their sky subtraction a priori)

    [[answers.duration]]               # the smallest duration reaching a target sigma
    based_on = "night only"
    terms = ["W4"]
    target_arcsec = 6.0                # or targets_arcsec = {W4 = 6.0, ...}, one per term
    unit = "night"                     # hour | day | night | run_day (24 h from the start)
    max_days = 20
    note = "..."                       # printed beside the answer (e.g. a source's claim)

    [[answers.sources]]                # the best source list for a variant's duration
    based_on = "8 hours"

    [[answers.coverage]]               # equatorial mounts: how long until the hour-angle
    based_on = "as run"                # and declination cells below dec_max_deg that the
    dec_max_deg = 20.0                 # catalogue can reach each hold a scan
    ha_step_h = 1.0
    dec_step_deg = 10.0
    max_days = 10

Every key is declared once in :mod:`antsim.schema.plan` (a variant's as the scenario's key of
the same name; ``docs/scenarios.md`` lists them) and read through it. Every bad value is one
:class:`~controller.errors.InputError` line naming the file, the key and the value (exit
status 2 through the command line), as for scenarios.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from astropy.time import Time

from antsim.simulate.runner import NoScanError, check_scenario
from controller.errors import InputError
from controller.pointing.model import NAMED_MODELS, PointingModel
from controller.pointing.modelio import load_model
from controller.pointing.terms import TermError, get_term
from controller.scans.config import SkyConfig

from ..bundled import find
from ..scenario import PlanNotScenarioError, Scenario, check_scan, load_scenario, overcorrection
from ..schema import plan as schema
from ..schema.keys import duplicate
from ..schema.plan import MAX_MEMBERS, UNITS, WINDOWS
from ..schema.utc import end_problem
from ..tomlcheck import Table, load_toml

__all__ = ["MAX_MEMBERS", "UNITS", "WINDOWS", "CoverageQuestion", "DurationQuestion", "Plan",
           "SourcesQuestion", "VariantSpec", "load_plan", "make_variant"]



@dataclass(frozen=True)
class VariantSpec:
    """One what-if, as written in the plan (None: the base scenario's value)."""

    name: str
    description: str = ""
    window: str | None = None
    duration_h: float | None = None
    start_utc: str | None = None
    sources: tuple[str, ...] | None = None
    elevation_min_deg: float | None = None
    elevation_max_deg: float | None = None
    step_arcmin: float | None = None
    integration_s: float | None = None
    estimator: str | None = None
    model: str | None = None
    fit_model: str | None = None
    members: int | None = None
    #: another base scenario for this variant (path as written, relative to the plan file)
    scenario: str | None = None
    #: False: no tipping scans; the sky emission they would measure is subtracted a priori
    #: (the scenario's own opacity), so that only the time they take is saved
    tipping: bool | None = None
    key: str = ""  # where it sits in the plan file, e.g. variants[2]

    def settings(self) -> dict[str, Any]:
        """The settings this variant changes (for reports)."""
        names = ("scenario", "window", "duration_h", "start_utc", "sources",
                 "elevation_min_deg", "elevation_max_deg", "step_arcmin", "integration_s",
                 "estimator", "model", "fit_model", "tipping")
        return {n: (list(v) if isinstance(v, tuple) else v) for n in names
                if (v := getattr(self, n)) is not None}


@dataclass(frozen=True)
class DurationQuestion:
    """The smallest duration of ``based_on``'s plan giving each of ``terms`` a sigma no
    larger than its target (``targets_arcsec``, in the order of ``terms``)."""

    based_on: str
    terms: tuple[str, ...]
    targets_arcsec: tuple[float, ...]
    unit: str = "day"
    max_days: float = 10.0
    note: str = ""
    key: str = ""

    @property
    def target_arcsec(self) -> float | None:
        """The one target of every term, or None when they differ."""
        return self.targets_arcsec[0] if len(set(self.targets_arcsec)) == 1 else None


@dataclass(frozen=True)
class CoverageQuestion:
    """The smallest duration (24-hour days from the start) of ``based_on``'s plan after which
    every cell of ``ha_step_h`` hours by ``dec_step_deg`` below ``dec_max_deg`` that a
    catalogue source passes through within the scheduler's limits holds ``min_scans``
    scans (an equatorial mount's sky coverage)."""

    based_on: str
    dec_max_deg: float
    ha_step_h: float = 1.0
    dec_step_deg: float = 10.0
    min_scans: int = 1
    max_days: float = 10.0
    note: str = ""
    key: str = ""


@dataclass(frozen=True)
class SourcesQuestion:
    """The best source list for ``based_on``'s duration (D-optimal, or the smallest sigma
    of ``terms`` when given)."""

    based_on: str
    terms: tuple[str, ...] = ()
    min_sources: int = 2
    candidates: int = 3
    key: str = ""


@dataclass(frozen=True)
class Plan:
    """A validated plan: base scenario, variants and questions."""

    name: str
    path: str
    description: str
    scenario: Scenario
    seed: int
    members: int
    variants: tuple[VariantSpec, ...]
    scenarios: tuple[Scenario, ...]
    durations: tuple[DurationQuestion, ...] = ()
    sources: tuple[SourcesQuestion, ...] = ()
    coverage: tuple[CoverageQuestion, ...] = ()
    separation_level: float = 0.95
    block_members: int = 0
    extra: dict[str, Any] = field(default_factory=dict)

    def variant_index(self, name: str) -> int:
        return [v.name for v in self.variants].index(name)


# ---------------------------------------------------------------------------------------------
def load_plan(path: str | Path) -> Plan:
    """Read and validate a plan file; raises InputError on the first bad value."""
    path = Path(path)
    root = load_toml(path)
    if "variants" not in root and "site" in root:
        raise root.error("site", "[site]", "this file is a scenario, not a plan",
                         "antsim run runs a scenario; a plan names one as its scenario")
    keys = schema.ROOT
    name = keys.read(root, "name")
    description = keys.read(root, "description")
    base = _load_base(keys.read(root, "scenario"), path, "scenario")
    seed = keys.read(root, "seed", default=base.seed)
    members = keys.read(root, "members")
    block = keys.read(root, "block_members")
    level = keys.read(root, "separation_level")
    specs = []
    for i, t in enumerate(root.tables("variants")):
        specs.append(_variant(t, f"variants[{i}]"))
    if not specs:
        raise root.error("variants", [], "the plan lists no variants",
                         "add [[variants]] tables, e.g. name = \"as run\"")
    names = [v.name for v in specs]
    repeated = duplicate(names)  # upper and lower case alike, as a report shows them
    if repeated is not None:
        i, n = repeated
        raise InputError(str(path), f"variants[{i}].name", n, "duplicate variant name")
    scenarios = tuple(make_variant(_variant_base(v, path, base), v, str(path))
                      for v in specs)
    answers = root.table("answers", {})
    durations = tuple(_duration(t, f"answers.duration[{i}]", names, scenarios)
                      for i, t in enumerate(answers.tables("duration", [])))
    sources = tuple(_sources(t, f"answers.sources[{i}]", names, scenarios)
                    for i, t in enumerate(answers.tables("sources", [])))
    coverage = tuple(_coverage(t, f"answers.coverage[{i}]", names, scenarios)
                     for i, t in enumerate(answers.tables("coverage", [])))
    answers.finish()
    root.finish()
    return Plan(name=name, path=str(path), description=description, scenario=base, seed=seed,
                members=members, variants=tuple(specs), scenarios=scenarios,
                durations=durations, sources=sources, coverage=coverage,
                separation_level=level, block_members=block)


def _variant_base(spec: VariantSpec, path: Path, base: Scenario) -> Scenario:
    """The scenario a variant changes: the plan's, or its own ``scenario``."""
    if spec.scenario is None:
        return base
    return _load_base(spec.scenario, path, f"{spec.key}.scenario")


def _load_base(text: str, plan: Path, key: str) -> Scenario:
    """The scenario that ``key`` of the plan file ``plan`` names (a plan named there is
    refused by name: it would be read as a scenario without a site)."""
    try:
        return load_scenario(find(text, "scenario", str(plan), key, relative_to=plan.parent))
    except PlanNotScenarioError:
        raise InputError(str(plan), key, text, "names a plan, not a scenario",
                         "a plan's scenario is a scenario file or the name of one") from None


def _terms(t: Table, key: str, default: Any = None, fitted: tuple[str, ...] = (),
           raw: list[str] | None = None) -> tuple[str, ...]:
    """Term names, each as the fit names it (``fitted``: the fit's names, which include an
    equatorial model's terms such as Crane's C1..C11); ``raw``: names given otherwise than
    as the list ``key``."""
    if raw is None:
        raw = t.strings(key, default if default is not None else [])
    out = []
    for term in raw:
        if term.strip().upper() in fitted:
            out.append(term.strip().upper())
            continue
        try:
            out.append(get_term(term).name)
        except TermError as err:
            raise t.error(key, term, "not a pointing term", str(err)) from None
    return tuple(out)


def _fitted_names(scenario: Scenario) -> tuple[str, ...]:
    """The names of the terms the scenario's controller fits."""
    return PointingModel(list(scenario.controller.fit_spec()[0])).names


def _variant(t: Table, key: str) -> VariantSpec:
    keys = schema.VARIANT
    name = keys.read(t, "name")
    if "duration_h" in t and "duration_days" in t:
        raise t.error("duration_days", t.raw("duration_days"),
                      "give duration_h or duration_days, not both")
    duration = keys.read(t, "duration_h")
    if "duration_days" in t:
        duration = keys["duration_days"].scale * keys.read(t, "duration_days")
    else:
        t.raw("duration_days", None)
    start = keys.read(t, "start_utc")
    sources = keys.read(t, "sources")
    if sources is not None and not sources:
        raise t.error("sources", sources, "lists no sources")
    values = keys.read_all(t, ("description", "window", "elevation_min_deg",
                               "elevation_max_deg", "step_arcmin", "integration_s",
                               "estimator", "model", "fit_model", "members", "scenario",
                               "tipping"))
    spec = VariantSpec(name=name, duration_h=duration, start_utc=start,
                       sources=tuple(sources) if sources is not None else None, key=key,
                       **values)
    t.finish()
    return spec


def _scenario_for(t: Table, key: str, names: list[str], scenarios) -> Scenario:
    based_on = t.string(key)
    if based_on not in names:
        raise t.error(key, based_on, "not a variant of this plan",
                      f"variants are {', '.join(names)}")
    return scenarios[names.index(based_on)]


def _duration(t: Table, key: str, names: list[str], scenarios) -> DurationQuestion:
    scenario = _scenario_for(t, "based_on", names, scenarios)
    fitted = _fitted_names(scenario)
    terms = _terms(t, "terms", fitted=fitted, raw=schema.DURATION.read(t, "terms"))
    if not terms:
        raise t.error("terms", [], "name at least one term", "e.g. terms = [\"W4\"]")
    for term in terms:
        if term not in fitted:
            raise t.error("terms", term, "is not fitted by this plan",
                          f"fitted terms are {' '.join(fitted)}")
    keys = schema.DURATION
    q = DurationQuestion(based_on=keys.read(t, "based_on"), terms=terms,
                         targets_arcsec=_targets(t, terms, fitted),
                         **keys.read_all(t, ("unit", "max_days", "note")), key=key)
    t.finish()
    return q


def _targets(t: Table, terms: tuple[str, ...], fitted: tuple[str, ...]) -> tuple[float, ...]:
    """One target per term: ``target_arcsec`` for all, or ``targets_arcsec`` = {term = ...}
    naming every term of ``terms``."""
    if ("target_arcsec" in t) == ("targets_arcsec" in t):
        raise t.error("target_arcsec", t.raw("target_arcsec", None),
                      "give target_arcsec (one for every term) or targets_arcsec (one per "
                      "term), not both or neither")
    keys = schema.DURATION
    if "target_arcsec" in t:
        return (keys.read(t, "target_arcsec"),) * len(terms)
    table = t.table("targets_arcsec")
    given: dict[str, str] = {}
    for k in table:
        term = _terms(table, k, fitted=fitted, raw=[k])[0]
        if term in given:
            raise table.error(k, table.raw(k), f"gives the term {term} again (first as "
                              f"{given[term]})", "give each term once")
        given[term] = k
    missing = [n for n in terms if n not in given]
    extra = [k for n, k in given.items() if n not in terms]
    if missing or extra:
        raise t.error("targets_arcsec", sorted(table.keys()),
                      f"must name exactly the terms {' '.join(terms)}",
                      f"missing {' '.join(missing) or '-'}, not in terms {' '.join(extra) or '-'}")
    bounds = keys["targets_arcsec"]
    out = tuple(table.number(given[n], gt=bounds.gt) for n in terms)
    table.finish()
    return out


def _coverage(t: Table, key: str, names: list[str], scenarios) -> CoverageQuestion:
    scenario = _scenario_for(t, "based_on", names, scenarios)
    if scenario.mount.kind != "equatorial":
        raise t.error("based_on", t.string("based_on"), "coverage is asked of hour angle and "
                      "declination cells: the variant's mount must be equatorial")
    q = CoverageQuestion(**schema.COVERAGE.read_all(t), key=key)
    t.finish()
    return q


def _sources(t: Table, key: str, names: list[str], scenarios) -> SourcesQuestion:
    scenario = _scenario_for(t, "based_on", names, scenarios)
    fitted = _fitted_names(scenario)
    thermal = [n for n in fitted if get_term(n).kind == "thermal"]
    if thermal:
        raise t.error("based_on", t.string("based_on"), f"fits thermal terms "
                      f"({', '.join(thermal)}); the source lists are ranked on positions "
                      "alone, without the structure temperatures those terms read",
                      "ask it of a variant that fits the position terms only")
    terms = _terms(t, "terms", fitted=fitted, raw=schema.SOURCES.read(t, "terms"))
    for term in terms:
        if term not in fitted:
            raise t.error("terms", term, "is not fitted by this plan",
                          f"fitted terms are {' '.join(fitted)}")
    keys = schema.SOURCES
    n_sources = len(scenario.sources)
    q = SourcesQuestion(based_on=keys.read(t, "based_on"), terms=terms,
                        min_sources=t.integer("min_sources", keys["min_sources"].default,
                                              min=int(keys["min_sources"].min), max=n_sources),
                        candidates=keys.read(t, "candidates"), key=key)
    t.finish()
    return q


# ---------------------------------------------------------------------------------------------
def make_variant(base: Scenario, spec: VariantSpec, where: str = "plan") -> Scenario:
    """The base scenario changed as ``spec`` says; InputError naming ``spec.key`` if the
    result is not a runnable campaign."""
    c = base.controller

    def err(field: str, value: Any, problem: str, hint: str = "") -> InputError:
        return InputError(where, f"{spec.key}.{field}" if spec.key else field, value, problem,
                          hint)

    scenario = base
    if spec.duration_h is not None or spec.start_utc is not None:
        duration = base.duration_s if spec.duration_h is None else spec.duration_h * 3600.0
        epoch = base.epoch_utc if spec.start_utc is None else _iso(spec.start_utc)
        problem = end_problem(epoch, duration)
        if problem:
            raise err("start_utc" if spec.duration_h is None else "duration_h",
                      spec.start_utc if spec.duration_h is None else spec.duration_h, problem)
        scenario = replace(scenario, duration_s=duration, epoch_utc=epoch,
                           controller=replace(scenario.controller, duration_s=duration,
                                              epoch_utc=epoch))
    sched = scenario.controller.scheduler
    if spec.window is not None:
        sched = replace(sched, window=spec.window)
    if spec.sources is not None:
        names = [s.name for s in base.sources]
        for s in spec.sources:
            if s not in names:
                raise err("sources", s, "not a source of the scenario",
                          f"sources are {', '.join(names)}")
        sched = replace(sched, sources=tuple(spec.sources))
    if spec.elevation_min_deg is not None:
        sched = replace(sched, elevation_min_deg=spec.elevation_min_deg)
    if spec.elevation_max_deg is not None:
        sched = replace(sched, elevation_max_deg=spec.elevation_max_deg)
    if sched.elevation_max_deg <= sched.elevation_min_deg:
        raise err("elevation_max_deg", sched.elevation_max_deg,
                  f"must exceed elevation_min_deg = {sched.elevation_min_deg:g}")
    scan = c.scan
    if spec.step_arcmin is not None:
        scan = replace(scan, step_arcmin=spec.step_arcmin)
    if spec.integration_s is not None:
        scan = replace(scan, integration_s=spec.integration_s)
    if spec.estimator is not None:
        scan = replace(scan, estimator=spec.estimator)
    # the scenario's own checks of a scan, on the variant's (its keys are the scenario's)
    check_scan(scan, base.receiver.sample_interval_s, err)
    lowest = sched.elevation_min_deg - 4.0 * scan.step_arcmin / 60.0
    if lowest < base.mount.el.min_deg:
        raise err("elevation_min_deg", sched.elevation_min_deg,
                  f"the -4D point at the lowest scheduled elevation falls below the mount's "
                  f"limit ({base.mount.el.min_deg:g} deg)",
                  "raise elevation_min_deg or use a smaller step")
    controller = replace(scenario.controller, scheduler=sched, scan=scan)
    if spec.tipping is False and controller.tipping is not None:
        controller = replace(controller, tipping=None, sky=SkyConfig(
            base.atmosphere.zenith_opacity, controller.tipping.t_atm_k))
    elif spec.tipping and controller.tipping is None:
        raise err("tipping", True, "the scenario makes no tipping scans",
                  "add [controller.tipping] to the scenario")
    if spec.model is not None:
        controller = replace(controller, model=_model(spec, base, where, err))
        found = overcorrection(controller.model, base.mount, sched)
        if found is not None:
            raise err("model", spec.model, found.problem, "check the model's values and units")
    if spec.fit_model is not None:
        controller = replace(controller, fit_terms=_fit_terms(spec.fit_model, err),
                             fit_model_name=spec.fit_model if spec.fit_model in NAMED_MODELS
                             else "custom")
    scenario = replace(scenario, controller=controller)
    try:
        check_scenario(scenario)
    except NoScanError as e:
        raise InputError(where, spec.key or "variant", spec.name, "the controller schedules "
                         f"no scan in this variant: {e.field.split('.')[-1]} = {e.value!r}: "
                         f"{e.problem.removeprefix('the controller can schedule no scan: ')}",
                         "lengthen it, widen its window or elevation limits, or give it "
                         "sources that are up") from None
    except InputError as e:
        if e.field == "controller.scheduler.sources" or spec.elevation_min_deg is None:
            field = "sources"
        else:
            field = "elevation_min_deg"
        raise err(field, e.value, e.problem, e.hint) from None
    if not math.isfinite(scenario.duration_s):
        raise err("duration_h", spec.duration_h, "must be finite")
    return scenario


def _iso(text: str) -> str:
    return Time(text, scale="utc").isot


def _model(spec: VariantSpec, base: Scenario, where: str, err) -> PointingModel:
    text = spec.model
    if not text.strip():  # as a path, it would name the plan's own directory
        raise err("model", text, "is empty", "give scenario, none, truth, a named model or a "
                  "model file")
    if text == "scenario":
        return base.controller.model
    if text == "truth":
        return base.truth_model
    if text == "none":
        return PointingModel()
    if text in NAMED_MODELS:
        return PointingModel(text)
    path = Path(text)
    if not path.is_absolute():
        path = Path(where).parent / path
    if not path.exists():
        raise err("model", text, "neither scenario, none, truth, a named model nor a file",
                  f"named models: {', '.join(sorted(NAMED_MODELS))}")
    return load_model(path)


def _fit_terms(text: str, err) -> tuple[str, ...]:
    if text in NAMED_MODELS:
        terms = NAMED_MODELS[text]
        if not terms:
            raise err("fit_model", text, "fits no terms")
        return terms
    names = tuple(n.strip().upper() for n in text.split(",") if n.strip())
    if not names:
        raise err("fit_model", text, "names no terms")
    for n in names:
        try:
            get_term(n)
        except TermError as e:
            raise err("fit_model", text, f"{n} is not a pointing term", str(e)) from None
    return names

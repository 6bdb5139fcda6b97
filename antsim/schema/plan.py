"""The plan file's keys: the one declaration :mod:`antsim.plan.planfile` reads them by and
``docs/scenarios.md`` lists them from.

A variant's settings are the scenario's keys of the same name (:mod:`antsim.schema.scenario`)
with the base scenario's value as their default: a plan cannot give a value its scenario
could not. The plan's dataclasses sit above this package, in :mod:`antsim.plan.planfile`,
and are named.
"""

from __future__ import annotations

from dataclasses import replace

from .keys import REQUIRED, Key, Section
from .scenario import CAMPAIGN, MAX_DURATION_H, MAX_DURATION_WHY, SCAN, SCHEDULER

__all__ = ["MAX_MEMBERS", "PLAN", "UNITS", "WINDOWS", "section"]

WINDOWS = ("all", "day", "night")
#: what a duration question counts
UNITS = ("hour", "day", "night", "run_day")
#: most members a plan may ask for per variant
MAX_MEMBERS = 100_000


def _scenarios(key: Key) -> Key:
    """A scenario's key as a variant changes it: the base scenario's value by default."""
    return replace(key, default=None, doc=f"{key.doc} (default: the scenario's)", field="")


ROOT = Section("", "The plan: a base scenario, what-if variants of it, and the questions "
               "to answer.", {
    "name": Key(REQUIRED, "the plan's name", kind="name"),
    "description": Key("", "one line: what the plan asks", kind="line"),
    "scenario": Key(REQUIRED, "the base scenario: a name (antsim scenarios lists them) or a "
                    "file, relative to the plan", kind="string", field=None,
                    note="a scenario, not a plan"),
    "seed": Key(None, "the plan's seed, from which every member's derives (default: the "
                "scenario's)", kind="integer", min=0),
    "members": Key(200, "Monte Carlo members per variant", kind="integer", min=2,
                   max=MAX_MEMBERS),
    "block_members": Key(0, "members simulated together (0: chosen by the campaign's "
                         "length)", kind="integer", min=0, max=4096),
    "separation_level": Key(0.95, "confidence with which two variants' answers are told "
                            "apart", gt=0.0, lt=1.0, unit="1"),
    "variants": Key(REQUIRED, "the what-ifs, a table each", kind="tables"),
    "answers": Key({}, "the questions, by kind", kind="table", field=None),
}, settings="Plan", derived={
    "path": "the plan file's path",
    "scenario": "the scenario file the key scenario names",
    "scenarios": "each variant's scenario, made from the base scenario and the variant",
    "durations": "answers.duration",
    "sources": "answers.sources",
    "coverage": "answers.coverage",
    "extra": "not a plan setting",
})

VARIANT = Section("variants[]", "One what-if: the base scenario with these changes.", {
    "name": Key(REQUIRED, "the variant's name, unique in the plan", kind="name"),
    "description": Key("", "one line: what the variant changes", kind="line"),
    "scenario": Key(None, "another base scenario for this variant (as the plan's "
                    "scenario)", kind="string"),
    "window": _scenarios(SCHEDULER["window"]),
    "duration_h": _scenarios(CAMPAIGN["duration_h"]),
    "duration_days": Key(None, "the campaign's length in days (or duration_h)",
                         gt=0.0, max=MAX_DURATION_H / 24.0, why=MAX_DURATION_WHY,
                         field="duration_h", scale=24.0),
    "start_utc": _scenarios(CAMPAIGN["start_utc"]),
    "sources": _scenarios(SCHEDULER["sources"]),
    "elevation_min_deg": _scenarios(SCHEDULER["elevation_min_deg"]),
    "elevation_max_deg": _scenarios(SCHEDULER["elevation_max_deg"]),
    "step_arcmin": _scenarios(SCAN["step_arcmin"]),
    "integration_s": _scenarios(SCAN["integration_s"]),
    "estimator": _scenarios(SCAN["estimator"]),
    "model": Key(None, "the pointing model in use: scenario, none, truth, a named model or "
                 "a model file", kind="string"),
    "fit_model": Key(None, "the terms fitted: a named model or a comma-separated list "
                     "(default: the scenario's)", kind="string"),
    "members": Key(None, "Monte Carlo members of this variant (default: the plan's)",
                   kind="integer", min=2, max=MAX_MEMBERS),
    "tipping": Key(None, "false: no tipping scans (the sky they would measure is "
                   "subtracted a priori)", kind="boolean"),
}, settings="VariantSpec", derived={"key": "where the variant sits in the plan file"})

ANSWERS = Section("answers", "The questions, a table each.", {
    "duration": Key([], "the smallest duration reaching a target error", kind="tables"),
    "sources": Key([], "the best source list for a variant's duration", kind="tables"),
    "coverage": Key([], "equatorial mounts: how long until the sky's cells hold a scan",
                    kind="tables"),
})

_BASED_ON = Key(REQUIRED, "the variant asked about, by name", kind="string")
_NOTE = Key("", "a note printed beside the answer (e.g. a source's claim)", kind="line")

DURATION = Section("answers.duration[]", "The smallest duration of a variant giving each "
                   "term an error no larger than its target.", {
    "based_on": _BASED_ON,
    "terms": Key(REQUIRED, "the terms (fitted by the variant)", kind="strings"),
    "target_arcsec": Key(None, "one target for every term (or targets_arcsec)", gt=0.0,
                         field=None),
    "targets_arcsec": Key(None, "a target per term, by name (or target_arcsec)",
                          kind="terms", gt=0.0, unit="arcsec", field="targets_arcsec",
                          note="names exactly the terms"),
    "unit": Key("day", "what the duration counts", kind="string", choices=UNITS),
    "max_days": Key(10.0, "the longest duration tried", gt=0.0, max=366.0, unit="d"),
    "note": _NOTE,
}, settings="DurationQuestion", derived={"key": "where the question sits in the plan file"})

SOURCES = Section("answers.sources[]", "The best source list for a variant's duration "
                  "(D-optimal, or the smallest error of terms).", {
    "based_on": _BASED_ON,
    "terms": Key([], "the terms whose errors rank the lists (empty: all, D-optimal)",
                 kind="strings"),
    "min_sources": Key(2, "the fewest sources in a list", kind="integer", min=1,
                       note="at most the scenario's sources"),
    "candidates": Key(3, "how many lists to show", kind="integer", min=1, max=20),
}, settings="SourcesQuestion", derived={"key": "where the question sits in the plan file"})

COVERAGE = Section("answers.coverage[]", "Equatorial mounts: the smallest duration after "
                   "which every reachable cell of hour angle and declination holds "
                   "min_scans scans.", {
    "based_on": _BASED_ON,
    "dec_max_deg": Key(REQUIRED, "the cells below this declination", min=-90.0, max=90.0),
    "ha_step_h": Key(1.0, "a cell's hour-angle width", gt=0.0, max=12.0),
    "dec_step_deg": Key(10.0, "a cell's declination height", gt=0.0, max=90.0),
    "min_scans": Key(1, "scans each cell must hold", kind="integer", min=1, max=1000),
    "max_days": Key(10.0, "the longest duration tried", gt=0.0, max=366.0, unit="d"),
    "note": _NOTE,
}, settings="CoverageQuestion", derived={"key": "where the question sits in the plan file"})

#: every table of a plan, in the order of the reference page
PLAN: tuple[Section, ...] = (ROOT, VARIANT, ANSWERS, DURATION, SOURCES, COVERAGE)


def section(path: str) -> Section:
    """The plan table at ``path`` (``variants[]``, ``answers.duration[]``)."""
    return next(s for s in PLAN if s.path == path)

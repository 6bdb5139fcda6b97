"""`antsim blindtest [--n N] [--seed S]`: prove diagnose on recordings with hidden effects.

Each case hides a random effect from the library (or none) at 3-10 times its detection
threshold in a simulated campaign of the scenario, diagnoses the recordings against the
scenario without the effect, and scores what was named (see :mod:`antsim.diagnose.blind`).
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys

from antsim.options import MAX_CASES, MAX_SIMULATIONS, check_count, check_processes
from controller.errors import InputError

#: the scenario the effects are hidden in unless --scenario says otherwise
DEFAULT_SCENARIO = "ghigo1990"


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--n", type=int, default=100, metavar="N",
                        help="number of cases (default 100, at most 10000)")
    parser.add_argument("--seed", type=int, default=1, metavar="S",
                        help="seed of the draws (default 1)")
    parser.add_argument("--scenario", metavar="SCENARIO", default=DEFAULT_SCENARIO,
                        help="scenario the effects are hidden in: a name or a TOML file "
                             f"(default: {DEFAULT_SCENARIO}, the 1990 run)")
    parser.add_argument("--sims", type=int, default=8, metavar="K",
                        help="baseline simulations that predict the noise (default 8, at "
                             "most 1000)")
    parser.add_argument("--jobs", type=int, default=1, metavar="J",
                        help="worker processes (default 1)")
    parser.add_argument("--cache", metavar="DIR", default=None,
                        help="cache of baseline simulations (default $ANTSIM_CACHE or "
                             "~/.cache/antsim)")
    parser.add_argument("--no-cache", action="store_true", help="do not read or write it")
    parser.add_argument("--json", action="store_true", help="print the report as JSON")
    parser.add_argument("--out", metavar="FILE", default=None,
                        help="also write the JSON report to FILE")
    parser.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                        help="a progress bar and a line per case, or none (default: on a "
                             "terminal; off one, a line every few seconds to stderr)")
    parser.epilog = ("Scores: confusion table by effect, correct identification of non-null "
                     "cases, false alarms on null cases, amplitude recovered within 3 sigma.")


def _check_out_file(name: str) -> None:
    """``--out FILE`` must name a file in a directory that exists."""
    import os

    if not name.strip():
        raise InputError("command line", "--out", name, "is empty", "name a file")
    if os.path.isdir(name):
        raise InputError("command line", "--out", name, "is a directory", "name a file in it")
    parent = os.path.dirname(os.path.abspath(name))
    if not os.path.isdir(parent):
        raise InputError("command line", "--out", name,
                         f"cannot be written: {parent} is not a directory")


def main(args: argparse.Namespace) -> int:
    from antsim.bundled import find
    from antsim.diagnose.blind import run_blindtest
    from antsim.progress import Progress
    from antsim.scenario import load_scenario

    check_count(args.n, "--n", 1, MAX_CASES, "each is a campaign simulated and diagnosed")
    check_count(args.sims, "--sims", 2, MAX_SIMULATIONS, "each is a campaign simulated")
    if args.seed < 0:
        raise InputError("command line", "--seed", args.seed, "must be >= 0")
    check_processes(args.jobs, "--jobs")
    if args.out is not None:
        _check_out_file(args.out)  # before the cases, not after them
    scenario = load_scenario(find(args.scenario, field="--scenario"))
    with Progress("blindtest", args.progress) as shown:
        shown.stage("cases", total=args.n, unit="case")

        def progress(case) -> None:
            if shown.mode == "bar":
                mark = "ok" if case.correct else ("group" if case.group_ok else "MISS")
                shown.write(f"case {case.index:4d}: hidden {case.hidden:<24} named "
                            f"{case.named:<24} {mark}", file=sys.stderr)
            shown.advance()

        report = run_blindtest(scenario, n=args.n, seed=args.seed, n_sims=args.sims,
                               cache_dir=args.cache, use_cache=not args.no_cache,
                               jobs=args.jobs, progress=progress)
    doc = _null_for_no_rate(report.to_json())
    if args.out is not None:
        from antsim.outdir import write_file

        write_file(args.out, json.dumps(doc, indent=2, allow_nan=False) + "\n")
    if args.json:
        json.dump(doc, sys.stdout, indent=2, allow_nan=False)
        sys.stdout.write("\n")
    else:
        print(_no_case_words(report.text()))
    return 0


def _null_for_no_rate(value):
    """The report's JSON with the rate of a kind of case none of the draws had (0 of 0, a
    NaN, which is not JSON) as null."""
    if isinstance(value, dict):
        return {k: _null_for_no_rate(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_null_for_no_rate(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _no_case_words(text: str) -> str:
    """The report's text with a rate of 0 of 0 cases (written "0/0 = nan%", e.g. the false
    alarms of a draw without a null case) said in words."""
    text = re.sub(r"(\d+)/0 = nan%", r"\1/0 (no such case was drawn)", text)
    return text.replace(" (group-aware nan%)", "")

"""`antsim diagnose RECORDINGS [--scenario S] [--model M] [--json] [--out DIR]`.

Finds what a pointing model misses: locates where the residuals exceed the noise the baseline
predicts, tests a library of physical effects, selects honestly, and reports the findings best
first (see :mod:`antsim.diagnose`). With ``--out DIR`` it also writes the report, an updated
pointing model, an updated scenario (with ``--scenario``), before/after residual plots and,
unless ``--resimulate 0``, a re-simulation showing that the simulated residuals now match the
recorded ones.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from controller.errors import InputError


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("recordings", metavar="RECORDINGS", nargs="?",
                        help="recordings.ecsv from 'antsim run', or a TPOINT pointing data "
                             "file (required except with --list)")
    parser.add_argument("--scenario", metavar="SCENARIO",
                        help="the scenario that should explain the recordings (a name, e.g. "
                             "ghigo1990, or a TOML file): its simulation predicts the noise "
                             "and the residual distribution")
    parser.add_argument("--model", metavar="MODEL",
                        help="baseline terms: a named model (ghigo10, tpoint8, ...; for an "
                             "equatorial mount's recordings crane1981, crane11, ...), a model "
                             "file, or T1,T2,... (default: the scenario's fit model, else the "
                             "recordings' model in use, else IA IE NPAE CA AN AW TF TX, or "
                             "crane11 on an equatorial mount)")
    parser.add_argument("--mount", choices=("altaz",), default=None,
                        help="a TPOINT file's decimal records are Az/El whatever its options "
                             "say (a file without a mount option is read so, with a note)")
    parser.add_argument("--csv", action="append", default=[], metavar="'KEY: VALUE'",
                        help="a setting of a CSV of your own measurements that the file does "
                             "not state, e.g. 'sign: true-minus-indicated' (docs/inputs.md)")
    parser.add_argument("--json", action="store_true",
                        help="print the result as JSON (the keys: docs/contract.md)")
    parser.add_argument("--out", metavar="DIR",
                        help="write diagnose.json/.txt, report.html, model_updated.dat/.json, "
                             "scenario_updated.toml and before/after plots into DIR")
    parser.add_argument("--resimulate", type=int, default=None, metavar="K",
                        help="with --out and --scenario: re-simulate the updated scenario K "
                             "times and compare (default 4; 0 skips it; at most 1000)")
    parser.add_argument("--sims", type=int, default=8, metavar="K",
                        help="simulations of the scenario that predict the noise (default 8, "
                             "at most 1000)")
    parser.add_argument("--jobs", type=int, default=min(2, os.cpu_count() or 1), metavar="J",
                        help="processes for the simulations (default: 2 on a machine with two "
                             "or more cores, else 1)")
    parser.add_argument("--cache", metavar="DIR",
                        help="cache of the baseline simulations (default $ANTSIM_CACHE or "
                             "~/.cache/antsim)")
    parser.add_argument("--no-cache", action="store_true",
                        help="neither read nor write the cache")
    parser.add_argument("--list", action="store_true",
                        help="print the candidate library (effects, terms, signatures) and exit")
    parser.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                        help="a progress bar, or none (default: a bar on a terminal, a line "
                             "every few seconds to stderr off one)")
    parser.epilog = (
        "Selection: forward addition by a family-corrected chi^2 or F test of what the model "
        "cannot absorb (sin/cos pairs jointly; correlations with the model reported in "
        "TPOINT's words), confirmed on held-out data, stopping when the residuals match the "
        "predicted noise. Without a noise prediction (a TPOINT file, no --scenario), once "
        "something is significant, effects that lower the held-out Sky RMS follow, up to 4 "
        "findings.")


def _library_text() -> str:
    from antsim.diagnose.candidates.library import CANDIDATES

    lines = []
    for c in CANDIDATES:
        d = c.describe()
        terms = f" [{' '.join(d['terms'])}]" if d["terms"] else ""
        lines.append(f"{d['candidate']}{terms}: {d['title']}")
        lines.append(f"    signature: {d['signature']}")
        params = ", ".join(f"{k} ({v})" for k, v in d["parameters"].items())
        lines.append(f"    parameters: {params}")
        lines.append(f"    cause: {d['explanation']}")
        if d["mounts"] != ["altaz"]:
            lines.append(f"    mounts: {', '.join(d['mounts'])}")
    return "\n".join(lines)


def main(args: argparse.Namespace) -> int:
    if args.list:
        print(_library_text())
        return 0
    if args.recordings is None:
        raise InputError("command line", "RECORDINGS", "(none)",
                         "is required (a recordings.ecsv or a TPOINT data file)",
                         "antsim diagnose --list alone prints the candidate library")
    from antsim.diagnose.request import check_options

    check_options(args.jobs, args.sims, args.resimulate, args.model)
    if args.out is None:
        return _diagnose(args, None)
    from antsim.diagnose.request import refuse_links
    from antsim.outdir import held_output_dir

    # held from the start: refused early
    with held_output_dir(args.out, "--out", "antsim diagnose") as out:
        refuse_links(out)
        return _diagnose(args, out)


def _diagnose(args: argparse.Namespace, out: Path | None) -> int:
    from antsim.diagnose.request import diagnose_file, read_scenario

    scenario = None
    if args.scenario:
        scenario = read_scenario(args.scenario, args.recordings, args.jobs)
    from antsim.progress import Progress

    with Progress("diagnose", args.progress) as progress:
        asked = diagnose_file(
            args.recordings, scenario, scenario_spec=args.scenario, model=args.model,
            mount=args.mount, csv_options=args.csv, sims=args.sims, jobs=args.jobs,
            cache_dir=args.cache, use_cache=not args.no_cache, out=out,
            resimulate=args.resimulate, progress=progress,
            note=lambda line: progress.write(f"note: {line}", file=sys.stderr))
    diag, written = asked.diagnosis, asked.written
    if args.json:
        doc = diag.to_json()
        if written is not None:
            doc["outputs"] = written
        json.dump(doc, sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        print(diag.text())
        if written and "resimulation" in written:
            from antsim.diagnose.modelit import resimulation_words

            print(resimulation_words(written["resimulation"]))
        if out is not None:
            from antsim.outdir import LOCK_NAME

            names = " ".join(sorted(p.name for p in out.iterdir() if p.name != LOCK_NAME))
            print(f"wrote {out}/: {names}")
    return 0

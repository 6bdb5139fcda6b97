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

from antsim.commands import MAX_SIMULATIONS, check_count, check_processes
from controller.errors import InputError


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("recordings", metavar="RECORDINGS", nargs="?",
                        help="recordings.ecsv from 'antsim run', a TPOINT pointing data "
                             "file, or a CSV file of your own measurements (docs/inputs.md; "
                             "required except with --list)")
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
                        help="print the result as JSON (docs/outputs.md, docs/diagnose.md)")
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
        "cannot absorb (one threshold, 2.58 sigma; sin/cos pairs jointly; correlations with "
        "the model reported in TPOINT's words), within a fifth of the numbers fitted. A "
        "finding is kept when the selection, repeated inside folds of the data, predicts the "
        "held-out data better with it, and when bootstrap resamples choose it again; the "
        "held-out Sky RMS printed is the whole selection's, repeated on each fold "
        "(docs/diagnose.md).")


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
    check_processes(args.jobs, "--jobs")
    check_count(args.sims, "--sims", 2, MAX_SIMULATIONS, "each is a campaign simulated")
    if args.resimulate is not None:
        check_count(args.resimulate, "--resimulate", 0, MAX_SIMULATIONS,
                    "each is a campaign simulated")
    if args.model is not None and not args.model.strip():  # not "no model": said so
        raise InputError("command line", "--model", args.model, "is empty",
                         "give a named model, a model file or T1,T2,...")
    if args.out is None:
        return _diagnose(args, None)
    from antsim.outdir import held_output_dir

    # held from the start: refused early
    with held_output_dir(args.out, "--out", "antsim diagnose") as out:
        _refuse_links(out)
        return _diagnose(args, out)


#: the files diagnose writes into --out (and its figures, diagnose*.png)
OUTPUTS = ("diagnose.json", "diagnose.txt", "report.html", "model_updated.dat",
           "model_updated.json", "scenario_updated.toml")


def _refuse_links(out: Path) -> None:
    """A symbolic link where diagnose writes one of its files would be written through
    (its target overwritten): refused before anything runs."""
    from fnmatch import fnmatch

    links = sorted(p.name for p in out.iterdir() if p.is_symlink() and (
        p.name in OUTPUTS or fnmatch(p.name, "diagnose*.png")))
    if links:
        raise InputError("command line", "--out", str(out),
                         f"holds {' '.join(links)} as a symbolic link: diagnose writes its "
                         "outputs there and does not write through a link",
                         "remove the link, or write into another directory")


def _diagnose(args: argparse.Namespace, out: Path | None) -> int:
    scenario = None
    if args.scenario:
        from antsim.bundled import find
        from antsim.scenario import load_scenario

        scenario = load_scenario(find(args.scenario, field="--scenario"))
        from controller.program.recordings import recorded_mount

        mount = recorded_mount(args.recordings)
        if mount is not None and mount != scenario.mount.kind:  # before 7 s of simulation
            raise InputError(args.recordings, "mount", mount,
                             f"the recordings' mount; --scenario {args.scenario} is an "
                             f"{scenario.mount.kind} mount's",
                             "diagnose them with a scenario of their own telescope")
        if Path(args.recordings).is_file():
            # a cold baseline's quiet campaign starts now, on the second core, while this
            # process imports the analysis and reads the recordings (antsim.simulate.streaming)
            from antsim.simulate.streaming import prestart

            prestart(args.jobs, scenario)
    from antsim.progress import Progress

    with Progress("diagnose", args.progress) as progress:
        progress.stage("reading the recordings")
        from antsim.diagnose import diagnose, load_observations

        obs = load_observations(args.recordings, mount=args.mount, csv_options=args.csv)
        for note in obs.meta.get("notes", ()):
            progress.write(f"note: {note}", file=sys.stderr)
        if scenario is not None and (obs.kind == "tpoint" or not obs.has_time):
            raise InputError(args.recordings, "--scenario", args.scenario,
                             f"{'a TPOINT data file' if obs.kind == 'tpoint' else 'a file'} "
                             "without times has nothing to simulate against",
                             "diagnose it without --scenario")
        progress.stage("the noise the scenario predicts (simulations) and the candidate "
                       "effects" if scenario is not None else "testing the candidate effects")
        try:
            diag = diagnose(obs, scenario, args.model, n_sims=args.sims, cache_dir=args.cache,
                            use_cache=not args.no_cache, jobs=args.jobs)
        except ValueError as err:
            if isinstance(err, InputError):
                raise
            raise InputError(args.recordings, "observations", obs.n, str(err)) from None
        written = None
        if out is not None:
            from antsim.diagnose.modelit import resimulation_words, write_outputs

            resim = 4 if args.resimulate is None else args.resimulate
            progress.stage("writing the outputs" + (f" and re-simulating {resim} times"
                                                    if scenario and resim else ""))
            written = write_outputs(diag, out, scenario, resim if scenario else 0,
                                    cache_dir=args.cache, use_cache=not args.no_cache,
                                    jobs=args.jobs)
    if args.json:
        doc = diag.to_json()
        if written is not None:
            doc["outputs"] = written
        json.dump(doc, sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        print(diag.text())
        if written and "resimulation" in written:
            print(resimulation_words(written["resimulation"]))
        if out is not None:
            from antsim.outdir import LOCK_NAME

            names = " ".join(sorted(p.name for p in out.iterdir() if p.name != LOCK_NAME))
            print(f"wrote {out}/: {names}")
    return 0

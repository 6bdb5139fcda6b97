"""`antsim plan PLAN.toml`: what-if questions about an observing plan, answered with numbers.

For each variant of the plan: the predicted (Fisher) sigma of every fitted term from the
schedule the controller would produce and a noise model of the physics, the Monte Carlo sigma
and bias from N simulated campaigns fitted as the observatory fits them, Sky RMS predicted
and simulated, telescope time; then the plan's questions (how long, which sources) and the
pairs of terms the plan cannot separate. See :mod:`antsim.plan`.
"""

from __future__ import annotations

import argparse
import json
import sys
from contextlib import nullcontext


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("plan", help="plan: a name (antsim scenarios lists them, e.g. "
                                     "ghigo1990_whatif) or a TOML file")
    parser.add_argument("--json", action="store_true",
                        help="print the result as JSON ({\"plans\": [...], \"answers\": ...})")
    parser.add_argument("--out", default=None,
                        help="directory for plan.json, plan.txt, report.html and the "
                             "comparison figures")
    parser.add_argument("--workers", type=int, default=None,
                        help="local worker processes (default: the machine's cores; 0: run "
                             "in this process)")
    parser.add_argument("--scheduler", default=None, metavar="ADDRESS",
                        help="run the members on a Dask distributed scheduler, e.g. "
                             "tcp://127.0.0.1:8786 (pip install 'antsim[dask]')")
    parser.add_argument("--members", type=int, default=None,
                        help="Monte Carlo members per variant (default: the plan's): fewer "
                             "make the Monte Carlo columns noisier (their +- grows as "
                             "1/sqrt(N)) and the members' share of the time smaller; the "
                             "predictions and the answers do not depend on it, nor does "
                             "their time")
    parser.add_argument("--no-answers", action="store_true",
                        help="skip the plan's questions (how long, which sources, "
                             "coverage): the tables of the variants alone, the quick look "
                             "(the answers' long deterministic runs are most of the time)")
    parser.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                        help="a progress bar, or none (default: a bar on a terminal, a line "
                             "every few seconds to stderr off one)")
    parser.epilog = ("Results are the same for any --workers or --scheduler: member seeds "
                     "derive from the plan seed and the member index, and the answers' "
                     "simulations are cut into the same tasks whatever the workers. The "
                     "answers run on the same workers as the members, beside them with two "
                     "workers or more; the answering stage counts its steps.")


def main(args: argparse.Namespace) -> int:
    from antsim.bundled import find
    from antsim.outdir import held_output_dir
    from antsim.plan.outputs import check_options, write_outputs
    from antsim.plan.planfile import load_plan
    from antsim.plan.study import run_plan
    from antsim.progress import Progress

    check_options(args.members, args.workers, args.scheduler)
    held = (held_output_dir(args.out, "--out", "antsim plan") if args.out is not None
            else nullcontext())
    with held as out, Progress("plan", args.progress) as progress:
        progress.stage("reading the plan")
        plan = load_plan(find(args.plan, "plan"))

        def log(message: str) -> None:
            if progress.mode != "off":
                progress.write(message, file=sys.stderr)

        result = run_plan(plan, workers=args.workers, scheduler=args.scheduler,
                          members=args.members, progress=progress,
                          answers=not args.no_answers, log=log)
        doc = result.to_json()
        text = result.text()
        if out is not None:
            progress.stage("figures")
            figures = write_outputs(result, out, doc)
            text += (f"wrote {out}/: plan.json plan.txt report.html and {len(figures)} "
                     "figures\n")
    if args.json:
        print(json.dumps(doc, indent=2))
    else:
        print(text, end="")
    return 0

"""`antsim run SCENARIO.toml --out DIR`: simulate a campaign, reduce, fit and report."""

from __future__ import annotations

import argparse
import sys

from controller.errors import InputError


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scenario", help="a scenario's name (antsim scenarios lists them, "
                                         "e.g. ghigo1990) or a scenario file (TOML)")
    parser.add_argument("--out", required=True, help="output directory")
    parser.add_argument("--seed", type=int, default=None,
                        help="random seed (default: the scenario's)")
    parser.add_argument("--model", default=None,
                        help="pointing model the controller uses: a named model with zero "
                             "coefficients (none, ghigo10, ...), a model.dat/.mod file or a "
                             "fit.json (default: the scenario's)")
    parser.add_argument("--resume", action="store_true",
                        help="continue an interrupted run in DIR (byte-identical result)")
    parser.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                        help="a progress bar, or none (default: a bar on a terminal, a line "
                             "every few seconds to stderr off one)")
    parser.add_argument("--no-report", action="store_true",
                        help="skip the figures and report.html (faster)")
    parser.add_argument("--connect", default=None, metavar="HOST:PORT",
                        help="drive the antenna of a KATCP server (antsim serve) instead of "
                             "simulating one: the truth and the seed are the server's")


def main(args: argparse.Namespace) -> int:
    from antsim.bundled import find
    from antsim.outdir import held_output_dir
    from antsim.progress import Progress
    from antsim.run.campaign import check_seed, model_in_use, refuse_earlier_run
    from antsim.run.outputs import clear_products, write_outputs
    from antsim.scenario import load_scenario
    from antsim.simulate.runner import run_campaign

    check_seed(args.seed)
    scenario = load_scenario(find(args.scenario))
    model = model_in_use(args.model, scenario)
    for option, given in (("--seed", args.seed is not None), ("--resume", args.resume)):
        if given and args.connect is not None:
            raise InputError("command line", option, True, "not with --connect",
                             "the simulation is the server's (antsim serve --seed)")
    with held_output_dir(args.out, "--out", "antsim run") as out:
        refuse_earlier_run(out, args.resume)
        antenna, seed = None, args.seed
        if args.connect is not None:
            from antsim.serve.remote import connect

            antenna, seed = connect(scenario, args.connect)
        with Progress("run", args.progress) as progress:
            try:
                result = run_campaign(scenario, out, seed=seed, model=model,
                                      resume=args.resume, show_progress=progress,
                                      antenna=antenna)
            except ConnectionError as err:  # controller.wire.ConnectionLostError, mid-campaign
                progress.close()
                print(f"antsim run: error: {err}; the scans recorded so far are in "
                      f"{out / 'recordings.ecsv'}", file=sys.stderr)
                return 1
            finally:
                if antenna is not None:
                    antenna.close()
            clear_products(out)  # a resumed run's earlier fits, model and figures
            summary = write_outputs(result, report=not args.no_report, progress=progress)
    print(summary, file=sys.stdout)
    return 0

"""`antsim serve SCENARIO.toml`: the simulated antenna as a KATCP device (docs/katcp.md;
`antsim serve --requests` prints the request list from the device itself)."""

from __future__ import annotations

import argparse
import os

from controller.errors import InputError


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scenario", nargs="?", default=None,
                        help="a scenario's name (antsim scenarios lists them, "
                             "e.g. ghigo1990) or a scenario file (TOML)")
    parser.add_argument("--requests", action="store_true",
                        help="print the KATCP requests the antenna serves (arguments, reply, "
                             "meaning) and the conventions, and exit")
    parser.add_argument("--host", default="127.0.0.1",
                        help="address to listen on (default: 127.0.0.1, this machine only)")
    parser.add_argument("--port", type=int, default=5025,
                        help="TCP port (default: 5025; 0: any free port, printed at start)")
    parser.add_argument("--clock", default="virtual",
                        help="virtual (time passes only as commands run; the default), "
                             "realtime, or xK: K simulated seconds per second (x10)")
    parser.add_argument("--seed", type=int, default=None,
                        help="random seed (default: the scenario's)")
    parser.add_argument("--out", default=None,
                        help="directory for truth.json and requests.jsonl (the log of "
                             "every request); one that holds either is refused")


def main(args: argparse.Namespace) -> int:
    import asyncio

    from antsim.bundled import find
    from antsim.outdir import held_output_dir
    from antsim.scenario import load_scenario
    from antsim.serve.app import PRODUCTS, serve
    from antsim.serve.clock import parse_clock

    if args.requests:
        from antsim.serve.requests import request_list

        print(request_list(), end="")
        return 0
    if args.scenario is None:
        raise InputError("command line", "SCENARIO", "",
                         "a scenario is needed (a name antsim scenarios lists, or a TOML file)",
                         "or --requests for the request list")
    try:
        clock = parse_clock(args.clock)
    except ValueError as err:
        raise InputError("command line", "--clock", args.clock, str(err)) from None
    if not 0 <= args.port <= 65535:
        raise InputError("command line", "--port", args.port, "must be in 0..65535")
    if args.seed is not None and args.seed < 0:
        raise InputError("command line", "--seed", args.seed, "must be >= 0")
    scenario = load_scenario(find(args.scenario))
    if args.out is None:
        return asyncio.run(serve(scenario, clock, host=args.host, port=args.port,
                                 seed=args.seed))
    with held_output_dir(args.out, "--out", "antsim serve") as out:
        # as antsim run: an earlier session's log and truth, or a run's truth, are kept
        present = [name for name in PRODUCTS if os.path.lexists(out / name)]
        if present:
            raise InputError("command line", "--out", str(out),
                             f"already holds {' '.join(present)} of an earlier session or run",
                             "serve into an empty or new directory")
        return asyncio.run(serve(scenario, clock, host=args.host, port=args.port,
                                 seed=args.seed, out=out))

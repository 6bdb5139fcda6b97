"""`antsim scenarios [NAME]`: the scenarios and plans that come with antsim, one line each;
with a NAME, that file's text (to copy and edit: ``antsim scenarios ghigo1990 > my.toml``)."""

from __future__ import annotations

import argparse
import sys


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("name", nargs="?", default=None, metavar="NAME",
                        help="print this scenario's or plan's file instead of the list")
    parser.epilog = ("Every command that takes a scenario or a plan takes its name or a path: "
                     "antsim run ghigo1990 --out DIR, antsim plan ghigo1990_whatif.")


def main(args: argparse.Namespace) -> int:
    from antsim.bundled import catalogue, find, names, scenarios_dir
    from controller.errors import InputError

    if args.name is not None:
        for kind in ("scenario", "plan"):
            if args.name in names(kind):
                sys.stdout.write(find(args.name, kind).read_text(encoding="utf-8"))
                return 0
        raise InputError("command line", "NAME", args.name, "names no scenario or plan",
                         f"scenarios: {' '.join(names('scenario'))}; "
                         f"plans: {' '.join(names('plan'))}")
    for kind, command in (("scenario", "antsim run NAME --out DIR"),
                          ("plan", "antsim plan NAME")):
        entries = catalogue(kind)
        width = max(len(e.name) for e in entries)
        scope = max(len(e.telescope) for e in entries)
        print(f"{kind}s ({command}):")
        for e in entries:
            print(f"  {e.name:<{width}}  {e.telescope:<{scope}}  {e.description}")
        print()
    print(f"files in {scenarios_dir()}; antsim scenarios NAME prints one")
    return 0

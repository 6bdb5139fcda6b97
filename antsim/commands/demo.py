"""`antsim demo`: not built yet (issue 8); the subcommand exists so the contract is visible."""

from __future__ import annotations

import argparse
import sys


def configure(parser: argparse.ArgumentParser) -> None:
    parser.epilog = "Not implemented yet: arrives with issue 8."


def main(args: argparse.Namespace) -> int:
    print("antsim demo: not implemented yet (issue 8)", file=sys.stderr)
    return 1

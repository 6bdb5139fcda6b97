"""`antsim blindtest`: not built yet (issue 5); the subcommand exists so the contract is visible."""

from __future__ import annotations

import argparse
import sys


def configure(parser: argparse.ArgumentParser) -> None:
    parser.epilog = "Not implemented yet: arrives with issue 5."


def main(args: argparse.Namespace) -> int:
    print("antsim blindtest: not implemented yet (issue 5)", file=sys.stderr)
    return 1

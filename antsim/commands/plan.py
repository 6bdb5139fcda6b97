"""`antsim plan`: not built yet (issue 6); the subcommand exists so the contract is visible."""

from __future__ import annotations

import argparse
import sys


def configure(parser: argparse.ArgumentParser) -> None:
    parser.epilog = "Not implemented yet: arrives with issue 6."


def main(args: argparse.Namespace) -> int:
    print("antsim plan: not implemented yet (issue 6)", file=sys.stderr)
    return 1

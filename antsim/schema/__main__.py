"""``python -m antsim.schema --markdown``: print the reference page of scenario and plan
files (``docs/scenarios.md`` is this output)."""

from __future__ import annotations

import argparse
import sys

from .markdown import reference_page


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m antsim.schema",
                                     description="the scenario and plan schema")
    parser.add_argument("--markdown", action="store_true",
                        help="print the reference page (docs/scenarios.md)")
    args = parser.parse_args(argv)
    if not args.markdown:
        parser.print_help()
        return 2
    sys.stdout.write(reference_page())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

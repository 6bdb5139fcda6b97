"""`antsim fit RECORDINGS`: fit a pointing model to recordings or a TPOINT data file.

The file is read through the front door of every command's pointing data,
:func:`controller.program.inputs.read_pointing_file`, which decides its kind by content
(ECSV recordings from ``antsim run``, TPOINT pointing data, CSV measurements). Bad input
(missing file, malformed line, unknown term) ends as one line on stderr and exit status 2.
Recordings of an equatorial mount (metadata ``mount: equatorial``) are fitted in hour angle and
declination with TPOINT's equatorial terms (default model ``crane11``).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from controller.pointing.jackknife import BLOCK_S
from controller.pointing.model import NAMED_MODELS


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("recordings", metavar="RECORDINGS",
                        help="recordings.ecsv from 'antsim run', a TPOINT pointing data file, "
                             "or a CSV of your own measurements (docs/inputs.md)")
    which = parser.add_mutually_exclusive_group()
    which.add_argument("--model", metavar="NAME",
                       help="named model (" + ", ".join(sorted(NAMED_MODELS)) + "), a "
                            "TPOINT .mod file or a fit.json whose terms are fitted (default: "
                            "tpoint8 for TPOINT data and CSV, ghigo10 for recordings)")
    which.add_argument("--terms", metavar="T1,T2,...",
                       help="comma-separated term names, e.g. IA,IE,NPAE,CA,AN,AW,TF,TX")
    parser.add_argument("--fixed", metavar="T=ARCSEC,...",
                        help="terms held at these values (arcsec) instead of fitted, e.g. "
                             "W5=66 (Fomalont 1973 held refraction at 1'.1)")
    parser.add_argument("--json", action="store_true",
                        help="print the fit as JSON (the 'antsim fit --json' schema)")
    parser.add_argument("--write-model", metavar="FILE",
                        help="also write the fitted model as a TPOINT .mod file, in TPOINT's "
                             "term names and signs (usable as antsim run --model FILE)")
    parser.add_argument("--no-robust", action="store_true",
                        help="plain least squares on every observation (no outlier rejection)")
    parser.add_argument("--csv", action="append", default=[], metavar="'KEY: VALUE'",
                        help="a CSV setting the file does not state, e.g. 'sign: "
                             "true-minus-indicated' or 'units: d_el=arcsec' (repeatable)")
    parser.add_argument("--include-masked", action="store_true",
                        help="also fit the observations a TPOINT file masks with ';'")
    parser.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                        help="a progress bar, or none (default: a bar on a terminal, a line "
                             "every few seconds to stderr off one)")
    parser.add_argument("--mount", choices=("altaz",), default=None,
                        help="a TPOINT file's decimal records are Az/El whatever its options "
                             "say (a file without a mount option is read so, with a note)")
    parser.epilog = (
        "Robust by default: least-absolute-deviation fit, reject beyond 4x the mean absolute "
        "deviation, least squares, reject beyond 3x the rms, final least squares (Ghigo 1990). "
        "Statistics as TPOINT's: Sky RMS, Popn SD, sigmas scaled by the Sky RMS. The honest "
        "sigma is a cluster jackknife of the same coefficients: where the file has times "
        "(recordings, a CSV with a time column) the clusters are the observations within "
        f"{BLOCK_S:g} s time blocks, as in a run's fit.json and report; where it has none (a "
        "TPOINT file) they are single observations. The output names the one it used "
        "(docs/outputs.md, 'The honest sigma')."
    )


def _note(line: str) -> None:
    print(f"antsim fit: note: {line}", file=sys.stderr)


def main(args: argparse.Namespace) -> int:
    from antsim.fit.fitfile import fit_file, read_file

    file = read_file(args.recordings, csv_options=args.csv, mount=args.mount)
    for line in file.notes:
        _note(line)
    fitted = fit_file(file, model=args.model, terms=args.terms, fixed=args.fixed,
                      robust=not args.no_robust, include_masked=args.include_masked,
                      write_model=args.write_model, show_progress=args.progress)
    if args.json:
        json.dump(fitted.result.to_json(), sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        print(f"{Path(args.recordings)} ({file.kind_name})")
        print(fitted.result.summary())
        if args.write_model is not None:
            print(f"wrote {Path(args.write_model)} (TPOINT's term names and signs)")
    return 0

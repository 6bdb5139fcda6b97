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
import math
import sys
from pathlib import Path

from controller.errors import InputError
from controller.pointing.jackknife import BLOCK_S
from controller.pointing.model import NAMED_MODELS
from controller.pointing.modelio import MAX_VALUE_ARCSEC

#: default model per input format: TPOINT users (and a CSV of one's own measurements) start
#: from TPOINT's eight physical terms; antsim's own recordings come from the 45-ft, whose
#: model is Ghigo's ten terms.
DEFAULT_MODEL = {"tpoint": "tpoint8", "csv": "tpoint8", "ecsv": "ghigo10"}


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


def _terms_from_option(text: str) -> tuple[str, ...]:
    from controller.pointing.terms import is_term_name, term_refusal

    names = [t.strip().upper() for t in text.split(",")]
    if not text.strip() or any(not n for n in names):
        raise InputError("command line", "--terms", text,
                         "must be comma-separated term names with none empty")
    for name in names:
        if not is_term_name(name):
            problem, hint = term_refusal(name)
            raise InputError("command line", "--terms", name, problem, hint)
    duplicates = sorted({n for n in names if names.count(n) > 1})
    if duplicates:
        raise InputError("command line", "--terms", ",".join(duplicates), "listed twice")
    return tuple(names)


def _fixed_from_option(text: str | None, terms) -> dict[str, float]:
    """``--fixed T=ARCSEC,...``: terms of the fit held at these values."""
    if text is None:
        return {}
    names = [getattr(t, "name", t) for t in terms]
    fixed: dict[str, float] = {}
    for item in text.split(","):
        name, sep, value = item.partition("=")
        name = name.strip().upper()
        try:
            number = float(value)
        except ValueError:
            number = None
        if not sep or number is None:
            raise InputError("command line", "--fixed", item.strip(),
                             "must be TERM=ARCSEC, e.g. W5=66")
        if not math.isfinite(number) or abs(number) > MAX_VALUE_ARCSEC:
            raise InputError("command line", "--fixed", item.strip(),
                             f"the value must be finite and within +-{MAX_VALUE_ARCSEC:g} "
                             "arcsec (180 deg)")
        if name not in names:
            raise InputError("command line", "--fixed", name, "is not a term of the fit",
                             f"its terms are {' '.join(names)}")
        if name in fixed:
            raise InputError("command line", "--fixed", item.strip(),
                             f"gives {name} a second value (first {fixed[name]:g})")
        fixed[name] = number
    return fixed


def _terms_from_model(spec: str) -> tuple[tuple[str, ...], str]:
    if spec in NAMED_MODELS:
        return NAMED_MODELS[spec], spec
    path = Path(spec)
    if spec.strip() and not path.is_file():  # an empty one: load_model says so
        raise InputError("command line", "--model", spec,
                         "is neither a named model nor an existing model file",
                         f"named models: {', '.join(sorted(NAMED_MODELS))}")
    from controller.pointing.modelio import load_model

    return load_model(spec).names, path.stem


def _pointing_data(file, include_masked: bool, terms=()):
    """The pointing data of a file :func:`~controller.program.inputs.read_pointing_file`
    read. Thermal terms among ``terms`` read the recordings' structure temperatures, or
    proxies (their site and times)."""
    from controller.pointing.model import PointingModel
    from controller.pointing.proxies import PROXY_NAMES

    needed = PointingModel(list(terms)).regressors if terms else frozenset()
    if needed and file.kind == "tpoint":
        raise InputError(file.path, "--terms", ",".join(terms),
                         "thermal terms need recordings with structure temperatures or "
                         "with times and a site (antsim's ECSV), not a TPOINT file")
    data = file.pointing_data(include_masked=include_masked,
                              proxies=bool(needed & set(PROXY_NAMES)))
    missing = sorted(needed - set(data.aux or {}))
    if missing:
        raise InputError(file.path, "--terms", ",".join(terms),
                         f"thermal terms read {', '.join(missing)}, which these recordings do "
                         "not have", "fit them to recordings of an antenna with structure "
                         "temperature sensors (columns temp_*)")
    return data


def _note(line: str) -> None:
    print(f"antsim fit: note: {line}", file=sys.stderr)


def main(args: argparse.Namespace) -> int:
    from controller.pointing.fitting import fit_model
    from controller.program.inputs import read_pointing_file

    path = Path(args.recordings)
    file = read_pointing_file(path, purpose="fit", csv_options=args.csv, mount=args.mount)
    for line in file.notes:
        _note(line)
    equatorial = (float(file.meta["site"]["latitude_deg"])
                  if file.mount == "equatorial" else None)
    if equatorial is not None:
        terms, model_name = _equatorial_terms(args, equatorial)
    elif args.terms is not None:
        terms, model_name = _terms_from_option(args.terms), "custom"
    else:
        terms, model_name = _terms_from_model(
            DEFAULT_MODEL[file.kind] if args.model is None else args.model)
    fixed = _fixed_from_option(args.fixed, terms)
    target = Path(args.write_model) if args.write_model is not None else None
    if target is not None and (not args.write_model.strip() or target.is_dir()
                               or not target.parent.is_dir()):
        raise InputError("command line", "--write-model", str(args.write_model),
                         "is empty" if not args.write_model.strip() else "is a directory"
                         if target.is_dir() else "its folder does not exist")
    if target is not None and target.exists() and target.resolve() == path.resolve():
        raise InputError("command line", "--write-model", str(target),
                         "is the pointing data being fitted: writing the model there would "
                         "replace them", "give the model a file of its own")
    from antsim.blas import one_blas_thread
    from antsim.progress import Progress

    with Progress("fit", args.progress) as progress, one_blas_thread():
        progress.stage("reading")
        data = _pointing_data(file, args.include_masked, terms=terms)
        progress.stage(f"fitting {len(data)} observations")
        try:
            result = fit_model(data, terms, robust=not args.no_robust, name=model_name,
                               fixed=fixed)
        except InputError:
            raise
        except ValueError as err:  # too few observations, a term infinite at the zenith, ...
            raise InputError(str(path), "observations", len(data), str(err)) from None
        progress.stage("the honest sigma (jackknife)")
        result.sigma_honest_arcsec  # noqa: B018 (computed on first use: computed here)
    if target is not None:
        from controller.pointing.modelio import write_model_file
        from controller.pointing.tpoint import TPointModel

        caption = f"{path.name}: antsim fit, model {model_name}"
        write_model_file(TPointModel.from_fit(result, caption=caption), target)
    if args.json:
        json.dump(result.to_json(), sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        print(f"{path} ({file.kind_name})")
        print(result.summary())
        if target is not None:
            print(f"wrote {target} (TPOINT's term names and signs)")
    return 0


def _equatorial_terms(args: argparse.Namespace, latitude_deg: float):
    """Equatorial terms from ``--terms`` or a named equatorial ``--model`` (crane11)."""
    from controller.pointing.equatorial import EQUATORIAL_MODELS, equatorial_terms
    from controller.pointing.terms import TermError

    if args.terms is not None:
        names = [t.strip().upper() for t in args.terms.split(",")]
        try:
            return equatorial_terms(names, latitude_deg), "custom"
        except TermError as err:
            raise InputError("command line", "--terms", args.terms, str(err)) from None
    spec = "crane11" if args.model is None else args.model
    if spec not in EQUATORIAL_MODELS:
        raise InputError("command line", "--model", spec,
                         "these recordings are from an equatorial mount",
                         f"equatorial models: {', '.join(sorted(EQUATORIAL_MODELS))}")
    return equatorial_terms(EQUATORIAL_MODELS[spec], latitude_deg), spec

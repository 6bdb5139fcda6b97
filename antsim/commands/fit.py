"""`antsim fit RECORDINGS`: fit a pointing model to recordings or a TPOINT data file.

The file's format is detected by content: ECSV recordings from ``antsim run`` (read through
:func:`controller.program.recordings.read_pointing_data`) or TPOINT pointing data. Bad input
(missing file, malformed line, unknown term) ends as one line on stderr and exit status 2.
Recordings of an equatorial mount (metadata ``mount: equatorial``) are fitted in hour angle and
declination with TPOINT's equatorial terms (default model ``crane11``).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from controller.errors import InputError
from controller.pointing.jackknife import BLOCK_S
from controller.pointing.model import NAMED_MODELS

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
    from controller.pointing.terms import is_term_name

    names = [t.strip().upper() for t in text.split(",")]
    if not text.strip() or any(not n for n in names):
        raise InputError("command line", "--terms", text,
                         "must be comma-separated term names with none empty")
    for name in names:
        if not is_term_name(name):
            raise InputError("command line", "--terms", name, "unknown pointing term",
                             "use TPOINT names (IA IE CA NPAE AN AW TF TX ...), harmonics "
                             "such as HESA2, W1..W10, P1..P22 or thermal terms (TEDFB ...: "
                             "docs/assumptions.md)")
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
        if name not in names:
            raise InputError("command line", "--fixed", name, "is not a term of the fit",
                             f"its terms are {' '.join(names)}")
        fixed[name] = number
    return fixed


def _terms_from_model(spec: str) -> tuple[tuple[str, ...], str]:
    if spec in NAMED_MODELS:
        return NAMED_MODELS[spec], spec
    path = Path(spec)
    if not path.is_file():
        raise InputError("command line", "--model", spec,
                         "is neither a named model nor an existing model file",
                         f"named models: {', '.join(sorted(NAMED_MODELS))}")
    from controller.pointing.modelio import load_model

    return load_model(path).names, path.stem


def _read_data(path: Path, fmt: str, include_masked: bool, mount: str | None, say,
               terms=(), table=None):
    """The pointing data of a TPOINT file, recordings (``table``, read already) or a CSV
    (``table`` too); a TPOINT reader's notes (how a file without a mount option was read)
    go to ``say``. Thermal terms among ``terms`` read the recordings' structure
    temperatures, or proxies (their site and times)."""
    from controller.pointing.model import PointingModel
    from controller.pointing.proxies import PROXY_NAMES

    needed = PointingModel(list(terms)).regressors if terms else frozenset()
    if fmt == "tpoint":
        from controller.pointing.tpoint import read_tpoint

        if needed:
            raise InputError(str(path), "--terms", ",".join(terms),
                             "thermal terms need recordings with structure temperatures or "
                             "with times and a site (antsim's ECSV), not a TPOINT file")
        data = read_tpoint(path, mount=mount)
        for note in data.notes:
            say(f"note: {note}")
        return data.pointing_data(include_masked=include_masked)
    if mount is not None:
        raise InputError(str(path), "--mount", mount, "applies to TPOINT data files only",
                         "recordings name their mount in their metadata")
    if fmt == "csv":
        from controller.program.csvdata import pointing_data

        data = pointing_data(table)
    else:
        from controller.program.recordings import table_pointing_data

        data = table_pointing_data(table, str(path), proxies=bool(needed & set(PROXY_NAMES)))
    data = _with_times(data, fmt, table)
    missing = sorted(needed - set(data.aux or {}))
    if missing:
        raise InputError(str(path), "--terms", ",".join(terms),
                         f"thermal terms read {', '.join(missing)}, which these recordings do "
                         "not have", "fit them to recordings of an antenna with structure "
                         "temperature sensors (columns temp_*)")
    return data


def _with_times(data, fmt: str, table):
    """``data`` with each observation's time (s) where the file has times, so that the honest
    sigma clusters the observations in time blocks, as a run's fit.json does: recordings
    (the rows read: the averaged polarization, good scans) and a CSV with a time column."""
    import dataclasses

    import numpy as np

    if fmt == "csv":
        times = table.columns.get("t_s")
    elif "t_s" in table.colnames:
        rows = np.asarray(table["polarization"]) == "AVG"
        if "good" in table.colnames:
            rows &= np.asarray(table["good"], dtype=bool)
        else:
            rows &= np.isfinite(np.asarray(table["xel_arcmin"], dtype=float))
            rows &= np.isfinite(np.asarray(table["el_arcmin"], dtype=float))
        times = np.asarray(table["t_s"], dtype=float)[rows]
    else:
        times = None
    if times is None:
        return data
    if len(times) != len(data):  # the reader's selection of rows changed: keep them in step
        raise RuntimeError(f"{len(times)} times for {len(data)} observations")
    return dataclasses.replace(data, t_s=np.asarray(times, dtype=float))


def _note(line: str) -> None:
    print(f"antsim fit: note: {line}", file=sys.stderr)


def main(args: argparse.Namespace) -> int:
    from controller.pointing.fitting import fit_model
    from controller.program.csvdata import input_format_and_text

    path = Path(args.recordings)
    fmt, text = input_format_and_text(path)
    if args.csv and fmt != "csv":
        raise InputError("command line", "--csv", args.csv[0], f"{path} is not a CSV file")
    if fmt == "mod":
        raise InputError(str(path), "RECORDINGS", str(path),
                         "is a TPOINT model (.mod) file, not pointing data",
                         "pass a model file with --model")
    table = None
    if fmt == "csv":
        from controller.program.csvdata import read_csv

        table = read_csv(path, args.csv)
    if fmt == "ecsv":
        from controller.program.recordings import read_recordings, recording_notes

        table = read_recordings(path, text=text)
        for line in recording_notes(table, "fit"):
            _note(f"{path}: {line}")
    equatorial = (float(table.meta["site"]["latitude_deg"])
                  if table is not None and table.meta.get("mount") == "equatorial" else None)
    if equatorial is not None:
        terms, model_name = _equatorial_terms(args, equatorial)
    elif args.terms is not None:
        terms, model_name = _terms_from_option(args.terms), "custom"
    else:
        terms, model_name = _terms_from_model(args.model or DEFAULT_MODEL[fmt])
    fixed = _fixed_from_option(args.fixed, terms)
    target = Path(args.write_model) if args.write_model else None
    if target is not None and (target.is_dir() or not target.parent.is_dir()):
        raise InputError("command line", "--write-model", str(target),
                         "is a directory" if target.is_dir() else "its folder does not exist")
    from antsim.blas import one_blas_thread
    from antsim.progress import Progress

    with Progress("fit", args.progress) as progress, one_blas_thread():
        progress.stage("reading")
        data = _read_data(path, fmt, args.include_masked, args.mount,
                          say=lambda text: progress.write(text, file=sys.stderr), terms=terms,
                          table=table)
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
        kind = {"tpoint": "TPOINT data", "csv": "CSV measurements"}.get(fmt, "recordings")
        print(f"{path} ({kind})")
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
    spec = args.model or "crane11"
    if spec not in EQUATORIAL_MODELS:
        raise InputError("command line", "--model", spec,
                         "these recordings are from an equatorial mount",
                         f"equatorial models: {', '.join(sorted(EQUATORIAL_MODELS))}")
    return equatorial_terms(EQUATORIAL_MODELS[spec], latitude_deg), spec

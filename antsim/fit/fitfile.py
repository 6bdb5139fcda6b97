"""A file of pointing measurements fitted as ``antsim fit`` fits it.

The file is read through the front door of every command's pointing data,
:func:`controller.program.inputs.read_pointing_file`, which decides its kind by content
(ECSV recordings from ``antsim run``, TPOINT pointing data, CSV measurements). The terms
come from a named model, a model file, a list of term names, or the default of the file's
kind; recordings of an equatorial mount (metadata ``mount: equatorial``) are fitted in hour
angle and declination with TPOINT's equatorial terms (default model ``crane11``). Bad input
(a missing file, a malformed line, an unknown term) is one
:class:`~controller.errors.InputError` line naming the option (``--terms``, ``--fixed``,
``--model``, ``--write-model``) as the command line has it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from antsim.blas import one_blas_thread
from antsim.progress import Progress
from controller.errors import InputError
from controller.pointing.data import PointingData
from controller.pointing.equatorial import EQUATORIAL_MODELS, equatorial_terms
from controller.pointing.fitting import fit_model
from controller.pointing.model import NAMED_MODELS, PointingModel
from controller.pointing.modelio import MAX_VALUE_ARCSEC, load_model, write_model_file
from controller.pointing.proxies import PROXY_NAMES
from controller.pointing.result import FitResult
from controller.pointing.terms import TermError, is_term_name, term_refusal
from controller.pointing.tpoint import TPointModel
from controller.program.inputs import PointingFile, read_pointing_file

__all__ = ["DEFAULT_MODEL", "FileFit", "fit_file", "model_target", "read_file"]

#: default model per input format: TPOINT users (and a CSV of one's own measurements) start
#: from TPOINT's eight physical terms; antsim's own recordings come from the 45-ft, whose
#: model is Ghigo's ten terms.
DEFAULT_MODEL = {"tpoint": "tpoint8", "csv": "tpoint8", "ecsv": "ghigo10"}


@dataclass(frozen=True)
class FileFit:
    """A file fitted: the file as read, the pointing data fitted, the fit (its honest sigma
    computed) and the name of the model whose terms were fitted."""

    file: PointingFile
    data: PointingData
    result: FitResult
    model_name: str

    @property
    def caption(self) -> str:
        """The caption of the model file written of this fit (its name read back)."""
        return f"{Path(self.file.path).name}: antsim fit, model {self.model_name}"

    def write_model(self, target: str | Path) -> Path:
        """Write the fitted model as a TPOINT ``.mod`` file (TPOINT's names and signs)."""
        return write_model_file(TPointModel.from_fit(self.result, caption=self.caption),
                                target)


def read_file(path: str | Path, csv_options: Sequence[str] = (),
              mount: str | None = None) -> PointingFile:
    """The file to fit (its notes are for the user: the command prints them)."""
    return read_pointing_file(Path(path), purpose="fit", csv_options=list(csv_options),
                              mount=mount)


def model_target(text: str | None, data_path: str | Path) -> Path | None:
    """Where ``--write-model`` writes (None: nowhere), refused in one line when empty, a
    folder, in a folder that does not exist, or the data being fitted."""
    if text is None:
        return None
    target = Path(text)
    if not text.strip() or target.is_dir() or not target.parent.is_dir():
        raise InputError("command line", "--write-model", str(text),
                         "is empty" if not text.strip() else "is a directory"
                         if target.is_dir() else "its folder does not exist")
    if target.exists() and target.resolve() == Path(data_path).resolve():
        raise InputError("command line", "--write-model", str(target),
                         "is the pointing data being fitted: writing the model there would "
                         "replace them", "give the model a file of its own")
    return target


def fit_file(file: PointingFile, *, model: str | None = None, terms: str | None = None,
             fixed: str | None = None, robust: bool = True, include_masked: bool = False,
             write_model: str | None = None, show_progress: bool | None = False) -> FileFit:
    """Fit ``file`` (:func:`read_file`) as ``antsim fit`` does. ``model``: a named model or
    a model file whose terms are fitted; ``terms``: "T1,T2,..." instead; ``fixed``:
    "T=ARCSEC,..." held at those values; ``robust``: the 1990 report's stages (else plain
    least squares); ``include_masked``: a TPOINT file's masked observations too;
    ``write_model``: a ``.mod`` file to write the fitted model to; ``show_progress``: a
    progress bar (None: on a terminal, lines off one). The options are the command line's,
    in its words."""
    if model is not None and terms is not None:  # argparse refuses both on the command line
        raise InputError("command line", "--terms", terms, "not with --model",
                         "give the terms by a model or by name, not both")
    if file.mount == "equatorial":
        fitted, model_name = _equatorial_terms(model, terms,
                                               float(file.meta["site"]["latitude_deg"]))
    elif terms is not None:
        fitted, model_name = _terms_from_option(terms), "custom"
    else:
        fitted, model_name = _terms_from_model(
            DEFAULT_MODEL[file.kind] if model is None else model)
    held = _fixed_from_option(fixed, fitted)
    target = model_target(write_model, file.path)
    with Progress("fit", show_progress) as progress, one_blas_thread():
        progress.stage("reading")
        data = _pointing_data(file, include_masked, terms=fitted)
        progress.stage(f"fitting {len(data)} observations")
        try:
            result = fit_model(data, fitted, robust=robust, name=model_name, fixed=held)
        except InputError:
            raise
        except ValueError as err:  # too few observations, a term infinite at the zenith, ...
            raise InputError(str(file.path), "observations", len(data), str(err)) from None
        progress.stage("the honest sigma (jackknife)")
        result.sigma_honest_arcsec  # noqa: B018 (computed on first use: computed here)
    fitted_file = FileFit(file, data, result, model_name)
    if target is not None:
        fitted_file.write_model(target)
    return fitted_file


def _terms_from_option(text: str) -> tuple[str, ...]:
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
    return load_model(spec).names, path.stem


def _pointing_data(file: PointingFile, include_masked: bool, terms=()):
    """The pointing data of a file :func:`~controller.program.inputs.read_pointing_file`
    read. Thermal terms among ``terms`` read the recordings' structure temperatures, or
    proxies (their site and times)."""
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


def _equatorial_terms(model: str | None, terms: str | None, latitude_deg: float):
    """Equatorial terms from ``--terms`` or a named equatorial ``--model`` (crane11)."""
    if terms is not None:
        names = [t.strip().upper() for t in terms.split(",")]
        try:
            return equatorial_terms(names, latitude_deg), "custom"
        except TermError as err:
            raise InputError("command line", "--terms", terms, str(err)) from None
    spec = "crane11" if model is None else model
    if spec not in EQUATORIAL_MODELS:
        raise InputError("command line", "--model", spec,
                         "these recordings are from an equatorial mount",
                         f"equatorial models: {', '.join(sorted(EQUATORIAL_MODELS))}")
    return equatorial_terms(EQUATORIAL_MODELS[spec], latitude_deg), spec

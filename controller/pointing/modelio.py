"""Loading and saving pointing models: named models, TPOINT ``.mod`` files, ``fit.json``."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import TYPE_CHECKING

from controller.errors import InputError, read_text_file
from controller.filekind import KIND_NAMES, file_kind

from .legacy import W_TERMS_KEY, names_w_terms, relabel_reconstructed, w_terms_marker
from .model import NAMED_MODELS, PointingModel
from .terms import TermError
from .tpoint import TPointModel, parse_mod, write_mod
from .vocabulary import in_tpoint_terms

if TYPE_CHECKING:
    from .tpoint import TPointModel

__all__ = [
    "check_value",
    "load_model",
    "model_from_json",
    "model_to_json",
    "read_model_file",
    "refuse_empty",
    "write_model_file",
]


def model_to_json(model: PointingModel) -> dict:
    return {"model": model.name, **w_terms_marker(model.names),
            "terms": {n: {"value_arcsec": v} for n, v in model.as_dict().items()}}


def write_model_file(model: TPointModel, path: str | Path) -> Path:
    """Write ``model`` as a TPOINT ``.mod`` file in TPOINT's vocabulary and sign wherever a
    term maps (:func:`controller.pointing.vocabulary.in_tpoint_terms`: the old name in a
    comment on the line, units and sign convention in the header); :func:`load_model` (and
    ``antsim run --model``) reads it back. The one writer of ``run``'s ``model.dat``,
    ``fit --write-model`` and ``diagnose``'s ``model_updated.dat``."""
    path = Path(path)
    write_mod(in_tpoint_terms(model), path)
    return path


#: the largest coefficient a model file may give (arcsec): half a turn
MAX_VALUE_ARCSEC = 648000.0


def check_value(value: float, where: str, field: str) -> float:
    """A model coefficient (arcsec): finite and within half a turn, else one InputError."""
    if not math.isfinite(value) or abs(value) > MAX_VALUE_ARCSEC:
        raise InputError(where, field, value, f"must be finite and within +-{MAX_VALUE_ARCSEC:g}"
                         " arcsec (180 deg)")
    return value


def model_from_json(data: dict, where: str) -> PointingModel:
    """A model from ``{"model": name, "terms": {"IA": {"value_arcsec": x}, ...}}``; from a
    fit's document (``fit.json``, with ``sky_rms_arcsec``) a
    :class:`~controller.pointing.tpoint.TPointModel` that remembers the fit's Sky RMS,
    observations and sigmas."""
    if not isinstance(data, dict) or "terms" not in data:
        raise InputError(where, "terms", "<missing>", "a model JSON needs a 'terms' object")
    terms = data["terms"]
    if not isinstance(terms, dict):
        raise InputError(where, "terms", terms, "must be an object of term -> {value_arcsec}")
    values_of: dict[str, float] = {}
    upper: dict[str, str] = {}
    for name, entry in terms.items():
        if str(name).strip().upper() in upper:
            raise InputError(where, "terms", name, f"repeats {upper[str(name).strip().upper()]}"
                             " (term names are not case-sensitive)")
        upper[str(name).strip().upper()] = name
        value = entry.get("value_arcsec") if isinstance(entry, dict) else entry
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise InputError(where, f"terms.{name}.value_arcsec", value, "must be a number")
        try:
            number = float(value)
        except OverflowError:  # an integer of hundreds of digits
            raise InputError(where, f"terms.{name}.value_arcsec", value,
                             f"must be finite and within +-{MAX_VALUE_ARCSEC:g} arcsec") \
                from None
        values_of[name] = check_value(number, where, f"terms.{name}.value_arcsec")
    if names_w_terms(values_of) and W_TERMS_KEY not in data:
        values_of = relabel_reconstructed(values_of, where)
    names, values = list(values_of), list(values_of.values())
    name = str(data.get("model", "custom"))
    if not name.isprintable():  # written into recordings' headers and model files' captions
        raise InputError(where, "model", name, "holds a control character (a line break, "
                         "a tab, ...): a model's name is one line of text")
    try:
        model = PointingModel(names, values, name=name)
    except TermError as err:
        raise InputError(where, "terms", names, str(err)) from None
    rms = data.get("sky_rms_arcsec")
    if rms is not None and (not _is_number(rms) or not 0.0 <= rms <= MAX_VALUE_ARCSEC):
        raise InputError(where, "sky_rms_arcsec", rms,
                         f"must be a number within 0..{MAX_VALUE_ARCSEC:g} arcsec")
    for name in names:
        entry = terms.get(name)
        sigma = entry.get("sigma_arcsec") if isinstance(entry, dict) else None
        if sigma is not None and (not _is_number(sigma) or sigma < 0
                                  or math.isinf(sigma)):
            raise InputError(where, f"terms.{name}.sigma_arcsec", sigma,
                             "must be a finite number >= 0 (NaN or null: none)")
    if isinstance(rms, int | float) and not isinstance(rms, bool):
        sigmas = [_number_or_nan(terms.get(n)) for n in names] if names == list(terms) \
            else None  # renamed from an old file: its sigmas are left out
        n_used = data.get("n_used", 0)
        return TPointModel.from_model(model, sigmas, n_obs=n_used if isinstance(n_used, int)
                                      else 0, sky_rms_arcsec=float(rms))
    return model


def _is_number(value) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _number_or_nan(entry) -> float:
    value = entry.get("sigma_arcsec") if isinstance(entry, dict) else None
    return float(value) if isinstance(value, int | float) and not isinstance(value, bool) \
        else float("nan")


def read_model_file(path: str | Path) -> tuple[str, object]:
    """What a model file holds: ``("json", data)`` for JSON (a ``fit.json``), or
    ``("mod", text)`` for a TPOINT ``.mod`` file, the kind decided by
    :func:`controller.filekind.file_kind`; anything else (TPOINT pointing data, ECSV
    recordings, CSV measurements, free text, a JSON list) is one InputError line."""
    where = str(path)
    text = read_text_file(path, limit=MAX_MODEL_BYTES)
    try:
        kind = file_kind(path, text)
    except InputError as err:  # free text: say what it is not, as a model
        raise InputError(where, "model", where, "is not a pointing model (a TPOINT .mod file "
                         f"or a fit.json): {err.problem}") from None
    if kind == "json":
        return "json", _json(text, where)
    if kind != "mod":
        what = KIND_NAMES[kind]
        raise InputError(where, "model", where, f"is {what}, not a pointing model",
                         "give a TPOINT .mod file, a fit.json or a named model")
    return "mod", text


#: the largest model file (bytes): a model of 10,000 terms is below 1 MB
MAX_MODEL_BYTES = 16 << 20

#: how deep a model's JSON may nest: a fit.json is three levels deep
_MAX_JSON_DEPTH = 32


def _json(text: str, where: str):
    """The JSON document of a model file, or one InputError line (its syntax, or nesting
    so deep that it is no model: Python's parser would overflow its stack)."""
    depth = deepest = 0
    in_string = escaped = False
    for ch in text:  # the nesting, counted before parsing (strings skipped)
        if in_string:
            if escaped:
                escaped = False
            elif ch == "\\":
                escaped = True
            elif ch == '"':
                in_string = False
        elif ch == '"':
            in_string = True
        elif ch in "[{":
            depth += 1
            deepest = max(deepest, depth)
            if deepest > _MAX_JSON_DEPTH:
                raise InputError(where, "JSON", f"nested {deepest} levels deep",
                                 f"is no model: a model's JSON nests at most "
                                 f"{_MAX_JSON_DEPTH} levels")
        elif ch in "]}":
            depth -= 1
    def pairs(items):  # an object's keys once each: JSON readers keep the last silently
        keys: dict[str, None] = {}
        for key, _ in items:
            if key in keys:
                raise InputError(where, "JSON", key, "is a key given twice in one object")
            keys[key] = None
        return dict(items)

    try:
        return json.loads(text, object_pairs_hook=pairs)
    except json.JSONDecodeError as err:
        raise InputError(f"{where}:{err.lineno}", "JSON", err.msg, "invalid JSON") from None
    except ValueError as err:  # an integer beyond Python's digit limit
        if isinstance(err, InputError):
            raise
        raise InputError(where, "JSON", str(err).split(";")[0], "is no number a model "
                         "holds") from None


def refuse_empty(model: PointingModel, where: str) -> PointingModel:
    """``model``, unless it has no terms: a model file without terms is a mistake (a cold
    start is asked for by name)."""
    if not len(model):
        raise InputError(where, "model", where, "holds no pointing terms",
                         "use --model none for a cold start")
    return model


def load_model(spec: str | Path) -> PointingModel:
    """A pointing model from a name (zero coefficients), a ``.mod`` file or a JSON file."""
    text_spec = str(spec)
    if text_spec in NAMED_MODELS:
        return PointingModel(text_spec)
    if not text_spec.strip():
        raise InputError("command line", "--model", text_spec, "is empty",
                         f"give a named model ({', '.join(sorted(NAMED_MODELS))}), a TPOINT "
                         ".mod file or a fit.json")
    path = Path(spec)
    if not path.exists():
        raise InputError("command line", "--model", text_spec,
                         "neither a named model nor an existing file",
                         f"named models: {', '.join(sorted(NAMED_MODELS))}")
    kind, content = read_model_file(path)
    if kind == "json":
        return refuse_empty(model_from_json(content, str(path)), str(path))
    return refuse_empty(parse_mod(content, source=str(path)), str(path))

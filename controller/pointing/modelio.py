"""Loading and saving pointing models: named models, TPOINT ``.mod`` files, ``fit.json``."""

from __future__ import annotations

import json
from pathlib import Path

from controller.errors import InputError

from .model import NAMED_MODELS, PointingModel
from .terms import TermError

__all__ = ["load_model", "model_from_json", "model_to_json"]


def model_to_json(model: PointingModel) -> dict:
    return {"model": model.name,
            "terms": {n: {"value_arcsec": v} for n, v in model.as_dict().items()}}


def model_from_json(data: dict, where: str) -> PointingModel:
    """A model from ``{"model": name, "terms": {"IA": {"value_arcsec": x}, ...}}``."""
    if not isinstance(data, dict) or "terms" not in data:
        raise InputError(where, "terms", "<missing>", "a model JSON needs a 'terms' object")
    terms = data["terms"]
    if not isinstance(terms, dict):
        raise InputError(where, "terms", terms, "must be an object of term -> {value_arcsec}")
    names, values = [], []
    for name, entry in terms.items():
        value = entry.get("value_arcsec") if isinstance(entry, dict) else entry
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise InputError(where, f"terms.{name}.value_arcsec", value, "must be a number")
        names.append(name)
        values.append(float(value))
    try:
        return PointingModel(names, values, name=str(data.get("model", "custom")))
    except TermError as err:
        raise InputError(where, "terms", names, str(err)) from None


def load_model(spec: str | Path) -> PointingModel:
    """A pointing model from a name (zero coefficients), a ``.mod`` file or a JSON file."""
    text_spec = str(spec)
    if text_spec in NAMED_MODELS:
        return PointingModel(text_spec)
    path = Path(spec)
    if not path.exists():
        raise InputError(text_spec, "model", text_spec,
                         "neither a named model nor an existing file",
                         f"named models: {', '.join(sorted(NAMED_MODELS))}")
    head = path.read_text(encoding="utf-8", errors="replace").lstrip()[:1]
    if head == "{":
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
        except json.JSONDecodeError as err:
            raise InputError(str(path), "JSON", err.msg, f"invalid JSON at line {err.lineno}") \
                from None
        return model_from_json(data, str(path))
    from .tpoint import read_mod

    return read_mod(path)

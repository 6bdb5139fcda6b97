"""A campaign as ``antsim run`` asks for one, checked before anything runs: the seed, the
pointing model the controller uses, and the output directory (no earlier run's products
overwritten). The command line and the Python API (:func:`antsim.api.run_campaign`) ask
through here, with the same one-line errors.
"""

from __future__ import annotations

import os
from pathlib import Path

from antsim.scenario import Scenario, overcorrection, thermal_terms_of
from controller.errors import InputError
from controller.pointing.equatorial import load_equatorial_model
from controller.pointing.model import PointingModel
from controller.pointing.modelio import load_model

from .outputs import PRODUCTS

__all__ = ["check_seed", "model_in_use", "refuse_earlier_run"]


def check_seed(seed: int | None) -> int | None:
    """``seed`` (None: the scenario's), unless negative: one InputError line."""
    if seed is not None and seed < 0:
        raise InputError("command line", "--seed", seed, "must be >= 0")
    return seed


def model_in_use(spec: str | PointingModel | None, scenario: Scenario) -> PointingModel | None:
    """The pointing model the controller uses (``--model``): None for the scenario's own; a
    named model, a model file or a fit.json by its name or path (on an equatorial mount
    re-bound to the mount's terms); or a model already made. A model with thermal terms is
    refused: the controller cannot apply them."""
    if spec is None:
        return None
    if isinstance(spec, str) and not spec.strip():
        raise InputError("command line", "--model", spec, "is empty",
                         "give a named model (none, ghigo10, ...) or a model file")
    given = spec if isinstance(spec, str) else spec.name
    if isinstance(spec, PointingModel):
        model = spec
    elif scenario.mount.kind == "equatorial":
        model = load_equatorial_model(spec, scenario.site.latitude_deg)
    else:
        model = load_model(spec)
    thermal = [] if scenario.mount.kind == "equatorial" else thermal_terms_of(model)
    if thermal:
        raise InputError("command line", "--model", given,
                         f"has thermal terms ({', '.join(thermal)}), which the controller "
                         "does not apply (they need structure temperatures at every "
                         "instant)", "give a model of the position alone")
    found = overcorrection(model, scenario.mount, scenario.controller.scheduler)
    if found is not None:
        raise InputError("command line", "--model", given, found.problem,
                         "check the model's values and their units")
    return model


def refuse_earlier_run(out: Path, resume: bool) -> None:
    """Refuse ``out`` where it holds an earlier run's products (unless ``resume``), or, to
    resume, recordings that are a link or not a file."""
    # a link counts (a dangling one too): antsim never writes through one
    present = [name for name in PRODUCTS if os.path.lexists(out / name)]
    if present and not resume:
        raise InputError("command line", "--out", str(out),
                         f"already holds {' '.join(present)} of an earlier run",
                         "use --resume to continue that run, or an empty or new directory")
    recordings = out / "recordings.ecsv"
    if resume and recordings.is_symlink():
        raise InputError("command line", "--out", str(out),
                         "holds recordings.ecsv as a symbolic link: a resumed run appends "
                         "to its recordings and does not write through a link",
                         "copy the file there, or run into a new directory")
    if resume and recordings.exists() and not recordings.is_file():
        raise InputError("command line", "--out", str(out),
                         "holds recordings.ecsv as something other than a file (a "
                         "directory, a FIFO): there is no run to resume",
                         "run into a new directory")

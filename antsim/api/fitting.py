"""``antsim.fit_model``: a pointing model fitted to a file, as ``antsim fit`` fits it."""

from __future__ import annotations

import os
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from antsim.fit.fitfile import fit_file, read_file
from controller.errors import Note

from .campaign import recordings_file
from .fit import Fit
from .show import as_arcsec

__all__ = ["fit_model"]


def fit_model(data: str | os.PathLike | Any, *, model: str | os.PathLike | None = None,
              terms: str | Sequence[str] | None = None,
              fixed: Mapping[str, Any] | None = None, robust: bool = True,
              csv: Sequence[str] = (), include_masked: bool = False,
              mount: str | None = None, write_model: str | os.PathLike | None = None,
              progress: bool | None = False) -> Fit:
    """Fit a pointing model to a file, as ``antsim fit`` does.

    ``data``: recordings (``recordings.ecsv`` of a run), a TPOINT data file or a CSV of your
    own measurements (docs/inputs.md), or a :class:`~antsim.api.Campaign` run with ``out=``
    (its recordings). ``model``: a named model (``tpoint8``, ``ghigo10``, ...) or a model
    file whose terms are fitted (default: ``tpoint8`` for TPOINT data and CSV, ``ghigo10``
    for recordings, ``crane11`` on an equatorial mount); or ``terms``, e.g.
    ``["IA", "IE", "CA"]``. ``fixed``: terms held at values (``{"W5": 66 * u.arcsec}``, or
    numbers of arcsec). ``robust``: the 1990 report's stages (least absolute deviations,
    rejections, least squares), else plain least squares as TPOINT. ``csv``: CSV settings
    the file does not state ("sign: true-minus-indicated"); ``include_masked``: a TPOINT
    file's masked observations too; ``mount="altaz"``: a TPOINT file's decimal records as
    Az/El. ``write_model``: also write the model as a TPOINT ``.mod`` file; nothing else is
    written. ``progress``: a progress bar on stderr (None: on a terminal only).

    The file's notes (what its reader left out or assumed) are issued as
    :class:`controller.errors.Note` warnings. Bad input raises
    :class:`controller.errors.InputError` with the line ``antsim fit`` prints."""
    path = recordings_file(data, "antsim.fit_model")
    term_text = terms if terms is None or isinstance(terms, str) else ",".join(terms)
    fixed_text = None if not fixed else ",".join(
        f"{name}={as_arcsec(value, 'antsim.fit_model', f'fixed[{name!r}]')!r}"
        for name, value in fixed.items())
    file = read_file(path, csv_options=csv, mount=mount)
    for line in file.notes:
        warnings.warn(line, Note, stacklevel=2)
    fitted = fit_file(file, model=None if model is None else os.fspath(model), terms=term_text,
                      fixed=fixed_text, robust=robust, include_masked=include_masked,
                      write_model=None if write_model is None else os.fspath(write_model),
                      show_progress=progress)
    return Fit(fitted.result, fitted.data, source=Path(path).name, caption=fitted.caption,
               notes=tuple(file.notes))

"""The front door to a user's pointing file: its kind decided once, the file read once.

Every command that takes a file of pointing measurements (``antsim fit``, ``antsim
diagnose``) calls :func:`read_pointing_file`. It reads the file (bounded:
:func:`~controller.errors.read_text_file`), asks :func:`controller.filekind.file_kind` what
it is, and hands the text to that kind's reader:

* TPOINT pointing data: :func:`controller.pointing.tpoint.parse_tpoint`;
* antsim's recordings (ECSV): :func:`controller.program.recordings.read_recordings`;
* CSV measurements: :func:`controller.program.csvdata.read_csv`.

The answer is a :class:`PointingFile` naming the kind and holding what the reader made,
with the notes the user sees (what is left out for want of a column, how a file without a
mount option was read). A model given where data is expected (a TPOINT ``.mod`` file, a
``fit.json``), an option that does not apply to the kind (``--csv``, ``--mount``) and
anything no reader takes are one :class:`~controller.errors.InputError` line. Models given
with ``--model`` go through :func:`controller.pointing.modelio.load_model`, whose kind the
same :func:`~controller.filekind.file_kind` decides.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from controller.errors import InputError, read_text_file
from controller.filekind import file_kind
from controller.pointing.tpoint import TPointData, parse_tpoint

from .csvdata import CsvData, pointing_data, read_csv
from .recordings import read_recordings, recording_notes, table_pointing_data

__all__ = ["DataKind", "PointingFile", "read_pointing_file"]

DataKind = Literal["tpoint", "ecsv", "csv"]

#: each kind of pointing data in words
DATA_KIND_NAMES: dict[str, str] = {"tpoint": "TPOINT data", "ecsv": "recordings",
                                   "csv": "CSV measurements"}


@dataclass(frozen=True)
class PointingFile:
    """A user's file of pointing measurements, read: its ``kind`` and, for that kind, the
    ``tpoint`` data, the ``recordings`` (an astropy Table in the units of the column names)
    or the ``csv`` measurements (recordings columns). ``notes``: one line each, starting
    with the file's name, of what the reader left out or assumed."""

    path: str
    kind: DataKind
    tpoint: TPointData | None = None
    recordings: Any = None
    csv: CsvData | None = None
    notes: tuple[str, ...] = ()

    @property
    def kind_name(self) -> str:
        """The kind in words: "TPOINT data", "recordings", "CSV measurements"."""
        return DATA_KIND_NAMES[self.kind]

    @property
    def table(self) -> Any:
        """The recordings or the CSV measurements as columns and ``meta`` (None for TPOINT
        data)."""
        return self.recordings if self.kind == "ecsv" else self.csv

    @property
    def meta(self) -> dict[str, Any]:
        """The metadata (site, mount, epoch, model in use) a table carries; {} for TPOINT."""
        table = self.table
        return dict(table.meta) if table is not None else {}

    @property
    def mount(self) -> str:
        """The mount whose axes the positions are on: "altaz" or "equatorial"."""
        return str(self.meta.get("mount") or "altaz")

    def pointing_data(self, include_masked: bool = False, proxies: bool = False):
        """The measurements as :class:`~controller.pointing.data.PointingData` (total
        pointing error, indicated minus true), with their times where the file has them
        (recordings, a CSV with a time column: the honest sigma's time blocks).
        ``include_masked``: a TPOINT file's masked observations too; ``proxies``: the
        recordings' thermal proxies (site and times)."""
        if self.kind == "tpoint":
            return self.tpoint.pointing_data(include_masked=include_masked)
        if self.kind == "csv":
            return pointing_data(self.csv)
        return table_pointing_data(self.recordings, self.path, proxies=proxies,
                                   with_times=True)


def read_pointing_file(path: str | Path, *, purpose: Literal["fit", "diagnose"] = "fit",
                       csv_options: Sequence[str] = (), mount: str | None = None
                       ) -> PointingFile:
    """Read a file of pointing measurements of any kind (see the module). ``purpose``: what
    it is read for (``"diagnose"`` needs the recordings' times and names what the tests
    miss); ``csv_options``: CSV settings from the command line (``--csv``); ``mount="altaz"``
    reads a TPOINT file's decimal records as Az/El (``--mount altaz``)."""
    where = str(path)
    if where and not Path(path).exists():
        raise InputError(where, "RECORDINGS", where, "no such file")
    text = read_text_file(path)
    kind = file_kind(path, text)
    if csv_options and kind != "csv":
        raise InputError("command line", "--csv", csv_options[0], f"{where} is not a CSV file")
    if kind == "mod":
        raise InputError(where, "RECORDINGS", where,
                         "is a TPOINT model (.mod) file, not pointing data",
                         "pass a model file with --model")
    if kind == "json":
        raise InputError(where, "RECORDINGS", where,
                         "is JSON (a model such as a fit.json), not pointing data",
                         "pass a model file with --model")
    if mount is not None and kind != "tpoint":
        raise InputError(where, "--mount", mount, "applies to TPOINT data files only",
                         "recordings name their mount in their metadata" if kind == "ecsv"
                         else "")
    if kind == "tpoint":
        data = parse_tpoint(text, source=where, mount=mount)
        return PointingFile(where, "tpoint", tpoint=data, notes=tuple(data.notes))
    if kind == "csv":
        measurements = read_csv(path, csv_options, text=text)
        notes = measurements.notes if purpose == "diagnose" else []
        return PointingFile(where, "csv", csv=measurements,
                            notes=tuple(f"{where}: {n}" for n in notes))
    table = read_recordings(path, purpose=purpose, text=text)
    return PointingFile(where, "ecsv", recordings=table,
                        notes=tuple(f"{where}: {n}" for n in recording_notes(table, purpose)))

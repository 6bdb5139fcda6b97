"""Recordings: one ECSV row per reduced cross scan and polarization, written as scans complete.

The header (column names, units, types, descriptions and the run's metadata: scenario, seed,
software version, site, beam, step, integration time, the pointing model in use) is written
once; each scan's rows are then appended with a single ``write`` system call, so a run killed
at any moment leaves a file that reads back with every completed scan (a partial last line
is ignored by :func:`read_recordings`). Resuming replays the deterministic run, checks that
the rows it regenerates equal the ones on disk, and appends the rest: the result is
byte-identical to an uninterrupted run.

Sign convention: ``xel_arcmin``/``el_arcmin`` are the measured corrections to apply (source
minus beam), "indicated minus true" like the model's offset; the total pointing error is
measured + model in use + applied correction (columns ``model_*`` and ``applied_*``).

Columns beyond the 1990 set are added only where they apply (:func:`recording_columns`):
``ha_deg``/``dec_deg`` for an equatorial mount, whose ``xel_*``/``el_*`` offsets are then
cross-declination (dH cos Dec) and declination; ``feed_angle_deg`` when the feed is turned;
``temp_<sensor>_xel_c`` and ``temp_<sensor>_el_c`` (and when they were read, ``temp_xel_t_s``,
``temp_el_t_s``) where the antenna has structure temperature sensors
(:func:`structure_columns`).
Optical pointing rows (a TV camera on stars) fill the radio-only columns with NaN.
"""

from __future__ import annotations

import io
import math
import os
import re
import warnings
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from astropy.io.misc import yaml as astropy_yaml
from astropy.table import Table
from astropy.time import Time

from controller.astro.frames import MOUNT_KINDS
from controller.errors import InputError, read_text_file
from controller.pointing.data import PointingData
from controller.pointing.equatorial import is_equatorial_term
from controller.pointing.legacy import W_TERMS, W_TERMS_KEY, names_w_terms, relabel_reconstructed
from controller.pointing.proxies import proxy_aux
from controller.pointing.terms import is_term_name
from controller.pointing.thermal import (
    STRUCTURE_SENSORS,
    sensor_aux,
    structure_column,
    structure_sensor_names,
    structure_time_column,
)

from .tablecheck import ColumnRule, check_range, first_repeat, unit_factor

__all__ = [
    "COLUMNS",
    "EXTRA_COLUMNS",
    "SENSOR_COLUMNS",
    "RecordingWriter",
    "ResumeMismatchError",
    "read_pointing_data",
    "read_recordings",
    "recorded_mount",
    "recording_columns",
    "recording_notes",
    "structure_columns",
    "table_pointing_data",
]


@dataclass(frozen=True)
class Column:
    """A recordings column: how it is written (``dtype``, ``unit``, ``description``) and
    what reading it accepts (``lo``..``hi`` in ``unit``; ``finite``: never NaN). A reader
    converts the unit a file declares into ``unit`` (:mod:`.tablecheck`)."""

    name: str
    dtype: str
    unit: str | None
    description: str
    lo: float | None = None
    hi: float | None = None
    finite: bool = False

    @property
    def rule(self) -> ColumnRule:
        return ColumnRule(self.name, self.unit, self.lo, self.hi, self.finite)


_POS = ("m4", "m1", "0", "p1", "p4")
#: the range of a pointing offset or correction (arcmin): half a turn
_OFFSET = (-10800.0, 10800.0)

COLUMNS: tuple[Column, ...] = (
    Column("scan", "int64", None, "scan number in the campaign"),
    Column("time", "str", None, "UTC at the middle of the scan (ISO)"),
    Column("t_s", "float64", "s", "seconds since the campaign epoch (antenna clock)",
           -1e9, 1e9, finite=True),
    Column("source", "str", None, "source name"),
    Column("polarization", "str", None, "XR, XL or AVG (mean of XR and XL powers)"),
    Column("az_deg", "float64", "deg", "observed azimuth of the source (N=0, E=90)",
           -360.0, 720.0, finite=True),
    Column("el_deg", "float64", "deg", "observed (refracted) elevation of the source",
           -90.0, 90.0, finite=True),
    Column("cmd_az_deg", "float64", "deg", "commanded encoder azimuth at the pattern centre"),
    Column("cmd_el_deg", "float64", "deg", "commanded encoder elevation at the pattern centre"),
    Column("model_xel_arcmin", "float64", "arcmin", "pointing model in use, cross-elevation",
           *_OFFSET, finite=True),
    Column("model_el_arcmin", "float64", "arcmin", "pointing model in use, elevation",
           *_OFFSET, finite=True),
    Column("applied_xel_arcmin", "float64", "arcmin", "controller's extra correction, xel",
           *_OFFSET, finite=True),
    Column("applied_el_arcmin", "float64", "arcmin", "controller's extra correction, el",
           *_OFFSET, finite=True),
    Column("xel_arcmin", "float64", "arcmin", "measured correction to apply, cross-elevation",
           *_OFFSET),
    Column("el_arcmin", "float64", "arcmin", "measured correction to apply, elevation",
           *_OFFSET),
    Column("xel_sigma_arcmin", "float64", "arcmin", "formal error of xel_arcmin"),
    Column("el_sigma_arcmin", "float64", "arcmin", "formal error of el_arcmin"),
    Column("xel_amp_k", "float64", "K", "amplitude of the azimuth scan"),
    Column("el_amp_k", "float64", "K", "amplitude of the elevation scan"),
    Column("xel_snr", "float64", None, "S/N of the azimuth scan, A / stddev(P)"),
    Column("el_snr", "float64", None, "S/N of the elevation scan, A / stddev(P)"),
    Column("xel_std_k", "float64", "K", "stddev of the total-power samples, azimuth scan"),
    Column("el_std_k", "float64", "K", "stddev of the total-power samples, elevation scan"),
    Column("xel_width_arcmin", "float64", "arcmin", "beam FWHM from the inner points, az scan"),
    Column("el_width_arcmin", "float64", "arcmin", "beam FWHM from the inner points, el scan"),
    Column("xel_flags", "int64", None, "quality flags of the azimuth scan (bit mask)"),
    Column("el_flags", "int64", None, "quality flags of the elevation scan (bit mask)"),
    Column("good", "bool", None, "both axes reduced without flags"),
    Column("air_temp_c", "float64", "deg_C", "air temperature (weather sensor)", -100.0, 100.0),
    Column("pressure_hpa", "float64", "hPa", "air pressure (weather sensor)", 0.0, 1200.0),
    Column("humidity", "float64", None, "relative humidity 0..1 (weather sensor)", 0.0, 1.0),
    Column("wind_m_s", "float64", "m / s", "wind speed (weather sensor)", 0.0, 100.0),
    Column("sun_el_deg", "float64", "deg", "elevation of the Sun", -90.0, 90.0),
    Column("slew_az", "int64", None, "direction of the last slew in azimuth (+1/-1/0)",
           -1, 1),
    Column("slew_el", "int64", None, "direction of the last slew in elevation (+1/-1/0)",
           -1, 1),
    *(Column(f"p_az_{p}", "float64", "K", f"total power, azimuth scan, position {p}")
      for p in _POS),
    *(Column(f"p_el_{p}", "float64", "K", f"total power, elevation scan, position {p}")
      for p in _POS),
)
COLUMN_NAMES = tuple(c.name for c in COLUMNS)

#: columns written only where they apply (see :func:`recording_columns`)
EXTRA_COLUMNS: dict[str, Column] = {c.name: c for c in (
    Column("ha_deg", "float64", "deg", "observed hour angle (equatorial mount; West positive)",
           -360.0, 360.0, finite=True),
    Column("dec_deg", "float64", "deg", "observed declination (equatorial mount)", -90.0, 90.0,
           finite=True),
    Column("feed_angle_deg", "float64", "deg", "feed (feed-box rotation) angle of the scan",
           -360.0, 360.0, finite=True),
)}


#: the range of a structure temperature (deg_C), as of the air's (``air_temp_c``)
_STRUCTURE_TEMP = (-100.0, 100.0)


def structure_columns(sensors: Sequence[str]) -> tuple[Column, ...]:
    """The columns of structure temperature sensors (optional: only recordings of an antenna
    with sensors have them; :mod:`controller.pointing.thermal`): each sensor read during the
    azimuth (cross-elevation) and the elevation half of the cross scan."""
    if not sensors:
        return ()
    halves = {"xel": "azimuth (cross-elevation)", "el": "elevation"}
    return (*(Column(structure_time_column(a), "float64", "s",
                     f"antenna clock when the structure temperatures were read during the "
                     f"{what} scan") for a, what in halves.items()),
            *(Column(structure_column(s, a), "float64", "deg_C",
                     f"structure temperature {s}, read during the {what} scan",
                     *_STRUCTURE_TEMP)
              for s in sensors for a, what in halves.items()))


#: one reading of a sensor per row (``temp_<sensor>_c``: a CSV of one's own measurements,
#: :mod:`controller.program.csvdata`), which the thermal terms read as both halves' reading
SENSOR_COLUMNS: dict[str, Column] = {c.name: c for c in (
    *structure_columns(tuple(STRUCTURE_SENSORS)),
    *(Column(f"temp_{s}_c", "float64", "deg_C", f"structure temperature {s}, one reading",
             *_STRUCTURE_TEMP) for s in STRUCTURE_SENSORS))}


def recording_columns(mount: str = "altaz", feed: bool = False,
                      sensors: Sequence[str] = ()) -> tuple[Column, ...]:
    """The columns of a campaign's recordings: the 1990 set, plus hour angle and declination
    on an equatorial mount, the feed angle when the feed is turned and the structure
    temperatures where the antenna has sensors."""
    extra: list[str] = []
    if mount == "equatorial":
        extra += ["ha_deg", "dec_deg"]
    if feed:
        extra.append("feed_angle_deg")
    return COLUMNS + tuple(EXTRA_COLUMNS[n] for n in extra) + structure_columns(sensors)


class ResumeMismatchError(InputError):
    """The regenerated rows differ from those on disk: the file is not this run's (one
    line, as any bad input: the scenario, seed or model changed since it was written)."""

    def __init__(self, path: str | Path, row: int, recorded: str):
        super().__init__(str(path), f"row {row}", recorded.strip(),
                         "differs from the same row of the resumed run: the scenario, seed or "
                         "model changed since this file was written",
                         "the file is kept as it is; run without --resume into a new directory")
        self.args = (path, row, recorded)  # rebuilt as type(err)(*err.args) (simpy)


def _format(value: Any, dtype: str) -> str:
    if dtype == "str":
        text = str(value)
        if not text or any(ch in text for ch in ' "\t#'):
            return '"' + text.replace('"', '""') + '"'
        return text
    if dtype == "bool":
        return "True" if value else "False"
    if dtype == "int64":
        return str(int(value))
    value = float(value)
    if math.isnan(value):
        return "nan"
    return repr(value)


def header_text(meta: dict[str, Any], columns: Sequence[Column] = COLUMNS) -> str:
    """The ECSV header (with the column-name line) for the given metadata."""
    table = Table(meta=meta)
    for col in columns:
        dtype = "U1" if col.dtype == "str" else col.dtype
        table.add_column(np.zeros(0, dtype=dtype), name=col.name)
        table[col.name].unit = col.unit
        table[col.name].description = col.description
    buf = io.StringIO()
    table.write(buf, format="ascii.ecsv")
    text = buf.getvalue()
    # astropy writes an empty table's string columns with the dtype it sees; declare str
    return text


class RecordingWriter:
    """Appends rows to ``recordings.ecsv``; with ``resume`` verifies and skips existing rows."""

    def __init__(self, path: str | Path, meta: dict[str, Any], resume: bool = False,
                 columns: Sequence[Column] = COLUMNS):
        self.path = Path(path)
        self.columns = tuple(columns)
        self.header = header_text(meta, self.columns)
        self._existing: list[str] = []
        self._cursor = 0
        self.rows_written = 0
        if resume and self.path.exists():
            text = self.path.read_text(encoding="utf-8")
            complete = text[: text.rfind("\n") + 1]
            if not complete.startswith(self.header):
                raise InputError(str(self.path), "header", "(recorded header)",
                                 "was not written by this scenario, seed and model",
                                 "run without --resume into a new directory")
            self._existing = complete[len(self.header):].splitlines(keepends=True)
            # keep only the complete part on disk; a torn last line is discarded
            with open(self.path, "r+b") as fh:
                fh.truncate(len(complete.encode("utf-8")))
            self._fd = os.open(self.path, os.O_WRONLY | os.O_APPEND)
        else:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
            os.write(self._fd, self.header.encode("utf-8"))

    @property
    def existing_rows(self) -> int:
        return len(self._existing)

    def format_rows(self, rows: Sequence[dict[str, Any]]) -> list[str]:
        lines = []
        for row in rows:
            missing = [c.name for c in self.columns if c.name not in row]
            if missing:
                raise KeyError(f"recording row lacks column(s) {missing}")
            lines.append(" ".join(_format(row[c.name], c.dtype) for c in self.columns) + "\n")
        return lines

    def write_scan(self, rows: Sequence[dict[str, Any]]) -> None:
        """Append one scan's rows with a single write (or verify them when replaying)."""
        lines = self.format_rows(rows)
        fresh = []
        for line in lines:
            if self._cursor < len(self._existing):
                if self._existing[self._cursor] != line:
                    raise ResumeMismatchError(self.path, self._cursor + 1,
                                              self._existing[self._cursor])
                self._cursor += 1
            else:
                fresh.append(line)
        if fresh:
            try:
                os.write(self._fd, "".join(fresh).encode("utf-8"))
            except OSError as err:  # as one line: simpy re-raises an OSError without its file
                raise InputError(str(self.path), "rows", len(fresh),
                                 f"cannot be written: {err.strerror or err}",
                                 "the scans written before them are kept") from None
            self.rows_written += len(fresh)

    def check_replayed(self) -> None:
        """After the whole campaign: every row found on resuming was one the run wrote again
        (the run is deterministic); a row beyond them was not written by this run (appended
        by hand or by another program) and is an InputError naming it. The file is kept."""
        if self._cursor < len(self._existing):
            raise InputError(str(self.path), f"row {self._cursor + 1}",
                             self._existing[self._cursor].strip(),
                             f"was not written by this run: the campaign ends after row "
                             f"{self._cursor}, the file holds {len(self._existing)} rows",
                             "the file is kept as it is; remove the rows after row "
                             f"{self._cursor}, or run without --resume into a new directory")

    def discard(self) -> None:
        """Close and remove the file: for a run that failed before its first scan."""
        self.close()
        self.path.unlink(missing_ok=True)

    def close(self) -> None:
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None

    def __enter__(self) -> RecordingWriter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


#: columns without which recordings cannot be used: the total pointing error is measured +
#: model in use + applied correction, so a missing part would silently count as zero
REQUIRED = ("polarization", "az_deg", "el_deg", "xel_arcmin", "el_arcmin", "model_xel_arcmin",
            "model_el_arcmin", "applied_xel_arcmin", "applied_el_arcmin")
#: what is left out without an optional column (named in a note, never silently)
OPTIONAL = {
    "good": "every row with finite offsets is used",
    "scan": "rows are matched to their scan by time",
    "source": "the tests by source are left out",
    "sun_el_deg": "the tests against the Sun's elevation are left out",
    "air_temp_c": "the tests against air temperature are left out",
    "slew_az": "the tests of the last slew's direction are left out",
    "xel_width_arcmin": "the tests of the measured beam width are left out",
}
#: the optional columns each reader of recordings uses
USES = {"fit": ("good",), "diagnose": tuple(OPTIONAL)}
_KNOWN = {c.name: c for c in (*COLUMNS, *EXTRA_COLUMNS.values(), *SENSOR_COLUMNS.values())}


def _data_lines(text: str) -> list[int]:
    """The 1-based line number of each data row of ECSV ``text`` (after the header and the
    line of column names; blank lines are not rows)."""
    lines = text.split("\n")
    numbers = []
    names_seen = False
    for i, line in enumerate(lines, start=1):
        if not line.strip() or line.startswith("#"):
            continue
        if names_seen:
            numbers.append(i)
        names_seen = True
    return numbers


#: the ECSV datatypes :func:`_fast_table` reads (others go to astropy's reader)
_FAST_TYPES = ("int64", "int32", "int16", "int8", "uint64", "uint32", "uint16", "uint8",
               "float64", "float32")


def _lines(text: str, start: int, end: int):
    """The lines of ``text[start:end]`` one by one (no copy of the whole); ValueError at an
    empty line (a blank line: a row's line number is then not its count)."""
    while start < end:
        stop = text.index("\n", start, end)
        if stop == start:
            raise ValueError(f"a blank line at offset {start}")
        yield text[start:stop]
        start = stop + 1


def _yaml_header(lines: Iterable[str]) -> dict:
    """The YAML header of an ECSV file from its comment lines after ``# %ECSV``: by PyYAML's
    safe loader where it can (astropy's loader is that loader with tags added, for units,
    times, arrays, coordinates, tuples: the same objects from any document both read),
    else by astropy's, which also reports a malformed header (importing it imports
    astropy.coordinates, 0.05 s that nothing else in diagnose needs)."""
    text = "\n".join(line[2:] if line.startswith("# ") else line[1:] for line in lines)
    _refuse_aliases(text, None)
    try:
        return yaml.load(text, Loader=yaml.SafeLoader)
    except yaml.YAMLError:
        return astropy_yaml.load(text)


#: the largest header the readers take (bytes): antsim writes about 10 kB
MAX_HEADER_BYTES = 4 << 20


def _refuse_aliases(header: str, where: str | None) -> None:
    """InputError for a YAML anchor or alias (``&a``, ``*a``) in a header: a recordings
    header holds plain data, and an alias makes a small file a structure of gigabytes (an
    "alias bomb") once expanded. ``where``: the file (its line is named), or None."""
    if "&" not in header and "*" not in header:
        return
    try:
        for event in yaml.parse(header, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader)):
            if isinstance(event, yaml.AliasEvent):
                token = f"*{event.anchor}"
            elif getattr(event, "anchor", None):
                token = f"&{event.anchor}"
            else:
                continue
            line = event.start_mark.line + 2  # the header's first line is the file's second
            raise InputError(f"{where}:{line}" if where else "ECSV header", "header", token,
                             "is a YAML anchor or alias: a recordings header holds plain "
                             "data, never a reference expanded on reading")
    except yaml.YAMLError:
        return  # malformed: the reader says what is wrong


def _header_text(text: str, where: str) -> str:
    """The YAML of an ECSV file's header (its ``#`` lines after ``# %ECSV``), bounded and
    without anchors or aliases; one InputError line otherwise."""
    end = 0
    while text.startswith("#", end):
        nl = text.find("\n", end)
        end = len(text) if nl < 0 else nl + 1
        if end > MAX_HEADER_BYTES:
            raise InputError(where, "header", f"{end} bytes so far",
                             f"is larger than {MAX_HEADER_BYTES >> 20} MiB: not a recordings "
                             "header")
    lines = text[:end].splitlines()[1:]
    header = "\n".join(line[2:] if line.startswith("# ") else line[1:] for line in lines)
    _refuse_aliases(header, where)
    _refuse_repeated_keys(header, where)
    return header


def _refuse_repeated_keys(header: str, where: str) -> None:
    """InputError for a key given twice in one mapping of the header (``site`` twice in
    ``meta``, ``unit`` twice in a column): YAML readers keep one of the two silently."""
    try:
        root = yaml.compose(header, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
    except yaml.YAMLError:
        return  # malformed: the reader says what is wrong
    stack = [root] if root is not None else []
    while stack:
        node = stack.pop()
        if isinstance(node, yaml.MappingNode):
            pairs = node.value
        elif isinstance(node, yaml.SequenceNode) and node.tag.endswith(":omap"):
            pairs = [p for item in node.value if isinstance(item, yaml.MappingNode)
                     for p in item.value]  # an ordered map: one pair a list item
        else:
            if isinstance(node, yaml.SequenceNode):
                stack.extend(node.value)
            continue
        seen: dict[str, int] = {}
        for key, value in pairs:
            if isinstance(key, yaml.ScalarNode):
                line = key.start_mark.line + 2  # the header's first line is the file's second
                if key.value in seen:
                    raise InputError(f"{where}:{line}", "header", key.value,
                                     f"is a key given twice (first on line {seen[key.value]}):"
                                     " readers would keep one of them silently")
                seen[key.value] = line
            stack.append(value)


def _fast_table(text: str, end: int):
    """(astropy Table, each data row's line number) from ECSV ``text[:end]`` in the plain
    layout (numbers, booleans and quoted text, one delimiter, no blank lines), parsed by
    numpy's C reader a line at a time: astropy's holds every cell as a Python string
    (200,000 recordings: 590 MB and 3.5 s). None for anything else, which astropy's reader
    then reads."""
    try:
        head_end = 0
        while text.startswith("#", head_end):
            head_end = text.index("\n", head_end) + 1
        header = _yaml_header(text[:head_end].splitlines()[1:])
        columns = header["datatype"]
        delimiter = header.get("delimiter", " ")
        names_end = text.index("\n", head_end)
        if text[head_end:names_end].split(delimiter) != [c["name"] for c in columns]:
            return None
        dtype = []
        for c in columns:
            kind = c.get("datatype")
            if "subtype" in c or kind not in (*_FAST_TYPES, "string", "bool"):
                return None
            dtype.append((c["name"], object if kind in ("string", "bool") else kind))
        # blank lines (line numbers unknown) stop _lines: astropy's reader, as for a
        # malformed row (text.find("\n\n") took 40-75 ms of 44 MB)
        if names_end + 1 >= end:  # no rows (numpy would warn on stderr): astropy's reader
            return None
        with warnings.catch_warnings():
            # NumPy < 2 parses "1.5" in an integer column as 1 with this warning (2.x
            # refuses it): refused on every version, astropy's reader then decides
            warnings.simplefilter("error", DeprecationWarning)
            values = np.loadtxt(_lines(text, names_end + 1, end), dtype=dtype,
                                delimiter=delimiter, quotechar='"', comments=None, ndmin=1)
        table = Table(meta=dict(header.get("meta") or {}))  # an !!omap: (key, value) pairs
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # an unknown unit is refused later, by name
            for c in columns:
                column = values[c["name"]]
                if c["datatype"] == "bool":  # read as text: True and False only
                    truth = column == "True"
                    if not np.all(truth | (column == "False")):
                        return None
                    column = truth
                table[c["name"]] = column.astype(str) if column.dtype == object else column
                table[c["name"]].unit = c.get("unit")
                table[c["name"]].description = c.get("description")
    except Exception:  # not the plain layout (or malformed): astropy's reader decides
        return None
    first = text.count("\n", 0, names_end) + 2  # the line after the column names, 1-based
    return table, range(first, first + len(table))


def recorded_mount(path: str | Path) -> str | None:
    """The mount (``altaz``, ``equatorial``) ECSV recordings were made on, from their header
    alone (a quick look before reading them); None for a file that is not ECSV or whose
    header does not parse (reading it then says what is wrong)."""
    try:
        with open(path, encoding="utf-8") as fh:
            header = []
            for line in fh:
                if not line.startswith("#"):
                    break
                header.append(line)
        if not header or not header[0].lstrip("\ufeff").startswith("# %ECSV"):
            return None
        meta = dict(_yaml_header(line.rstrip("\n") for line in header[1:]).get("meta") or {})
    except Exception:  # not readable here: read_recordings names the problem
        return None
    return str(meta.get("mount", "altaz"))


def read_recordings(path: str | Path, purpose: str = "fit", text: str | None = None):
    """Read a recordings file into an astropy Table, ignoring a torn last line; ``text``:
    the file's, when the caller has read it (:func:`read_text_file`: 44 MB at 200,000 scans).

    Every column this package knows is converted from the unit the file declares into the
    unit of its name (``az_deg`` in deg, ``el_arcmin`` in arcmin, ...), or refused when the
    units are not convertible; values are checked against the column's range; a scan and
    polarization recorded twice is refused; the columns of :data:`REQUIRED` (and ``t_s`` for
    ``purpose="diagnose"``) must be there. Masked (missing) numbers become NaN. Every refusal
    is one InputError line naming ``file:line``, the column and the value.
    """
    path = Path(path)
    where = str(path)
    if text is None:
        text = read_text_file(path)
    if not text.startswith("# %ECSV"):
        raise InputError(where, "format", text[:20], "not an ECSV file (no '# %ECSV' line)")
    _header_text(text, where)  # bounded, no YAML references: before any parser expands one
    end = text.rfind("\n") + 1  # a torn last line is left out
    parsed = _fast_table(text, end)
    if parsed is not None:
        table, lines = parsed
    else:  # anything but the plain layout antsim writes: astropy's reader, and its errors
        text = text[:end]
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # an unknown unit is refused below, by name
                table = Table.read(text, format="ascii.ecsv")
        except Exception as err:  # astropy raises many types for malformed ECSV
            message = " ".join(str(err).split())[:200]
            # a value its column's declared datatype cannot hold: the column and the value
            bad = re.match(r"column '([^']+)' failed to convert: .*?'([^']*)'$", message)
            if bad:
                raise InputError(where, bad[1], bad[2], "is not of the column's declared "
                                 f"datatype (astropy: {message})") from None
            raise InputError(where, "ECSV", type(err).__name__,
                             f"cannot be parsed: {message}") from None
        lines = _data_lines(text)
        if len(lines) != len(table):  # astropy read rows we did not count: no line numbers
            lines = list(range(1, len(table) + 1))
    _check_meta(table.meta, where)
    need = REQUIRED + (("t_s",) if purpose == "diagnose" else ())
    if table.meta.get("mount") == "equatorial":
        need += ("ha_deg", "dec_deg")
    missing = [c for c in need if c not in table.colnames]
    if missing:
        raise InputError(where, "columns", " ".join(missing),
                         "required column(s) missing", "docs/inputs.md lists the columns")
    for name in table.colnames:
        if name in _KNOWN:
            _check_column(table, _KNOWN[name], where, lines)
    if "good" in table.colnames:  # a row marked good has both offsets (NaN: not measured)
        good = np.asarray(table["good"], dtype=bool)
        for name in ("xel_arcmin", "el_arcmin"):
            rule = _KNOWN[name].rule
            check_range(np.asarray(table[name], dtype=float),
                        ColumnRule(name, rule.unit, rule.lo, rule.hi, finite=True), where,
                        lines, rows=good)
    polarization = np.asarray(table["polarization"]).astype(str)
    average = np.char.upper(np.char.strip(polarization)) == "AVG"
    variant = np.flatnonzero(average & (polarization != "AVG"))
    if variant.size:  # read as another channel, these rows would silently drop out
        i = int(variant[0])
        raise InputError(f"{where}:{lines[i]}", "polarization", polarization[i],
                         f"is the polarization average written otherwise ({variant.size} "
                         f"of {int(average.sum())} average rows): the readers take the "
                         "rows written 'AVG'", "write it AVG (case matters)")
    keys = [np.asarray(table["scan"] if "scan" in table.colnames else table["t_s"]
                       if "t_s" in table.colnames else table["az_deg"]), polarization]
    repeat = first_repeat(keys)
    if repeat is not None:
        first, row = repeat
        key = "scan" if "scan" in table.colnames else "t_s" if "t_s" in table.colnames \
            else "az_deg"
        raise InputError(f"{where}:{lines[row]}", f"{key}, polarization",
                         f"{table[key][row]} {table['polarization'][row]}",
                         f"repeats line {lines[first]}", "record each scan and polarization once")
    if "scan" in table.colnames and "t_s" in table.colnames:  # a scan copied under another
        repeat = first_repeat([np.asarray(table["t_s"], dtype=float), polarization])
        if repeat is not None:
            first, row = repeat
            raise InputError(f"{where}:{lines[row]}", "t_s, polarization",
                             f"{table['t_s'][row]} {table['polarization'][row]}",
                             f"repeats line {lines[first]} (scan {table['scan'][first]}) "
                             f"under scan {table['scan'][row]}: one measurement twice",
                             "record each scan once")
    model = table.meta.get("model")
    if isinstance(model, dict) and isinstance(model.get("terms_arcsec"), dict) \
            and names_w_terms(model["terms_arcsec"]) and W_TERMS_KEY not in model:
        # written before antsim followed the 1990 report's W1..W10: the model in use is
        # renamed (the offsets recorded per row never depended on the names)
        model["terms_arcsec"] = relabel_reconstructed(model["terms_arcsec"], f"{path}")
        model[W_TERMS_KEY] = W_TERMS
    return table


def recording_notes(table, purpose: str = "fit") -> list[str]:
    """What the reader of ``purpose`` leaves out for want of an optional column."""
    return [f"no column {name}: {OPTIONAL[name]}" for name in USES.get(purpose, ())
            if name not in table.colnames]


def _check_column(table, column: Column, where: str, lines: list[int]) -> None:
    """Convert ``column`` to its unit in place and check its values (see read_recordings)."""
    col = table[column.name]
    if column.dtype == "str":
        return
    kind = col.dtype.kind
    if kind not in "biuf":
        raise InputError(f"{where}:{lines[0]}" if len(col) else where, column.name,
                         col[0] if len(col) else "", f"must be {column.dtype} values; the "
                         f"header declares {col.dtype.name if kind != 'U' else 'text'}")
    given = None if col.unit is None else col.unit.to_string()
    convert = unit_factor(given, column.rule, where, named=True)  # az_deg: deg
    mask = np.asarray(getattr(col, "mask", np.zeros(len(col), bool)), dtype=bool)
    if column.dtype in ("int64", "bool"):
        if mask.any():
            i = int(np.flatnonzero(mask)[0])
            raise InputError(f"{where}:{lines[i]}", column.name, "<missing>",
                             "has no value where one is needed")
        if column.dtype == "int64" and column.lo is not None:
            check_range(np.asarray(col, dtype=float), column.rule, where, lines)
        return
    shown = np.where(mask, np.nan, np.asarray(col, dtype=float))
    values = convert(shown)
    check_range(values, column.rule, where, lines, shown=shown)
    table.replace_column(column.name, values)
    if column.unit is not None:
        table[column.name].unit = column.unit


def _number(value) -> bool:
    return not isinstance(value, bool) and isinstance(value, int | float)


def _check_model_meta(model, mount: str, where: str) -> None:
    """``meta.model``: the model in use, a mapping whose ``terms_arcsec`` maps known term
    names to finite coefficients (arcsec); a term the readers do not know or a value that is
    no number would be left out of the model in use silently."""
    if not isinstance(model, dict):
        raise InputError(where, "meta.model", model, "must be a mapping (name, terms_arcsec)")
    terms = model.get("terms_arcsec", {})
    if not isinstance(terms, dict):
        raise InputError(where, "meta.model.terms_arcsec", terms,
                         "must be a mapping of term names to arcsec")
    known = is_equatorial_term if mount == "equatorial" else is_term_name
    for name, value in terms.items():
        if not known(str(name)):
            raise InputError(where, f"meta.model.terms_arcsec.{name}", value,
                             "is not a pointing term antsim knows")
        if not _number(value) or not math.isfinite(value) or abs(value) > 648000.0:
            raise InputError(where, f"meta.model.terms_arcsec.{name}", value,
                             "must be a finite number within +-648000 arcsec")


def _check_meta(meta, where: str) -> None:
    """The metadata readers use: the site (numbers within range), mount, epoch, the model in
    use and the structure sensors' response time."""
    site = meta.get("site")
    if site is not None:
        if not isinstance(site, dict):
            raise InputError(where, "meta.site", site, "must be a mapping (latitude_deg, ...)")
        for key, (lo, hi) in (("latitude_deg", (-90, 90)), ("longitude_deg", (-180, 360)),
                              ("height_m", (-500, 10000))):
            value = site.get(key)
            if value is None:
                continue
            if isinstance(value, bool) or not isinstance(value, int | float) \
                    or not lo <= value <= hi:
                raise InputError(where, f"meta.site.{key}", value,
                                 f"must be a number within {lo}..{hi}")
    mount = meta.get("mount", "altaz")
    if mount not in MOUNT_KINDS:
        raise InputError(where, "meta.mount", mount,
                         f"is not a mount antsim knows ({', '.join(MOUNT_KINDS)})")
    if mount == "equatorial" and not isinstance((site or {}).get("latitude_deg"), int | float):
        raise InputError(where, "meta.site.latitude_deg", "<missing>",
                         "an equatorial mount's recordings need the site latitude")
    if meta.get("model") is not None:
        _check_model_meta(meta["model"], mount, where)
    sensors = meta.get("structure_sensors")
    if sensors is not None:
        if not isinstance(sensors, dict):
            raise InputError(where, "meta.structure_sensors", sensors,
                             "must be a mapping (lag_s, ...)")
        lag = sensors.get("lag_s", 0.0)
        if not _number(lag) or not 0.0 <= lag <= 1e6:
            raise InputError(where, "meta.structure_sensors.lag_s", lag,
                             "must be a number of seconds within 0..1e+06")
    for key in ("duration_s", "beam_hpbw_arcmin"):
        value = meta.get(key)
        if value is not None and (isinstance(value, bool) or not isinstance(value, int | float)
                                  or not 0 < value < 1e9):
            raise InputError(where, f"meta.{key}", value, "must be a positive number")
    epoch = meta.get("epoch_utc")
    if epoch is not None:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # ERFA's "dubious year": refused below
                year = Time(str(epoch), scale="utc").ymdhms["year"]
        except ValueError:
            raise InputError(where, "meta.epoch_utc", epoch, "not an ISO UTC time") from None
        if not 1900 <= year <= 2200:
            raise InputError(where, "meta.epoch_utc", epoch, "year outside 1900..2200")


def total_errors_arcsec(table) -> tuple[np.ndarray, np.ndarray]:
    """Total pointing error (indicated - true), xel and el in arcsec, per row:
    measured correction + model in use + applied correction."""
    xel = (np.asarray(table["xel_arcmin"], dtype=float)
           + np.asarray(table["model_xel_arcmin"], dtype=float)
           + np.asarray(table["applied_xel_arcmin"], dtype=float)) * 60.0
    el = (np.asarray(table["el_arcmin"], dtype=float)
          + np.asarray(table["model_el_arcmin"], dtype=float)
          + np.asarray(table["applied_el_arcmin"], dtype=float)) * 60.0
    return xel, el


def read_pointing_data(path: str | Path, polarization: str = "AVG", good_only: bool = True,
                       proxies: bool = False):
    """Recordings as :class:`controller.pointing.data.PointingData` of total pointing errors,
    with the structure temperatures where the recordings have them (corrected for the
    sensors' response time in the metadata) and, with ``proxies``, the proxies of
    :mod:`controller.pointing.proxies` (they need the metadata's site and epoch)."""
    return table_pointing_data(read_recordings(path), str(path), polarization, good_only,
                               proxies)


def table_pointing_data(table, where: str, polarization: str = "AVG", good_only: bool = True,
                        proxies: bool = False, with_times: bool = False):
    """:func:`read_pointing_data` of a table :func:`read_recordings` returned; with
    ``with_times`` the observations carry their times (the honest sigma's time blocks)."""
    mask = np.asarray(table["polarization"]) == polarization
    if good_only and "good" in table.colnames:
        mask &= np.asarray(table["good"], dtype=bool)
    elif good_only:  # no flags: the rows that have both offsets
        mask &= np.isfinite(np.asarray(table["xel_arcmin"], dtype=float))
        mask &= np.isfinite(np.asarray(table["el_arcmin"], dtype=float))
    sel = table[mask]
    if len(sel) == 0:
        raise InputError(where, "polarization", polarization,
                         "no usable rows for this polarization")
    xel, el = total_errors_arcsec(sel)
    lon, lat = ("ha_deg", "dec_deg") if "ha_deg" in sel.colnames else ("az_deg", "el_deg")
    sensors = structure_sensor_names(sel.colnames)
    meta = table.meta
    lag = float((meta.get("structure_sensors") or {}).get("lag_s", 0.0))
    aux = sensor_aux({c: np.asarray(sel[c]) for c in sel.colnames}, sensors, lag) \
        if sensors else {}
    az = np.radians(np.asarray(sel[lon], dtype=float))
    el_rad = np.radians(np.asarray(sel[lat], dtype=float))
    if proxies:
        if not isinstance(meta.get("site"), dict) or "epoch_utc" not in meta \
                or "t_s" not in sel.colnames:
            raise InputError(where, "metadata", "site, epoch_utc",
                             "the proxies of thermal terms need the site, the epoch and the "
                             "times of the recordings")
        air = np.asarray(sel["air_temp_c"], dtype=float) if "air_temp_c" in sel.colnames \
            else None
        aux |= proxy_aux(np.asarray(sel["t_s"], dtype=float), az, el_rad, air, meta["site"],
                         meta["epoch_utc"])
    return PointingData(
        az_rad=az,
        el_rad=el_rad,
        xel_arcsec=xel,
        el_arcsec=el,
        feed_rad=(np.radians(np.asarray(sel["feed_angle_deg"], dtype=float))
                  if "feed_angle_deg" in sel.colnames else None),
        aux=aux or None,
        t_s=(np.asarray(sel["t_s"], dtype=float) if with_times and "t_s" in sel.colnames
             else None),
    )

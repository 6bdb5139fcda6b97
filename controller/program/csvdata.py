"""Your own pointing measurements as plain CSV (docs/inputs.md).

One row per measurement: the time (optional), where the source was (azimuth North-based and
elevation), and the measured pointing offsets; optionally the source, the weather and
structure temperatures. ``#`` lines before the column names may hold settings ``key: value``
(the same settings can be given on the command line, ``--csv "sign: ..."``)::

    # sign: indicated-minus-true
    # latitude_deg: 38.43
    time,az_deg,el_deg,d_xel_arcsec,d_el_arcsec,source,air_temp_c
    1990-02-08T17:03:10,52.31,20.14,-12.5,88.0,3C84,11.2

Columns are known by name, with the unit as a suffix (``az_deg``, ``az_rad``, ``d_el_arcmin``,
``air_temp_k``) or, for a bare name, from the ``units`` setting (``units: az=deg el=deg
d_xel=arcsec d_el=arcsec``): :data:`CSV_COLUMNS` lists them. The offsets are the total
pointing error the model must explain, ``d_xel`` (= dA cos E) or ``d_az`` (dA, converted with
the row's elevation) and ``d_el``, with the sign the ``sign`` setting states (required: no
guess): ``indicated-minus-true`` (the 1990 report's dA, dE and antsim's recordings) or
``true-minus-indicated`` (TPOINT's correction, obs - raw). Every bad value is one
:class:`~controller.errors.InputError` line naming ``file:line``, the column and the value.

The result is a table in the recordings' vocabulary (:func:`read_csv`), read by ``antsim fit``
and ``antsim diagnose`` as recordings are.
"""

from __future__ import annotations

import csv
import re
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from astropy.time import Time

from controller.errors import InputError, read_text_file
from controller.filekind import looks_like_csv
from controller.pointing.data import PointingData
from controller.pointing.thermal import STRUCTURE_SENSORS, sensor_aux, structure_sensor_names

from .tablecheck import ColumnRule, check_range, first_repeat, unit_factor

__all__ = ["CSV_COLUMNS", "SIGNS", "CsvData", "looks_like_csv", "parse_settings",
           "pointing_data", "read_csv"]

#: the ``sign`` setting: factor turning the file's offsets into "indicated minus true"
SIGNS = {"indicated-minus-true": 1.0, "true-minus-indicated": -1.0}
#: unit suffixes of column names, as astropy unit strings
UNIT_SUFFIXES = {"deg": "deg", "rad": "rad", "arcmin": "arcmin", "arcsec": "arcsec",
                 "c": "deg_C", "k": "K", "hpa": "hPa", "mbar": "mbar", "pa": "Pa",
                 "m_s": "m / s", "km_h": "km / h", "percent": "percent", "s": "s"}


@dataclass(frozen=True)
class CsvColumn:
    """A column the CSV reader knows: held as recordings column ``target`` in ``rule``'s
    unit and range; ``text`` for a string column."""

    target: str
    rule: ColumnRule | None = None
    required: bool = False
    text: bool = False


_OFFSET = (-10800.0, 10800.0)
#: base name -> what it is (table-driven: a new optional column is one more line)
CSV_COLUMNS: dict[str, CsvColumn] = {
    "time": CsvColumn("time", text=True),
    "az": CsvColumn("az_deg", ColumnRule("az", "deg", -360.0, 720.0, finite=True), True),
    "el": CsvColumn("el_deg", ColumnRule("el", "deg", -90.0, 90.0, finite=True), True),
    "d_xel": CsvColumn("xel_arcmin", ColumnRule("d_xel", "arcmin", *_OFFSET, finite=True)),
    "d_az": CsvColumn("d_az_arcmin", ColumnRule("d_az", "arcmin", -21600.0, 21600.0,
                                                finite=True)),
    "d_el": CsvColumn("el_arcmin", ColumnRule("d_el", "arcmin", *_OFFSET, finite=True), True),
    "source": CsvColumn("source", text=True),
    "air_temp": CsvColumn("air_temp_c", ColumnRule("air_temp", "deg_C", -100.0, 100.0)),
    "pressure": CsvColumn("pressure_hpa", ColumnRule("pressure", "hPa", 0.0, 1200.0)),
    "humidity": CsvColumn("humidity", ColumnRule("humidity", None, 0.0, 1.0)),
    "wind": CsvColumn("wind_m_s", ColumnRule("wind", "m / s", 0.0, 100.0)),
}
#: structure temperatures: ``temp_<sensor>`` (a temperature unit) for a sensor of the
#: recordings' (:data:`controller.pointing.thermal.STRUCTURE_SENSORS`), kept as
#: ``temp_<sensor>_c``, the recordings' one-reading column, which thermal terms read; any
#: other name is refused (a misspelt sensor silently left out would be a wrong answer)
_TEMPS = frozenset(f"temp_{s}" for s in STRUCTURE_SENSORS)
_SETTINGS = ("sign", "units", "latitude_deg", "longitude_deg", "height_m")


@dataclass
class CsvData:
    """A CSV file read into recordings columns (canonical units) and metadata."""

    columns: dict[str, np.ndarray]
    meta: dict[str, Any]
    path: str
    lines: list[int] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    @property
    def colnames(self) -> list[str]:
        return list(self.columns)

    def __len__(self) -> int:
        return int(self.columns["az_deg"].size)


def parse_settings(lines: Sequence[str], where: str) -> dict[str, str]:
    """Settings ``key: value`` (or ``key = value``) from header lines or ``--csv`` options."""
    out: dict[str, str] = {}
    for line in lines:
        m = re.match(r"^\s*([A-Za-z_]+)\s*[:=]\s*(.*?)\s*$", line)
        if not m:
            raise InputError(where, "setting", line.strip(), "is not 'key: value'",
                             f"settings: {', '.join(_SETTINGS)}")
        key, value = m.group(1).lower(), m.group(2)
        if key not in _SETTINGS:
            raise InputError(where, "setting", key, "unknown setting",
                             f"settings: {', '.join(_SETTINGS)}")
        if key in out and out[key] != value:
            raise InputError(where, key, value, f"contradicts {key}: {out[key]}")
        out[key] = value
    return out


def _suffix(unit: str | None) -> str:
    """The column-name suffix of an astropy unit string (``arcmin`` for ``"arcmin"``)."""
    return next((k for k, v in UNIT_SUFFIXES.items() if v == unit), "deg")


def _known(base: str) -> bool:
    return (base in CSV_COLUMNS and not CSV_COLUMNS[base].text) or base in _TEMPS


def _split_name(name: str, units: Mapping[str, str], where: str) -> tuple[str, str | None]:
    """(base name, astropy unit or None) of a column heading: a known name with a unit
    suffix, or a bare known name whose unit (if any) the ``units`` setting gives."""
    low = name.strip().lower()
    for suffix, unit in sorted(UNIT_SUFFIXES.items(), key=lambda kv: -len(kv[0])):
        base = low[: -len(suffix) - 1]
        if low.endswith("_" + suffix) and _known(base):
            if base in units:
                raise InputError(where, name, units[base],
                                 "has a unit in its name and in the units setting")
            return base, unit
    if low in CSV_COLUMNS or low in _TEMPS:
        return low, units.get(low)
    raise InputError(where, "column", name, "unknown column",
                     "known: " + ", ".join(CSV_COLUMNS) + ", temp_<sensor> with <sensor> "
                     "one of " + " ".join(STRUCTURE_SENSORS) + ", each with a unit suffix "
                     "such as _deg or _arcsec (docs/inputs.md)")


def _units_setting(text: str, where: str) -> dict[str, str]:
    out = {}
    for item in re.split(r"[\s,]+", text.strip()):
        if not item:
            continue
        name, _, unit = item.partition("=")
        if not unit:
            raise InputError(where, "units", item, "expected name=unit, e.g. d_el=arcsec")
        key = name.strip().lower()
        if key in out:
            raise InputError(where, "units", item, f"gives the unit of {key} twice")
        out[key] = UNIT_SUFFIXES.get(unit.strip().lower(), unit.strip())
    return out


def read_csv(path: str | Path, options: Sequence[str] = (), text: str | None = None
             ) -> CsvData:
    """Read CSV pointing data (see the module); ``options``: settings from the command line;
    ``text``: the file's, when the caller has read it (:func:`read_text_file`)."""
    where = str(path)
    if text is None:
        text = read_text_file(path)
    raw_lines = text.splitlines()
    header_settings: list[str] = []
    names_at = None
    for i, line in enumerate(raw_lines):
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith("#"):
            body = stripped.lstrip("#").strip()
            if re.match(r"^[A-Za-z_]+\s*:", body) and body.split(":")[0].strip().lower() \
                    in _SETTINGS:
                header_settings.append(body)
            continue
        names_at = i
        break
    if names_at is None:
        raise InputError(where, "columns", "", "no line of column names",
                         "the first line that is not a # comment names the columns")
    settings = parse_settings(header_settings, where)
    for key, value in parse_settings(options, "command line --csv").items():
        if key in settings and settings[key] != value:
            raise InputError("command line", f"--csv {key}", value,
                             f"contradicts the file's {key}: {settings[key]} ({where})")
        settings[key] = value
    sign_text = settings.get("sign")
    if sign_text is None:
        raise InputError(where, "sign", "<missing>", "the offsets' sign convention is not stated",
                         "add a line '# sign: indicated-minus-true' (or true-minus-indicated, "
                         "TPOINT's), or --csv 'sign: ...'")
    if sign_text.lower() not in SIGNS:
        raise InputError(where, "sign", sign_text, f"must be one of {', '.join(SIGNS)}")
    sign = SIGNS[sign_text.lower()]
    units = _units_setting(settings.get("units", ""), where)
    meta = _site_meta(settings, where)

    names_line = names_at + 1
    headings = next(csv.reader([raw_lines[names_at]]))
    bases = [_split_name(h, units, f"{where}:{names_line}") for h in headings]
    seen: dict[str, int] = {}
    for j, (base, _) in enumerate(bases):
        if base in seen:
            raise InputError(f"{where}:{names_line}", "column", headings[j],
                             f"repeats column {seen[base] + 1} ({headings[seen[base]]})")
        seen[base] = j
    missing = [n for n, c in CSV_COLUMNS.items() if c.required and n not in seen]
    if "d_xel" not in seen and "d_az" not in seen:
        missing.insert(2, "d_xel (or d_az)")
    if "d_xel" in seen and "d_az" in seen:
        raise InputError(f"{where}:{names_line}", "column", "d_az",
                         "give d_xel or d_az, not both")
    if missing:
        raise InputError(f"{where}:{names_line}", "columns", " ".join(missing),
                         "required column(s) missing", "docs/inputs.md lists the columns")

    lines = [k for k, line in enumerate(raw_lines[names_at + 1:], start=names_line + 1)
             if line.strip() and not line.lstrip().startswith("#")]
    rows = [[f.strip() for f in fields]
            for fields in csv.reader(raw_lines[k - 1] for k in lines)]
    for k, fields in zip(lines, rows, strict=True):
        if len(fields) != len(headings):
            raise InputError(f"{where}:{k}", "row", raw_lines[k - 1].strip(),
                             f"has {len(fields)} fields; the column names line has "
                             f"{len(headings)}")
    if not rows:
        raise InputError(where, "rows", 0, "the file has column names but no measurements")
    cells = list(zip(*rows, strict=True))
    columns: dict[str, np.ndarray] = {}
    for j, (base, unit) in enumerate(bases):
        spec = CSV_COLUMNS.get(base)
        if spec is None:  # a structure temperature
            spec = CsvColumn(f"{base}_c", ColumnRule(base, "deg_C", -100.0, 100.0))
        if spec.text:
            values = np.array(cells[j], dtype=str)
            if base == "time":
                columns["t_s"], meta["epoch_utc"] = _times(values, where, lines)
            columns[spec.target] = values
            continue
        numbers = _numbers(cells[j], headings[j], where, lines)
        converted = unit_factor(unit, spec.rule, f"{where}:{names_line}",
                                hint=f"name the column {base}_<unit> (e.g. {base}_"
                                f"{_suffix(spec.rule.unit)}) or add '# units: {base}=<unit>'"
                                )(numbers)
        check_range(converted, spec.rule, where, lines, shown=numbers)
        columns[spec.target] = np.asarray(converted, dtype=float)
    if "d_az_arcmin" in columns:
        columns["xel_arcmin"] = columns.pop("d_az_arcmin") * np.cos(np.radians(
            columns["el_deg"]))
    for axis in ("xel", "el"):
        columns[f"{axis}_arcmin"] = sign * columns[f"{axis}_arcmin"]
        columns[f"model_{axis}_arcmin"] = np.zeros(len(rows))
        columns[f"applied_{axis}_arcmin"] = np.zeros(len(rows))
    columns["polarization"] = np.full(len(rows), "AVG")
    columns["good"] = np.ones(len(rows), dtype=bool)
    if "t_s" in columns:
        repeat = first_repeat([columns["t_s"], columns["az_deg"], columns["el_deg"]])
        if repeat is not None:
            first, row = repeat
            raise InputError(f"{where}:{lines[row]}", "row", ",".join(rows[row]),
                             f"repeats line {lines[first]} (same time and position)",
                             "give each measurement once")
    else:  # no time to tell two measurements apart: a row equal in every column is one twice
        repeat = first_repeat([np.asarray(c) for c in columns.values()])
        if repeat is not None:
            first, row = repeat
            raise InputError(f"{where}:{lines[row]}", "row", ",".join(rows[row]),
                             f"repeats line {lines[first]} in every column",
                             "give each measurement once, or add a time column that tells "
                             "them apart")
    meta["sign_convention"] = ("offsets: indicated minus true (converted from the file's "
                               f"{sign_text})")
    notes = [f"no column {n}: {what}" for n, what in (
        ("time", "no time-dependent tests (and no duplicate check)"),
        ("source", "no tests by source"), ("air_temp", "no tests against air temperature"))
        if n not in seen]
    return CsvData(columns, meta, where, lines, notes)


def _numbers(cells: Sequence[str], heading: str, where: str, lines: list[int]) -> np.ndarray:
    try:
        return np.array(cells, dtype=float)
    except ValueError:
        for i, cell in enumerate(cells):
            try:
                float(cell)
            except ValueError:
                problem = "is empty" if not cell else "is not a number"
                raise InputError(f"{where}:{lines[i]}", heading, cell, problem) from None
        raise


def _times(values: np.ndarray, where: str, lines: list[int]) -> tuple[np.ndarray, str]:
    """Seconds since the first time, and that time (ISO UTC), from ISO UTC strings."""
    texts = [str(v).removesuffix("Z") for v in values]
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # ERFA's "dubious year": refused below, by name
            times = Time(texts, format="isot", scale="utc")
            year = np.asarray(times.ymdhms["year"])
    except ValueError:
        for i, text in enumerate(texts):
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    Time(text, format="isot", scale="utc")
            except ValueError:
                raise InputError(f"{where}:{lines[i]}", "time", str(values[i]),
                                 "is not an ISO UTC time", "write e.g. 1990-02-08T17:03:10") \
                    from None
        raise
    bad = (year < 1900) | (year > 2200)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise InputError(f"{where}:{lines[i]}", "time", str(values[i]), "year outside 1900..2200")
    epoch = times.min()
    return np.asarray((times - epoch).sec, dtype=float), epoch.isot


def _site_meta(settings: Mapping[str, str], where: str) -> dict[str, Any]:
    site: dict[str, float] = {}
    for key, (lo, hi) in (("latitude_deg", (-90.0, 90.0)), ("longitude_deg", (-180.0, 360.0)),
                          ("height_m", (-500.0, 10000.0))):
        if key not in settings:
            continue
        try:
            value = float(settings[key])
        except ValueError:
            raise InputError(where, key, settings[key], "is not a number") from None
        if not lo <= value <= hi:
            raise InputError(where, key, value, f"must lie within {lo:g}..{hi:g}")
        site[key] = value
    return {"site": site} if site else {}


def pointing_data(data: CsvData):
    """The measurements as :class:`~controller.pointing.data.PointingData` (total pointing
    error, indicated minus true, arcsec)."""
    c = data.columns
    sensors = structure_sensor_names(list(c))
    return PointingData(az_rad=np.radians(c["az_deg"]), el_rad=np.radians(c["el_deg"]),
                        xel_arcsec=60.0 * c["xel_arcmin"], el_arcsec=60.0 * c["el_arcmin"],
                        aux=sensor_aux(c, sensors) if sensors else None, t_s=c.get("t_s"))

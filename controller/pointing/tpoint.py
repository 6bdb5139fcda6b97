"""TPOINT file formats: pointing data files and ``.mod`` model files.

Pointing data (TPOINT's ``INDAT`` input), as in ``examples/*.dat``::

    ! comment lines, anywhere; "!" also starts a trailing comment
    Caption line (free text)
    : ALTAZ                      option records (ALTAZ, EQUAT, NODA, ROTNL, ROTNR, ...)
    : ROTNR
    -30 14 40.2 2020 3 15 12.0 741 2608 0.4 0.55 0.0065
                                 run parameters: latitude d m s (sign on the degrees), then
                                 optionally date y m d, temperature C, pressure mB, height m,
                                 relative humidity 0-1, wavelength micron, lapse rate K/m
    154.5139233 46.1577658 154.4096955 46.2199866 314.4605341
                                 A_obs E_obs A_raw E_raw [rotator], degrees
    ; 357.56 17.95 357.49 18.04 masked observation: read, flagged, not fitted by default
    END

The azimuth: a TPOINT data file gives it North-based (N = 0, E = 90), as TPOINT reads it,
and it is read and written as it is: the azimuth of every star is the one the file gives,
the same as antsim's everywhere else. TPOINT writes its terms in its own azimuth, South = 0,
East = 90, the mirror image of the North-based one (A_T = 180 deg - A_N); the terms of
:mod:`.terms` do the same, so they reproduce TPOINT's own fits (docs/inputs.md, "The azimuth
of a TPOINT file"; tested end to end in tests/end_to_end/test_tpoint_azimuth.py).
"obs" is the true (catalogue, observed) position and "raw" the indicated (encoder) one, so
the pointing error "indicated minus true" is raw - obs.

Sexagesimal records: TPOINT's original record format (the JCMT's ``.pnt`` files, "TPOINT input
version 1") gives catalogue and telescope RA/Dec as ``h m s  +d m s  h m s  +d m s`` followed
by the sidereal time ``h m`` and optional further fields. They are parsed (``coordinates ==
"radec"``) but cannot be fitted with the alt-az term set: that needs an astrometric reduction
to Az/El first. Sexagesimal Az/El records are not a TPOINT format we found documented and are
rejected with a clear message.

Model files (TPOINT ``OUTMOD``/``INMOD``), as read by RTS2 and LibDegorasSLR::

    Caption line
    T   80   0.932   0.0000   0.0000     method, observations, sky RMS, refraction A, B
      IA      +1209.2612     1.28477      flags (2 chars), name, value and sigma (arcsec)
    & HESA2     -11.8900     1.98200      "&": term applied in parallel with the previous one
     =IE          +0.0000                 "=": fixed term, no sigma
    END

Every malformed line raises :class:`~controller.errors.InputError` naming ``file:line``, the
field and the value.
"""

from __future__ import annotations

import datetime
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np

from controller.errors import InputError, read_text_file, write_text_file
from controller.filekind import tpoint_or_mod
from controller.units import RAD_PER_DEG

from .data import PointingData
from .legacy import W_TERMS, W_TERMS_COMMENT, names_w_terms, relabel_reconstructed
from .model import PointingModel
from .terms import TermError, get_term, term_refusal

__all__ = [
    "RunParameters",
    "TPointData",
    "TPointModel",
    "caption_problem",
    "format_mod",
    "format_tpoint",
    "parse_mod",
    "parse_tpoint",
    "read_mod",
    "read_tpoint",
    "sniff_format",
    "write_mod",
    "write_tpoint",
]

Format = Literal["tpoint", "ecsv", "mod"]

_NUMBER = re.compile(r"^[+-]?(\d+(\.\d*)?|\.\d+)([eE][+-]?\d+)?$")
_ROTATOR_OPTIONS = ("ROTNL", "ROTNR")
_RUN_FIELDS = (
    ("temperature_c", "temperature (C)"),
    ("pressure_mb", "pressure (mB)"),
    ("height_m", "height (m)"),
    ("humidity", "relative humidity (0-1)"),
    ("wavelength_um", "wavelength (micron)"),
    ("lapse_rate_k_per_m", "lapse rate (K/m)"),
)


# ---------------------------------------------------------------------------------------------
# Small parsing helpers
# ---------------------------------------------------------------------------------------------
def _strip_comment(line: str) -> str:
    """Text before a "!" comment, stripped."""
    return line.split("!", 1)[0].strip()


def _number(token: str, where: str, field_name: str) -> float:
    if not _NUMBER.match(token):
        raise InputError(where, field_name, token, "is not a number")
    value = float(token)
    if not math.isfinite(value):
        raise InputError(where, field_name, token, "is too large to be a number here")
    return value


def _integer(token: str, where: str, field_name: str) -> int:
    if not re.fullmatch(r"[+-]?\d+", token):
        raise InputError(where, field_name, token, "is not a whole number")
    return int(token)


def _sexagesimal(tokens: Sequence[str], where: str, field_name: str, limit: float) -> float:
    """``[sign]d m s`` (three tokens) to a decimal value; the sign is read from the text so
    that ``-00 30 00`` is negative. ``limit`` bounds the magnitude (90 deg, 24 h)."""
    text = " ".join(tokens)
    whole = _integer(tokens[0], where, field_name)
    minutes = _number(tokens[1], where, field_name)
    seconds = _number(tokens[2], where, field_name)
    if tokens[1].startswith(("+", "-")) or tokens[2].startswith(("+", "-")):
        raise InputError(where, field_name, text, "minutes and seconds cannot carry a sign")
    if not (minutes < 60 and seconds < 60):
        raise InputError(where, field_name, text, "minutes and seconds must be below 60")
    value = abs(whole) + minutes / 60.0 + seconds / 3600.0
    if value > limit:
        raise InputError(where, field_name, text, f"is beyond {limit:g}")
    return -value if tokens[0].startswith("-") else value


def _format_sexagesimal(value: float, places: int, *, signed: bool) -> str:
    """``+dd mm ss.ss`` (or ``hh mm ss.sss`` unsigned) with ``places`` decimals of seconds."""
    sign = "-" if value < 0 or (value == 0 and math.copysign(1, value) < 0) else "+"
    scale = 10**places
    total = round(abs(value) * 3600 * scale)  # integer units of the last printed digit
    whole, rest = divmod(total, 3600 * scale)
    minutes, sec_units = divmod(rest, 60 * scale)
    seconds = f"{sec_units // scale:02d}" + (f".{sec_units % scale:0{places}d}" if places else "")
    text = f"{whole:02d} {minutes:02d} {seconds}"
    return (sign + text) if signed else text


# ---------------------------------------------------------------------------------------------
# Pointing data
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class RunParameters:
    """TPOINT's run-parameters record. Fields after the latitude are ``None`` when absent."""

    latitude_deg: float
    date: datetime.date | None = None
    temperature_c: float | None = None
    pressure_mb: float | None = None
    height_m: float | None = None
    humidity: float | None = None
    wavelength_um: float | None = None
    lapse_rate_k_per_m: float | None = None
    extra: tuple[str, ...] = ()

    def format(self) -> str:
        """The record as TPOINT writes it (latitude to 0.01")."""
        parts = [_format_sexagesimal(self.latitude_deg, 2, signed=True)]
        values = [getattr(self, name) for name, _ in _RUN_FIELDS]
        if self.date is not None or any(v is not None for v in values) or self.extra:
            if self.date is None:
                raise ValueError("a run record with weather fields needs its date")
            parts.append(f"{self.date.year} {self.date.month} {self.date.day}")
        last = max((i for i, v in enumerate(values) if v is not None), default=-1)
        if self.extra:
            last = len(values) - 1
        for i in range(last + 1):
            if values[i] is None:
                raise ValueError(
                    f"run record field {_RUN_FIELDS[i][1]} is missing before later ones"
                )
            parts.append(f"{values[i]:.10g}")
        parts.extend(self.extra)
        return " ".join(parts)


def _parse_run(content: str, where: str) -> RunParameters:
    tokens = content.split()
    hint = ("the run-parameters record (latitude d m s, date, weather) follows the caption "
            "and options")
    if len(tokens) < 3:
        raise InputError(where, "run parameters", content, "needs at least the latitude d m s",
                         hint)
    try:
        latitude = _sexagesimal(tokens[:3], where, "latitude", 90.0)
    except InputError as err:
        raise InputError(err.where, err.field, err.value, err.problem, hint) from None
    date = None
    rest = tokens[3:]
    if rest:
        if len(rest) < 3:
            raise InputError(where, "date", " ".join(rest), "needs year, month and day")
        y, mo, d = (_integer(t, where, "date") for t in rest[:3])
        try:
            date = datetime.date(y, mo, d)
        except ValueError as err:
            raise InputError(where, "date", " ".join(rest[:3]), str(err)) from None
        rest = rest[3:]
    values: dict[str, float] = {}
    for (name, label), token in zip(_RUN_FIELDS, rest, strict=False):
        values[name] = _number(token, where, label)
    extra = tuple(rest[len(_RUN_FIELDS):])
    checks = {
        "temperature_c": (-100.0, 100.0),
        "pressure_mb": (0.0, 1200.0),
        "height_m": (-500.0, 10000.0),
        "humidity": (0.0, 1.0),
        "wavelength_um": (1e-6, 1e9),
        "lapse_rate_k_per_m": (0.0, 0.1),
    }
    for (name, label), _token in zip(_RUN_FIELDS, rest, strict=False):
        lo, hi = checks[name]
        if not lo <= values[name] <= hi:
            raise InputError(where, label, values[name], f"must lie between {lo:g} and {hi:g}")
    return RunParameters(latitude, date, extra=extra, **values)


@dataclass(frozen=True, eq=False)
class TPointData:
    """A TPOINT pointing data file.

    ``coordinates`` says what the four position columns hold:

    * ``"azel"`` (decimal records in an ``: ALTAZ`` file): azimuth (North-based, as the
      file gives it) and elevation, degrees;
      ``rotator_deg`` holds the fifth column when present (NaN where absent);
    * ``"radec"`` (sexagesimal records): right ascension (hours converted to degrees) and
      declination, with ``lst_hours`` the sidereal time (NaN if absent);
    * ``"decimal"`` (decimal records in a file whose options name another mount, such as
      ``: EQUAT``): the two coordinates as written, degrees, not converted.

    A file of decimal records with no mount option at all (TPOINT would assume ``EQUAT``) is
    read as alt-az when its second coordinate lies within 0..90 deg, as an elevation must,
    and says so in ``notes``; ``mount="altaz"`` (``--mount altaz``) asks for it outright.

    ``obs`` is the true (catalogue) position and ``raw`` the indicated (encoder) one. Masked
    (``;``) observations are kept with ``masked`` true; ``line_numbers`` are 1-based.
    """

    caption: str
    options: tuple[str, ...]
    run: RunParameters
    coordinates: Literal["azel", "radec", "decimal"]
    lon_obs_deg: np.ndarray
    lat_obs_deg: np.ndarray
    lon_raw_deg: np.ndarray
    lat_raw_deg: np.ndarray
    rotator_deg: np.ndarray
    lst_hours: np.ndarray
    masked: np.ndarray
    line_numbers: np.ndarray
    extra_fields: tuple[tuple[str, ...], ...] = ()
    source: str = "<memory>"
    has_end: bool = True
    comments: tuple[str, ...] = field(default=())
    #: one-line notes for the user (e.g. how a file without a mount option was read)
    notes: tuple[str, ...] = field(default=())

    def __len__(self) -> int:
        return int(self.lon_obs_deg.size)

    @classmethod
    def from_azel(
        cls,
        caption: str,
        run: RunParameters,
        az_obs_deg,
        el_obs_deg,
        az_raw_deg,
        el_raw_deg,
        rotator_deg=None,
        masked=None,
        options: Sequence[str] = ("ALTAZ",),
    ) -> TPointData:
        """Alt-az data from North-based azimuths and elevations (degrees), e.g. to export
        simulated observations to TPOINT. ``options`` must include ``ALTAZ``."""
        opts = tuple(" ".join(o.split()).upper() for o in options)
        if "ALTAZ" not in [o.split()[0] for o in opts if o.split()]:
            raise ValueError("alt-az data need the ALTAZ option")
        if "\n" in caption or not caption.strip():
            raise ValueError("the caption must be one non-empty line")
        if caption_problem(caption):
            raise ValueError(f"caption {caption!r} {caption_problem(caption)}")
        cols = [np.array(v, dtype=float).reshape(-1)
                for v in (az_obs_deg, el_obs_deg, az_raw_deg, el_raw_deg)]
        n = cols[0].size
        if any(c.size != n for c in cols):
            raise ValueError("az/el arrays differ in length")
        rot = (np.full(n, np.nan) if rotator_deg is None
               else np.array(rotator_deg, dtype=float).reshape(-1))
        mask = np.zeros(n, bool) if masked is None else np.array(masked, dtype=bool).reshape(-1)
        if rot.size != n or mask.size != n:
            raise ValueError("rotator/masked arrays differ in length from the positions")
        if not all(np.isfinite(c).all() for c in cols):
            raise ValueError("positions must be finite")
        if (np.abs(cols[1]) > 90).any() or (np.abs(cols[3]) > 90).any():
            raise ValueError("elevations must lie within -90..90 deg")
        cols[0] = cols[0] % 360.0
        cols[2] = cols[2] % 360.0
        arrays = [*cols, rot, np.full(n, np.nan), mask, np.zeros(n, int)]
        for a in arrays:
            a.setflags(write=False)
        return cls(caption.strip(), opts, run, "azel", *arrays,
                   extra_fields=((),) * n)

    # -- views with the alt-az names ----------------------------------------------------------
    def _azel(self, array: np.ndarray, what: str) -> np.ndarray:
        if self.coordinates != "azel":
            raise InputError(self.source, "coordinates", self.coordinates,
                             f"{what} exists only for alt-az (': ALTAZ') decimal records")
        return array

    @property
    def az_obs_deg(self) -> np.ndarray:
        """True azimuth, North-based, degrees."""
        return self._azel(self.lon_obs_deg, "az_obs_deg")

    @property
    def el_obs_deg(self) -> np.ndarray:
        return self._azel(self.lat_obs_deg, "el_obs_deg")

    @property
    def az_raw_deg(self) -> np.ndarray:
        """Indicated (encoder) azimuth, North-based, degrees."""
        return self._azel(self.lon_raw_deg, "az_raw_deg")

    @property
    def el_raw_deg(self) -> np.ndarray:
        return self._azel(self.lat_raw_deg, "el_raw_deg")

    @property
    def mount(self) -> str:
        """``"ALTAZ"``, ``"EQUAT"`` or another mount option; without one, ``"ALTAZ"`` when
        the records were read as Az/El, else ``"EQUAT"`` (TPOINT's default)."""
        word = _mount_option(self.options)
        if word is not None:
            return word
        return "ALTAZ" if self.coordinates == "azel" else "EQUAT"

    @property
    def has_rotator(self) -> bool:
        return bool(np.isfinite(self.rotator_deg).any())

    def pointing_data(self, include_masked: bool = False):
        """The observations as :class:`~controller.pointing.data.PointingData`.

        Pointing error = raw - obs ("indicated minus true"): dA wrapped to +-180 deg, then
        ``xel = dA cos E_obs``, both in arcsec. Masked observations are left out unless
        ``include_masked``. Equatorial data raise :class:`InputError`: the alt-az term set
        does not support them yet.
        """
        if self.coordinates != "azel":
            kind = "equatorial (RA/Dec)" if self.coordinates == "radec" else "non-alt-az"
            if _mount_option(self.options) is None and self.coordinates == "decimal":
                kind = "without a mount option and with second coordinates below 0 deg " \
                       "(not elevations), TPOINT's default equatorial"
            raise InputError(
                self.source, "mount", self.mount,
                f"{kind} data are not supported by the alt-az term set yet",
                "only decimal Az/El records (': ALTAZ', or --mount altaz) can be fitted",
            )
        keep = np.ones(len(self), dtype=bool) if include_masked else ~self.masked
        if len(self) and not keep.any():
            raise InputError(self.source, "observations", 0,
                             f"every one of the {len(self)} observations is masked (';')",
                             "--include-masked fits them too")
        unread = np.flatnonzero(keep & ~np.isfinite(self.lat_obs_deg))
        if unread.size:
            i = int(unread[0])
            raise InputError(f"{self.source}:{self.line_numbers[i]}", "observation",
                             " ".join(self.extra_fields[i]) if self.extra_fields else "",
                             "is a masked record whose fields are not an observation: "
                             "--include-masked cannot fit it",
                             "unmask only records of four or five numbers")
        az_obs = self.lon_obs_deg[keep]
        el_obs = self.lat_obs_deg[keep]
        d_az = (self.lon_raw_deg[keep] - az_obs + 180.0) % 360.0 - 180.0
        d_el = self.lat_raw_deg[keep] - el_obs
        el_rad = el_obs * RAD_PER_DEG
        rotator = self.rotator_deg[keep]
        return PointingData(
            az_rad=az_obs * RAD_PER_DEG,
            el_rad=el_rad,
            xel_arcsec=d_az * 3600.0 * np.cos(el_rad),
            el_arcsec=d_el * 3600.0,
            # the rotator column (ROTNL/ROTNR files) is the angle terms with a feed-angle
            # factor read (HSCF, HECF, ...); TPOINT's NRX and NRY need only the elevation
            feed_rad=(rotator * RAD_PER_DEG if rotator.size and np.isfinite(rotator).all()
                      else None),
        )


def _classify_record(tokens: list[str]) -> str:
    if len(tokens) in (4, 5):
        return "decimal"
    if len(tokens) >= 12:
        return "sexagesimal"
    return "bad"


def _decimal_record(tokens: list[str], where: str
                    ) -> tuple[tuple[float, ...], tuple[str, ...]]:
    """An observation of 4-5 decimal-degree fields (A_obs E_obs A_raw E_raw [rotator]): the
    row (obs, raw, rotator, no LST) and no extra fields."""
    values = [_number(t, where, name) for t, name in
              zip(tokens, ("A_obs", "E_obs", "A_raw", "E_raw", "rotator"), strict=False)]
    for value, name in ((values[1], "E_obs"), (values[3], "E_raw")):
        if not -90.0 <= value <= 90.0:
            raise InputError(where, name, value, "elevation must lie within -90..90 deg")
    for value, name in ((values[0], "A_obs"), (values[2], "A_raw")):
        if not -360.0 <= value <= 720.0:
            raise InputError(where, name, value, "azimuth must lie within -360..720 deg")
    rotator = values[4] if len(values) == 5 else math.nan
    if not -360.0 <= rotator <= 720.0 and len(values) == 5:
        raise InputError(where, "rotator", rotator, "a rotator angle must lie within "
                         "-360..720 deg")
    return (values[0], values[1], values[2], values[3], rotator, math.nan), ()


def _sexagesimal_record(tokens: list[str], where: str, content: str
                        ) -> tuple[tuple[float, ...], tuple[str, ...]]:
    """An observation as a sexagesimal RA/Dec record (h m s +d m s h m s +d m s [lst h m]):
    the row (obs, raw in degrees, no rotator, LST hours) and the fields after it."""
    for i in (0, 1, 3, 4, 6, 7, 9, 10):  # hours, degrees and minutes are whole
        if not re.fullmatch(r"[+-]?\d+", tokens[i]):
            raise InputError(
                where, "observation", content,
                "is neither 4-5 decimal-degree fields nor a sexagesimal RA/Dec record "
                "(h m s +d m s h m s +d m s [lst h m]); sexagesimal Az/El is not a "
                "TPOINT format",
            )
    ra_obs = _sexagesimal(tokens[0:3], where, "RA_obs", 24.0) * 15.0
    dec_obs = _sexagesimal(tokens[3:6], where, "Dec_obs", 90.0)
    ra_raw = _sexagesimal(tokens[6:9], where, "RA_raw", 24.0) * 15.0
    dec_raw = _sexagesimal(tokens[9:12], where, "Dec_raw", 90.0)
    for value, token, name in ((ra_obs, tokens[0], "RA_obs"),
                               (ra_raw, tokens[6], "RA_raw")):
        if token.startswith("-"):
            raise InputError(where, name, token, "right ascension cannot be negative")
        if value >= 360.0:
            raise InputError(where, name, token, "right ascension must be below 24 h")
    lst = math.nan
    rest = tokens[12:]
    if len(rest) >= 2 and re.fullmatch(r"\d+", rest[0]) and _NUMBER.match(rest[1]):
        hours = int(rest[0])
        minutes = float(rest[1])
        if hours >= 24 or minutes >= 60:
            raise InputError(where, "LST", " ".join(rest[:2]),
                             "sidereal time must be below 24 h and minutes below 60")
        lst = hours + minutes / 60.0
        rest = rest[2:]
    return (ra_obs, dec_obs, ra_raw, dec_raw, math.nan, lst), tuple(rest)


#: TPOINT's mount options (the first word of an option record)
_MOUNT_OPTIONS = ("ALTAZ", "EQUAT", "GIMBAL")
MOUNTS = ("altaz",)


def _mount_option(options: Sequence[str]) -> str | None:
    for option in options:
        word = option.split()[0].upper() if option.split() else ""
        if word in _MOUNT_OPTIONS:
            return word
    return None


def _coordinates(kind: str | None, options: list[str], rows: np.ndarray, mount: str | None,
                 source: str) -> tuple[Literal["azel", "radec", "decimal"], tuple[str, ...]]:
    """What the records' angles are, and a note when that was assumed: RA/Dec for
    sexagesimal records; azimuth and elevation with ``: ALTAZ`` or ``mount="altaz"``, or
    with no mount option when every second coordinate is a possible elevation (0..90 deg);
    else unspecified decimal degrees."""
    if kind == "sexagesimal":
        if mount == "altaz":
            raise InputError(source, "--mount", mount,
                             "the records are sexagesimal RA/Dec, which cannot be read as "
                             "Az/El")
        return "radec", ()
    option = _mount_option(options)
    if option == "ALTAZ" or mount == "altaz":
        return "azel", ()
    if option is None and rows.size and (rows[:, 1] >= 0.0).all() \
            and (rows[:, 3] >= 0.0).all():
        return "azel", (f"{source}: no mount option line (': ALTAZ'); its decimal records "
                        "were read as Az/El (alt-az), as their elevations allow; "
                        "--mount altaz says so outright",)
    return "decimal", ()


def parse_tpoint(text: str, source: str = "<string>", mount: str | None = None) -> TPointData:
    """Parse the text of a TPOINT pointing data file; ``source`` names it in errors.
    ``mount="altaz"`` reads decimal records as Az/El whatever the options say.

    As TPOINT reads it: ``!`` starts a comment anywhere; on a record, a ``;`` after the
    fields starts a comment (``... ; [0026] AT_O_...``); a ``;`` in front masks the record,
    which is kept as masked whatever its fields hold (``; nan nan nan nan``: NaN, never
    fitted). Refused: a file whose first line is not a caption, two mount options that
    contradict each other, and an observation repeated exactly (it would count twice)."""
    if mount is not None and mount not in MOUNTS:
        raise InputError(source, "--mount", mount, f"must be one of {', '.join(MOUNTS)}")
    text = text.removeprefix("\ufeff")
    caption: str | None = None
    options: list[str] = []
    comments: list[str] = []
    run: RunParameters | None = None
    rows: list[tuple[float, ...]] = []
    extras: list[tuple[str, ...]] = []
    masked: list[bool] = []
    line_numbers: list[int] = []
    kind: str | None = None
    has_end = False
    mount_line: tuple[str, int] | None = None

    for line_no, raw_line in enumerate(text.splitlines(), start=1):
        where = f"{source}:{line_no}"
        stripped = raw_line.strip()
        if stripped.startswith("!"):
            if caption is None:
                comments.append(stripped[1:].strip())
            continue
        if caption is None:
            if stripped:
                _check_caption(stripped, where)
                caption = stripped
            continue
        content = _strip_comment(raw_line)
        if not content:
            continue
        if content.startswith(":"):
            option = " ".join(content[1:].split())
            if not option:
                raise InputError(where, "option", content, "is empty")
            if run is not None:
                raise InputError(where, "option", option,
                                 "option records must come before the run-parameters record")
            word = option.split()[0].upper()
            if word in _MOUNT_OPTIONS:
                if mount_line is not None and mount_line[0] != word:
                    raise InputError(where, "option", option,
                                     f"contradicts ': {mount_line[0]}' on line "
                                     f"{mount_line[1]}: a file's records are of one mount")
                mount_line = (word, line_no)
            options.append(option.upper())
            continue
        if run is None:
            run = _parse_run(_strip_record_comment(content), where)
            continue
        if content.upper() == "END":
            has_end = True
            break
        is_masked = content.startswith(";")
        if is_masked:
            content = content[1:].strip()
            if not content:
                raise InputError(where, "observation", raw_line.strip(),
                                 "a ';' (masked observation) line needs an observation")
        content = _strip_record_comment(content)
        if content.upper() == "END" and not is_masked:
            has_end = True
            break
        tokens = content.split()
        record = _classify_record(tokens)
        try:
            if record == "bad":
                raise InputError(
                    where, "observation", content,
                    f"has {len(tokens)} fields; expected 4 or 5 decimal-degree fields "
                    "(A_obs E_obs A_raw E_raw [rotator]) or a sexagesimal RA/Dec record",
                )
            if kind is not None and kind != record:
                raise InputError(where, "observation", content,
                                 f"is a {record} record in a file of {kind} records")
            row, extra = (_decimal_record(tokens, where) if record == "decimal"
                          else _sexagesimal_record(tokens, where, content))
        except InputError:
            if not is_masked:
                raise
            # masked whatever its fields: kept, flagged, never fitted
            row, extra = (math.nan,) * 6, tuple(tokens)
        else:
            kind = kind or record
        rows.append(row)
        extras.append(extra)
        masked.append(is_masked)
        line_numbers.append(line_no)

    if caption is None:
        raise InputError(source, "caption", "", "the file is empty: no caption line")
    if run is None:
        raise InputError(source, "run parameters", "",
                         "no run-parameters record (latitude d m s ...) after the caption")
    table = np.array(rows, dtype=float).reshape(-1, 6)
    masked_arr = np.array(masked, dtype=bool)
    lines_arr = np.array(line_numbers, dtype=int)
    _refuse_repeats(table, masked_arr, lines_arr, text, source)
    coordinates, notes = _coordinates(kind, options,
                                      table[np.isfinite(table[:, :4]).all(axis=1)], mount,
                                      source)
    if coordinates == "azel":  # azimuths as the file gives them, within 0..360 deg
        table[:, 0] %= 360.0
        table[:, 2] %= 360.0
    arrays = [np.ascontiguousarray(table[:, i]) for i in range(6)]
    for a in (*arrays, masked_arr, lines_arr):
        a.setflags(write=False)
    return TPointData(
        caption=caption, options=tuple(options), run=run, coordinates=coordinates,
        lon_obs_deg=arrays[0], lat_obs_deg=arrays[1], lon_raw_deg=arrays[2],
        lat_raw_deg=arrays[3], rotator_deg=arrays[4], lst_hours=arrays[5],
        masked=masked_arr, line_numbers=lines_arr, extra_fields=tuple(extras),
        source=source, has_end=has_end, comments=tuple(comments), notes=notes,
    )


def _strip_record_comment(content: str) -> str:
    """A record's fields: what comes before a ``;`` that follows them (a comment, as TPOINT
    reads it: ``... 314.46 ; [0026] AT_O_20200315_000026``)."""
    return content.split(";", 1)[0].strip()


def caption_problem(line: str) -> str | None:
    """Why ``line`` cannot be a TPOINT data file's caption (free text), or None: an option
    record, or three or more numbers (a run-parameters record or an observation), means the
    caption is missing and TPOINT would take that record for it and misread what follows."""
    tokens = line.split()
    if line.strip().startswith(":"):
        return "is an option record: the caption line (free text) is missing before it"
    if len(tokens) >= 3 and all(_NUMBER.match(t) for t in tokens):
        return ("is a record of numbers: the caption line (free text) is missing before "
                "it")
    return None


def _check_caption(line: str, where: str) -> None:
    problem = caption_problem(line)
    if problem:
        raise InputError(where, "caption", line, problem,
                         "a TPOINT data file starts with a caption, then its options")


def _refuse_repeats(table: np.ndarray, masked: np.ndarray, lines: np.ndarray, text: str,
                    source: str) -> None:
    """InputError for the first observation (not masked) that repeats an earlier one in
    every field: a line given twice would count one star twice in the fit."""
    keep = np.flatnonzero(~masked & np.isfinite(table[:, :4]).all(axis=1))
    if keep.size < 2:
        return
    rows = np.nan_to_num(table[keep], nan=np.inf)  # no rotator, no LST: equal, as NaN is not
    _, first, inverse = np.unique(rows, axis=0, return_index=True, return_inverse=True)
    repeated = np.flatnonzero(first[inverse.reshape(-1)] != np.arange(keep.size))
    if repeated.size:
        i = int(repeated[0])
        j = int(first[inverse.reshape(-1)[i]])
        line = int(lines[keep[i]])
        raise InputError(f"{source}:{line}", "observation",
                         text.splitlines()[line - 1].strip(),
                         f"repeats line {int(lines[keep[j]])} exactly",
                         "give each observation once: a repeated line counts one star twice")


def _read_text(path: str | Path) -> str:
    return read_text_file(path)


def read_tpoint(path: str | Path, mount: str | None = None) -> TPointData:
    """Read a TPOINT pointing data file (see the module docstring and :func:`parse_tpoint`)."""
    return parse_tpoint(_read_text(path), source=str(path), mount=mount)


def format_tpoint(data: TPointData, decimals: int = 7) -> str:
    """TPOINT data file text for ``data``; positions printed with ``decimals`` decimals
    (7 decimals of a degree is 0.36 mas). Azimuths are written as they are, North-based."""
    lines = [f"! {c}" if c else "!" for c in data.comments]
    lines.append(data.caption)
    lines += [f": {o}" for o in data.options]
    lines.append(data.run.format())
    n = len(data)
    for i in range(n):
        prefix = "; " if data.masked[i] else ""
        if not math.isfinite(data.lat_obs_deg[i]):  # a masked record that is no observation
            lines.append(prefix + " ".join(data.extra_fields[i] if data.extra_fields
                                           else ("nan",) * 4))
            continue
        if data.coordinates == "radec":
            fields = [
                _format_sexagesimal(data.lon_obs_deg[i] / 15.0, 3, signed=False),
                _format_sexagesimal(data.lat_obs_deg[i], 2, signed=True),
                _format_sexagesimal(data.lon_raw_deg[i] / 15.0, 3, signed=False),
                _format_sexagesimal(data.lat_raw_deg[i], 2, signed=True),
            ]
            lst = data.lst_hours[i]
            if math.isfinite(lst):
                hours = int(lst)
                fields.append(f"{hours:02d} {(lst - hours) * 60.0:.5f}")
            fields.extend(data.extra_fields[i] if data.extra_fields else ())
            lines.append(prefix + "  ".join(fields))
            continue
        values = [data.lon_obs_deg[i], data.lat_obs_deg[i], data.lon_raw_deg[i],
                  data.lat_raw_deg[i]]
        if math.isfinite(data.rotator_deg[i]):
            values.append(data.rotator_deg[i])
        lines.append(prefix + " ".join(f"{v:.{decimals}f}" for v in values))
    lines.append("END")
    return "\n".join(lines) + "\n"


def write_tpoint(data: TPointData, path: str | Path, decimals: int = 7) -> None:
    """Write ``data`` as a TPOINT pointing data file."""
    write_text_file(path, format_tpoint(data, decimals))


# ---------------------------------------------------------------------------------------------
# Model files
# ---------------------------------------------------------------------------------------------
_DEFAULT_PARAMETERS = ("T", "0", "0.000", "0.0000", "0.0000")


class TPointModel(PointingModel):
    """A :class:`~controller.pointing.model.PointingModel` with what a TPOINT ``.mod`` file adds.

    It *is* a ``PointingModel`` (``read_mod`` results can be used wherever a model is
    expected); on top it carries, per term, ``sigma_arcsec`` (NaN where the file gives none),
    ``fixed`` ("=" flag) and ``parallel`` ("&" flag), and for the file the ``caption`` and
    the second record ``parameters`` kept verbatim (RTS2 reads it as method, number of
    observations, sky RMS, refraction constants A and B; ``None`` when a hand-written file
    leaves it out). The model's ``name`` defaults to the caption. Written, not read back:
    ``comments`` (lines after the caption, each starting with ``!``) and per term ``notes``
    (a comment at the end of its line; empty: none).
    """

    sigma_arcsec: np.ndarray
    fixed: tuple[bool, ...]
    parallel: tuple[bool, ...]
    caption: str
    parameters: tuple[str, ...] | None
    comments: tuple[str, ...]
    notes: tuple[str, ...]

    def __init__(
        self,
        terms=(),
        values_arcsec=None,
        name: str | None = None,
        *,
        sigma_arcsec: Sequence[float | None] | None = None,
        fixed: Sequence[bool] | None = None,
        parallel: Sequence[bool] | None = None,
        caption: str | None = None,
        parameters: tuple[str, ...] | None = _DEFAULT_PARAMETERS,
        comments: Sequence[str] = (),
        notes: Sequence[str] | None = None,
    ):
        super().__init__(terms, values_arcsec, name or caption)
        m = len(self.terms)
        if sigma_arcsec is None:
            sigmas = np.full(m, np.nan)
        else:
            sigmas = np.array([np.nan if v is None else float(v) for v in sigma_arcsec])
            if sigmas.size != m:
                raise ValueError(f"{sigmas.size} sigmas for {m} terms")
        sigmas.setflags(write=False)
        flags = {}
        for label, given in (("fixed", fixed), ("parallel", parallel)):
            values = (False,) * m if given is None else tuple(bool(v) for v in given)
            if len(values) != m:
                raise ValueError(f"{len(values)} {label} flags for {m} terms")
            flags[label] = values
        object.__setattr__(self, "sigma_arcsec", sigmas)
        object.__setattr__(self, "fixed", flags["fixed"])
        object.__setattr__(self, "parallel", flags["parallel"])
        object.__setattr__(self, "caption", caption if caption is not None else self.name)
        object.__setattr__(self, "parameters", None if parameters is None else tuple(parameters))
        notes = ("",) * m if notes is None else tuple(str(n) for n in notes)
        if len(notes) != m:
            raise ValueError(f"{len(notes)} notes for {m} terms")
        object.__setattr__(self, "comments", tuple(comments))
        object.__setattr__(self, "notes", notes)

    @property
    def fit_sky_rms_arcsec(self) -> float | None:
        """The Sky RMS (arcsec) of the fit this model came from, as the parameters record
        gives it (method, observations, sky RMS, ...); None when it gives none."""
        try:
            rms = float(self.parameters[2]) if self.parameters else 0.0
        except (IndexError, ValueError):
            return None
        return rms if rms > 0 and math.isfinite(rms) else None

    @property
    def fit_observations(self) -> int | None:
        """The observations of the fit this model came from (parameters record), or None."""
        try:
            n = int(self.parameters[1]) if self.parameters else 0
        except (IndexError, ValueError):
            return None
        return n if n > 0 else None

    @classmethod
    def from_model(
        cls,
        model: PointingModel,
        sigma_arcsec: Sequence[float] | None = None,
        *,
        caption: str | None = None,
        n_obs: int = 0,
        sky_rms_arcsec: float = 0.0,
        fixed: Sequence[str] = (),
    ) -> TPointModel:
        """``model`` with sigmas (NaN = none), the terms named in ``fixed`` flagged as fixed
        (``=``), and the parameters record filled in."""
        rms = sky_rms_arcsec if math.isfinite(sky_rms_arcsec) else 0.0
        params = ("T", str(int(n_obs)), f"{rms:.3f}", "0.0000", "0.0000")
        return cls(model.terms, model.values_arcsec, model.name, sigma_arcsec=sigma_arcsec,
                   fixed=[n in fixed for n in model.names], caption=caption or model.name,
                   parameters=params)

    @classmethod
    def from_fit(cls, result, caption: str | None = None) -> TPointModel:
        """The model of a :class:`~controller.pointing.result.FitResult` with its sigmas."""
        return cls.from_model(result.model, result.sigma_arcsec, caption=caption,
                              n_obs=result.n_used, sky_rms_arcsec=result.sky_rms_arcsec,
                              fixed=result.fixed)

    def to_pointing_model(self, name: str | None = None) -> PointingModel:
        """A plain :class:`~controller.pointing.model.PointingModel` with the same terms and
        values."""
        return PointingModel(self.terms, self.values_arcsec, name or self.name)


_TERM_LINE = re.compile(
    r"^(?P<flags>[\s&=]*)(?P<name>[A-Za-z][A-Za-z0-9]*)(?P<rest>(?=[\s+-]|$).*)$"
)


def _is_term_line(content: str) -> bool:
    m = _TERM_LINE.match(content)
    if not m:
        return False
    try:
        get_term(m.group("name"))
    except TermError:
        return False
    return True


def parse_mod(text: str, source: str = "<string>") -> TPointModel:
    """Parse the text of a TPOINT ``.mod`` model file."""
    text = text.removeprefix("\ufeff")
    caption: str | None = None
    parameters: tuple[str, ...] | None = None
    names: list[str] = []
    values: list[float] = []
    sigmas: list[float | None] = []
    fixed: list[bool] = []
    parallel: list[bool] = []
    seen: dict[str, int] = {}
    expect_parameters = True
    for line_no, raw_line in enumerate(text.splitlines(), start=1):
        where = f"{source}:{line_no}"
        if caption is None:
            if raw_line.strip() and not raw_line.strip().startswith("!"):
                caption = raw_line.strip()
            continue
        content = _strip_comment(raw_line)
        if not content:
            continue
        if content.upper() == "END":
            break
        tokens = content.split()
        if expect_parameters:
            expect_parameters = False
            if not _is_term_line(content):
                if not re.fullmatch(r"[A-Za-z]+", tokens[0]) or not all(
                    _NUMBER.match(t) for t in tokens[1:]
                ):
                    raise InputError(where, "parameters", content,
                                     "expected the model parameters record "
                                     "(method, observations, sky RMS, refraction A, B)")
                parameters = tuple(tokens)
                continue
        m = _TERM_LINE.match(raw_line.split("!", 1)[0].rstrip())
        if not m:
            raise InputError(where, "term", content, "is not a term line (name value [sigma])")
        flags, name, rest = m.group("flags"), m.group("name").upper(), m.group("rest").split()
        try:
            get_term(name)
        except TermError:
            problem, hint = term_refusal(name)
            raise InputError(where, "term", name, problem, hint) from None
        if name in seen:
            raise InputError(where, "term", name, f"already given on line {seen[name]}")
        if not 1 <= len(rest) <= 2:
            raise InputError(where, name, " ".join(rest) or content,
                             "expected a value in arcsec and optionally its sigma")
        value = _number(rest[0], where, f"{name} value")
        if abs(value) > 648000.0:
            raise InputError(where, f"{name} value", rest[0],
                             "a coefficient beyond 180 deg (648000 arcsec)")
        sigma = _number(rest[1], where, f"{name} sigma") if len(rest) == 2 else None
        if sigma is not None and sigma < 0:
            raise InputError(where, f"{name} sigma", rest[1], "a sigma cannot be negative")
        seen[name] = line_no
        names.append(name)
        values.append(value)
        sigmas.append(sigma)
        fixed.append("=" in flags)
        parallel.append("&" in flags)
    if caption is None:
        raise InputError(source, "caption", "", "the file is empty: no caption line")
    if names_w_terms(names) and W_TERMS not in text:
        renamed = relabel_reconstructed(dict(zip(names, range(len(names)), strict=True)),
                                        source)
        order = list(renamed.values())  # the old positions, in the new order
        names = list(renamed)
        values, sigmas, fixed, parallel = ([seq[i] for i in order]
                                           for seq in (values, sigmas, fixed, parallel))
    return TPointModel(names, values, sigma_arcsec=sigmas, fixed=fixed, parallel=parallel,
                       caption=caption, parameters=parameters)


def read_mod(path: str | Path) -> TPointModel:
    """Read a TPOINT ``.mod`` model file (a :class:`TPointModel`, hence a PointingModel)."""
    return parse_mod(_read_text(path), source=str(path))


def format_mod(model: PointingModel) -> str:
    """``.mod`` text: 2 flag columns, name in 8, value F10.4 with sign, sigma F12.5.

    A plain ``PointingModel`` is written with its name as caption and no sigmas; use
    :meth:`TPointModel.from_fit` to write a fit's sigmas.
    """
    if not isinstance(model, TPointModel):
        model = TPointModel.from_model(model)
    lines = [model.caption or model.name, *model.comments]
    if names_w_terms(model.names):
        lines.append(W_TERMS_COMMENT)
    if model.parameters is not None:
        lines.append("  ".join(model.parameters))
    for i, term in enumerate(model.terms):
        flags = ("&" if model.parallel[i] else " ") + ("=" if model.fixed[i] else " ")
        # The explicit sign keeps an 8-character name such as HSCA5CE8 apart from its value.
        line = f"{flags}{term.name:<8}{model.values_arcsec[i]:+10.4f}"
        if math.isfinite(model.sigma_arcsec[i]):
            line += f"{model.sigma_arcsec[i]:12.5f}"
        if model.notes[i]:
            line = f"{line:<34}! {model.notes[i]}"
        lines.append(line)
    lines.append("END")
    return "\n".join(lines) + "\n"


def write_mod(model: PointingModel, path: str | Path) -> None:
    """Write ``model`` (a :class:`TPointModel` or any PointingModel) as a ``.mod`` file,
    whole or not at all (:func:`~controller.errors.write_text_file`)."""
    write_text_file(path, format_mod(model))


# ---------------------------------------------------------------------------------------------
# Format detection (controller.filekind decides; this is its answer for one file on disk)
# ---------------------------------------------------------------------------------------------
def sniff_format(path: str | Path) -> Format:
    """``"ecsv"``, ``"tpoint"`` (pointing data) or ``"mod"`` (model), judged by content
    (:func:`controller.filekind.file_kind` without the CSV and JSON kinds)."""
    text = _read_text(path)
    if text.startswith("# %ECSV"):
        return "ecsv"
    return tpoint_or_mod(path, text)

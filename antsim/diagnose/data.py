"""What diagnosis reads: one row per scan (or star) with everything the candidates may need.

:class:`Observations` holds, per scan, the total pointing error (indicated minus true: measured
correction + model in use + applied correction) of the polarization average at the observed
position, and the context columns the recordings carry: time, source, Sun elevation, air
temperature, direction of the last slew, measured beam widths, the XR - XL offset
difference and the structure temperatures where the antenna has sensors. TPOINT data files
give only positions (and a rotator angle); the context columns are then absent (None) and
candidates that need them are not tried.

Recordings of an equatorial mount (metadata ``mount: equatorial``) are read on the mount's
axes: ``az_rad``/``el_rad`` hold the hour angle (positive West) and the declination, the
offsets are cross-declination (dH cos Dec) and declination, and pointing terms are TPOINT's
equatorial ones (:meth:`Observations.terms`), as everywhere a model works on "the mount's
two axes" (:mod:`controller.astro.frames`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from controller.errors import InputError
from controller.pointing.equatorial import equatorial_model, equatorial_terms
from controller.pointing.model import PointingModel
from controller.pointing.thermal import sensor_aux, structure_sensor_names
from controller.pointing.tpoint import read_tpoint
from controller.program.inputs import read_pointing_file

__all__ = ["Observations", "load_observations"]

_ARCSEC_PER_ARCMIN = 60.0


@dataclass(frozen=True)
class Observations:
    """Per-scan arrays (length n; angles in radians, offsets in arcsec; units in the names).

    ``az_rad``/``el_rad``: the position on the mount's axes, azimuth and elevation, or on an
    equatorial mount (``mount``) hour angle and declination; ``xel_arcsec`` is then the
    cross-declination error. ``good``: the reduction flagged nothing and the offsets are
    finite. ``pol_*_arcsec``: XR minus XL measured offsets of the same scan (NaN where either
    is flagged). ``width_*``: beam FWHM measured on the polarization average (arcmin).
    ``meta``: site (latitude_deg, longitude_deg), epoch_utc, beam_hpbw_arcmin, seed,
    scenario, model in use.
    """

    t_s: np.ndarray
    az_rad: np.ndarray
    el_rad: np.ndarray
    xel_arcsec: np.ndarray
    el_arcsec: np.ndarray
    good: np.ndarray
    source: np.ndarray | None = None
    sun_el_deg: np.ndarray | None = None
    air_temp_c: np.ndarray | None = None
    slew_az: np.ndarray | None = None
    slew_el: np.ndarray | None = None
    width_xel_arcmin: np.ndarray | None = None
    width_el_arcmin: np.ndarray | None = None
    pol_xel_arcsec: np.ndarray | None = None
    pol_el_arcsec: np.ndarray | None = None
    rotator_deg: np.ndarray | None = None
    model_in_use: PointingModel | None = None
    meta: dict[str, Any] = field(default_factory=dict)
    kind: str = "ecsv"
    path: str = "<memory>"
    #: the mount whose axes ``az_rad``/``el_rad`` are: "altaz" or "equatorial"
    mount: str = "altaz"
    #: the daily air-temperature curve (C) at campaign times (s), when a scenario gives it:
    #: it extends the recorded temperatures back over the day before the campaign
    air_daily_c: Any = field(default=None, compare=False, repr=False)
    #: structure temperatures (C) where the recordings have them: sensor -> (reading during
    #: the azimuth scan, during the elevation scan), corrected for the sensors' response
    #: time (controller.pointing.thermal.sensor_aux); the ``aux`` of thermal terms
    structure: dict[str, tuple[np.ndarray, np.ndarray]] | None = field(default=None,
                                                                     repr=False)

    def __len__(self) -> int:
        return int(self.t_s.size)

    @property
    def n(self) -> int:
        return len(self)

    @cached_property
    def cos_el(self) -> np.ndarray:
        """cos(``el_rad``), read-only: every term's cross-elevation column is scaled by it
        (a harmonic family's orders ask for it some 150 times at 200,000 scans)."""
        out = np.cos(self.el_rad)
        out.flags.writeable = False
        return out

    @cached_property
    def good_sources(self) -> tuple[np.ndarray, np.ndarray]:
        """The sources of the good scans and how many each has (``np.unique`` with counts):
        a source candidate asks for them several times a round (0.02 s each at 200,000
        scans, strings sorted)."""
        names, counts = np.unique(self.source[self.good], return_counts=True)
        names.flags.writeable = counts.flags.writeable = False
        return names, counts

    def has(self, name: str) -> bool:
        """Whether column ``name`` exists and has some finite values (or, for text, values)."""
        value = getattr(self, name, None)
        if value is None:
            return False
        if value.dtype.kind in "US O":
            return value.size > 0
        return bool(np.isfinite(value.astype(float)).any())

    @property
    def has_time(self) -> bool:
        return self.kind != "tpoint" and bool(np.ptp(self.t_s) > 0) if self.n else False

    @property
    def latitude_rad(self) -> float:
        return math.radians(float(self.meta.get("latitude_deg", float("nan"))))

    @property
    def axis_names(self) -> tuple[str, str]:
        """The two axes in words: ("azimuth", "elevation") or ("hour angle", "declination")."""
        return ("hour angle", "declination") if self.mount == "equatorial" \
            else ("azimuth", "elevation")

    def terms(self, names) -> list:
        """Pointing terms by name in the mount's vocabulary: TPOINT's alt-az names (passed
        through), or on an equatorial mount its equatorial terms at the site's latitude
        (:mod:`controller.pointing.equatorial`, Crane's C1..C11 included). Term objects pass
        through."""
        names = list(names)
        if self.mount != "equatorial":
            return names
        return list(equatorial_terms(names, math.degrees(self.latitude_rad)))

    def select(self, mask: np.ndarray) -> Observations:
        """The observations where ``mask`` is true (every per-scan array cut alike)."""
        mask = np.asarray(mask, dtype=bool)
        changes = {}
        for name in _ARRAYS:
            value = getattr(self, name)
            if value is not None:
                changes[name] = value[mask]
        if self.structure is not None:
            changes["structure"] = {k: (x[mask], e[mask]) for k, (x, e) in
                                    self.structure.items()}
        return replace(self, **changes)


_ARRAYS = ("t_s", "az_rad", "el_rad", "xel_arcsec", "el_arcsec", "good", "source", "sun_el_deg",
           "air_temp_c", "slew_az", "slew_el", "width_xel_arcmin", "width_el_arcmin",
           "pol_xel_arcsec", "pol_el_arcsec", "rotator_deg")


def _col(table: Any, name: str) -> np.ndarray | None:
    if isinstance(table, Mapping):
        return None if name not in table else np.asarray(table[name])
    return np.asarray(table[name]) if name in table.colnames else None


def from_columns(cols: Mapping[str, np.ndarray], meta: Mapping[str, Any] | None = None,
                 path: str = "<memory>", kind: str = "ecsv") -> Observations:
    """Observations from recording columns (one row per scan and polarization); an
    equatorial mount's (metadata ``mount``, or the columns ``ha_deg``/``dec_deg``) on its
    axes."""
    meta = dict(meta or {})
    mount = str(meta.get("mount") or ("equatorial" if "ha_deg" in cols else "altaz"))
    lon, lat = ("ha_deg", "dec_deg") if mount == "equatorial" else ("az_deg", "el_deg")
    pol = np.asarray(cols["polarization"]).astype(str)
    scan = np.asarray(cols["scan"]).astype(int) if "scan" in cols else None
    if scan is None:  # rows of one scan share their time
        _, scan = np.unique(np.asarray(cols["t_s"], dtype=float), return_inverse=True)
    avg = np.flatnonzero(pol == "AVG")
    if avg.size == 0:
        raise InputError(path, "polarization", sorted(set(pol.tolist()))[:3],
                         "the recordings have no AVG (polarization average) rows")

    def f(name: str, rows: np.ndarray = avg) -> np.ndarray | None:
        value = cols.get(name)
        return None if value is None else np.asarray(value, dtype=float)[rows]

    def total(axis: str, rows: np.ndarray) -> np.ndarray:
        out = np.asarray(cols[f"{axis}_arcmin"], dtype=float)[rows].copy()
        for part in ("model", "applied"):
            extra = cols.get(f"{part}_{axis}_arcmin")
            if extra is not None:
                out = out + np.asarray(extra, dtype=float)[rows]
        return out * _ARCSEC_PER_ARCMIN

    xel = total("xel", avg)
    el = total("el", avg)
    good = np.isfinite(xel) & np.isfinite(el)
    if "good" in cols:
        good &= np.asarray(cols["good"], dtype=bool)[avg]
    # XR - XL of the same scan
    pol_x = np.full(avg.size, np.nan)
    pol_e = np.full(avg.size, np.nan)
    xr = {int(scan[r]): r for r in np.flatnonzero(pol == "XR")}
    xl = {int(scan[r]): r for r in np.flatnonzero(pol == "XL")}
    good_all = (np.asarray(cols["good"], dtype=bool) if "good" in cols
                else np.ones(pol.size, dtype=bool))
    mx = np.asarray(cols["xel_arcmin"], dtype=float)
    me = np.asarray(cols["el_arcmin"], dtype=float)
    # recordings of the average alone (no XR or XL row): no scan has a pair, and no loop
    # over the scans (0.04 s at 200,000)
    index_of_scan = {int(s): i for i, s in enumerate(scan[avg])} if xr and xl else {}
    for s, i in index_of_scan.items():
        r, ell = xr.get(s), xl.get(s)
        if r is None or ell is None or not (good_all[r] and good_all[ell]):
            continue
        pol_x[i] = (mx[r] - mx[ell]) * _ARCSEC_PER_ARCMIN
        pol_e[i] = (me[r] - me[ell]) * _ARCSEC_PER_ARCMIN
    source = cols.get("source")
    sensors = structure_sensor_names(list(cols))
    lag = float((meta.get("structure_sensors") or {}).get("lag_s", 0.0))
    structure = ({k: (x[avg], e[avg]) for k, (x, e) in sensor_aux(cols, sensors, lag).items()}
                 if sensors else None)
    return Observations(
        t_s=np.asarray(cols["t_s"], dtype=float)[avg],
        az_rad=np.radians(np.asarray(cols[lon], dtype=float)[avg]),
        el_rad=np.radians(np.asarray(cols[lat], dtype=float)[avg]),
        xel_arcsec=xel, el_arcsec=el, good=good,
        source=None if source is None else np.asarray(source).astype(str)[avg],
        sun_el_deg=f("sun_el_deg"), air_temp_c=f("air_temp_c"),
        slew_az=f("slew_az"), slew_el=f("slew_el"),
        width_xel_arcmin=f("xel_width_arcmin"), width_el_arcmin=f("el_width_arcmin"),
        pol_xel_arcsec=pol_x, pol_el_arcsec=pol_e,
        rotator_deg=f("feed_angle_deg"),
        model_in_use=_model_from_meta(meta, mount), meta=_flat_meta(meta), kind=kind,
        path=path, mount=mount, structure=structure,
    )


def from_rows(rows: Sequence[Mapping[str, Any]], meta: Mapping[str, Any] | None = None,
              path: str = "<memory>") -> Observations:
    """Observations from the row dicts :func:`antsim.simulate.runner.simulate` returns."""
    if not rows:
        raise InputError(path, "rows", 0, "there are no recorded scans")
    names = rows[0].keys()
    cols = {k: np.array([r[k] for r in rows]) for k in names if k != "time"}
    return from_columns(cols, meta, path=path)


def _flat_meta(meta: Mapping[str, Any]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    site = meta.get("site")
    if isinstance(site, Mapping):
        for key in ("latitude_deg", "longitude_deg", "height_m"):
            if key in site:
                out[key] = float(site[key])
    for key in ("latitude_deg", "longitude_deg"):
        if key in meta:
            out[key] = float(meta[key])
    for key in ("epoch_utc", "scenario", "seed", "beam_hpbw_arcmin", "duration_s",
                "reduction_width_arcmin"):
        if key in meta:
            out[key] = meta[key]
    return out


def _model_from_meta(meta: Mapping[str, Any], mount: str = "altaz") -> PointingModel | None:
    model = meta.get("model")
    if isinstance(model, PointingModel):
        return model
    if not isinstance(model, Mapping):
        return None
    terms = model.get("terms_arcsec") or {}
    try:
        if mount == "equatorial":
            return equatorial_model(list(terms), float(meta["site"]["latitude_deg"]),
                                    list(terms.values()), name=str(model.get("name")))
        return PointingModel(list(terms), list(terms.values()), name=str(model.get("name")))
    except (KeyError, TypeError, ValueError):
        return None


def from_tpoint(path: str | Path, include_masked: bool = False,
                mount: str | None = None) -> Observations:
    """Observations from a TPOINT pointing data file (no time, source or weather columns);
    ``meta["notes"]`` carries the reader's notes (how a file without a mount option was
    read)."""
    return _from_tpoint_data(read_tpoint(path, mount=mount), include_masked)


def _from_tpoint_data(data, include_masked: bool = False) -> Observations:
    """Observations of a TPOINT file read (:class:`controller.pointing.tpoint.TPointData`)."""
    pd = data.pointing_data(include_masked=include_masked)
    keep = np.ones(len(data), dtype=bool) if include_masked else ~data.masked
    rot = data.rotator_deg[keep] if data.has_rotator else None
    n = len(pd)
    meta: dict[str, Any] = {"latitude_deg": float(data.run.latitude_deg)} \
        if hasattr(data.run, "latitude_deg") else {}
    if data.notes:
        meta["notes"] = list(data.notes)
    return Observations(
        t_s=np.arange(n, dtype=float), az_rad=np.asarray(pd.az_rad), el_rad=np.asarray(pd.el_rad),
        xel_arcsec=np.asarray(pd.xel_arcsec), el_arcsec=np.asarray(pd.el_arcsec),
        good=np.ones(n, dtype=bool), rotator_deg=None if rot is None else np.asarray(rot, float),
        meta=meta, kind="tpoint", path=data.source)


def load_observations(path: str | Path, mount: str | None = None,
                      csv_options: Sequence[str] = ()) -> Observations:
    """Recordings (``.ecsv``), TPOINT data or a CSV of one's own measurements
    (:mod:`controller.program.csvdata`, with its ``--csv`` settings), read through the front
    door of every command's pointing data
    (:func:`controller.program.inputs.read_pointing_file`, which decides the kind and
    checks the file); ``mount="altaz"`` reads a TPOINT file's decimal records as Az/El
    (``--mount altaz``). ``meta["notes"]``: the reader's notes, a line each."""
    file = read_pointing_file(path, purpose="diagnose", csv_options=csv_options, mount=mount)
    if file.kind == "tpoint":
        obs = _from_tpoint_data(file.tpoint)
    elif file.kind == "csv":
        obs = _from_csv_data(file.csv)
    else:
        table = file.recordings
        cols = {name: np.asarray(table[name]) for name in table.colnames if name != "time"}
        obs = from_columns(cols, dict(table.meta), path=file.path)
    return replace(obs, meta={**obs.meta, "notes": list(file.notes)})


def _from_csv_data(data) -> Observations:
    """Observations of CSV measurements read (:class:`controller.program.csvdata.CsvData`)."""
    cols = dict(data.columns)
    n = len(data)
    cols.setdefault("t_s", np.zeros(n))
    cols["scan"] = np.arange(n)
    return from_columns(cols, data.meta, path=data.path, kind="csv")

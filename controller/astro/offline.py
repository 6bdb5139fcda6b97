"""The one place where astropy is told never to reach the network, and the cache of its
Earth-orientation table.

IERS tables come from the ``astropy-iers-data`` package. Importing this module is cheap: it
only sets configuration values and does not import astropy.coordinates.

The parsed table is cached (:func:`use_cached_eop_table`) as data only: a NumPy ``.npz``
archive read with ``allow_pickle=False`` (numbers, strings and a JSON manifest; nothing in
it can run code), with a SHA-256 digest of its content and of the versions that made it,
recomputed when it is read. A file that fails the check is not what this code wrote (a torn
write, a disk error, an edit): it is ignored, the table is read from astropy's own files
again, the file rewritten, and a one-line note says so. docs/caches.md states what each cache
trusts.
"""

import contextlib
import hashlib
import json
import os
import warnings
from importlib import metadata
from pathlib import Path

import astropy
import numpy as np
from astropy import units as u
from astropy.table import Column, MaskedColumn
from astropy.utils import iers

from controller.errors import Note

iers.conf.auto_download = False
iers.conf.auto_max_age = None
# Dates beyond the bundled tables (future campaigns) fall back to zero corrections with a
# warning instead of an exception; 1990 is well inside IERS-B.
iers.conf.iers_degraded_accuracy = "warn"

__all__ = ["eop_cache_path", "read_eop_cache", "use_cached_eop_table", "write_eop_cache"]

#: a cache file larger than this (unpacked) is not the table (~7 MB) and is not read
MAX_CACHE_BYTES = 64 * 2**20
#: bump when the layout of the cache file changes
EOP_CACHE_LAYOUT = 1

_EOP_READY = False


def cache_dir():
    """``$ANTSIM_CACHE``, else ``$XDG_CACHE_HOME/antsim``, else ``~/.cache/antsim``."""
    env = os.environ.get("ANTSIM_CACHE")
    if env:
        return Path(env)
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "antsim"


def _versions() -> dict[str, str] | None:
    """The astropy and astropy-iers-data versions that make the table (None: the data
    package is not installed, astropy finds its tables its own way)."""
    try:
        data_version = metadata.version("astropy-iers-data")
    except metadata.PackageNotFoundError:
        return None
    return {"astropy": astropy.__version__, "astropy-iers-data": data_version,
            "layout": str(EOP_CACHE_LAYOUT)}


def eop_cache_path(versions: dict[str, str]):
    """The cache file of the table these versions make."""
    return cache_dir() / (f"iers-auto-{versions['astropy']}-"
                          f"{versions['astropy-iers-data']}.npz")


def _digest(manifest: str, arrays) -> str:
    h = hashlib.sha256(manifest.encode("utf-8"))
    for array in arrays:
        h.update(str(array.dtype.str).encode())
        h.update(str(array.shape).encode())
        h.update(array.tobytes())
    return h.hexdigest()


def _columns(table) -> tuple[dict, dict]:
    """The table as a JSON-able manifest and named plain arrays (values, masks)."""
    kinds, units, arrays = [], [], {}
    for i, name in enumerate(table.colnames):
        col = table[name]
        unit = getattr(col, "unit", None)
        units.append(None if unit is None else unit.to_string())
        if isinstance(col, MaskedColumn):
            kinds.append("masked")
            arrays[f"v{i}"] = np.asarray(col.data.data)
            arrays[f"m{i}"] = np.asarray(col.mask, dtype=bool)
        else:
            kinds.append("quantity" if hasattr(col, "to_value") else "column")
            arrays[f"v{i}"] = np.asarray(col.value if kinds[-1] == "quantity" else col)
    meta = {}
    for key, value in table.meta.items():
        value = value.item() if hasattr(value, "item") else value
        if not isinstance(value, int | float | str):
            raise TypeError(f"meta {key!r} is a {type(value).__name__}")  # not cached
        meta[key] = value
    return {"names": list(table.colnames), "kinds": kinds, "units": units, "meta": meta}, arrays


def write_eop_cache(table, versions: dict[str, str], path) -> None:
    """Write ``table`` (an ``IERS_Auto``) to ``path`` as data only, with its digest; the
    file appears whole or not at all (written beside it, then renamed)."""
    manifest, arrays = _columns(table)
    manifest["versions"] = versions
    text = json.dumps(manifest, sort_keys=True)
    order = sorted(arrays)
    digest = _digest(text, [arrays[k] for k in order])
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    # a new file of our own (O_EXCL, no link followed), renamed over the old one
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0),
                 0o644)
    try:
        with os.fdopen(fd, "wb") as fh:
            np.savez(fh, manifest=np.array(text), digest=np.array(digest), **arrays)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def read_eop_cache(path, versions: dict[str, str]):
    """The ``IERS_Auto`` table of a cache file; ValueError (saying why) when the file is not
    one this code wrote for ``versions``. Only data is read: ``allow_pickle=False``."""
    with open(path, "rb") as fh, np.load(fh, allow_pickle=False) as z:
        if not hasattr(z, "zip"):
            raise ValueError("it is not an archive of arrays")
        size = sum(info.file_size for info in z.zip.infolist())
        if size > MAX_CACHE_BYTES:  # the table is ~5 MB: not one this code wrote
            raise ValueError(f"it holds {size} bytes")
        if "manifest" not in z.files or "digest" not in z.files:
            raise ValueError("it has no manifest and digest")
        text, digest = str(z["manifest"][()]), str(z["digest"][()])
        arrays = {k: z[k] for k in z.files if k not in ("manifest", "digest")}
    if _digest(text, [arrays[k] for k in sorted(arrays)]) != digest:
        raise ValueError("its digest does not match its content")
    manifest = json.loads(text)
    if manifest.get("versions") != versions:
        raise ValueError(f"it was written for {manifest.get('versions')}")
    cols = []
    for i, (name, kind, unit) in enumerate(zip(manifest["names"], manifest["kinds"],
                                               manifest["units"], strict=True)):
        values = arrays[f"v{i}"]
        if kind == "quantity":
            cols.append(u.Quantity(values, unit, copy=False))
        elif kind == "masked":
            cols.append(MaskedColumn(values, name=name, mask=arrays[f"m{i}"], unit=unit))
        else:
            cols.append(Column(values, name=name, unit=unit))
    return iers.IERS_Auto(cols, names=manifest["names"], meta=manifest["meta"])


def use_cached_eop_table() -> None:
    """Make astropy's Earth-orientation table the bundled IERS one, read from the cache
    when there is one: parsing the bundled text tables costs ~0.7 s of every run, the cache
    a few hundredths. The cache is keyed by the astropy and astropy-iers-data versions and
    checked by its digest, so its content is exactly what astropy would read; a file that
    fails the check is rebuilt with a note, and a cache that cannot be written only costs
    time."""
    global _EOP_READY
    if _EOP_READY:
        return
    _EOP_READY = True
    versions = _versions()
    if versions is None:
        return  # let astropy find its tables its own way
    path = eop_cache_path(versions)
    table = None
    if path.exists():
        try:
            table = read_eop_cache(path, versions)
        except Exception as err:  # any failure: the cache is rebuilt, never trusted
            warnings.warn(Note(f"the Earth-orientation cache {path} was not written by "
                               f"antsim for these versions ({err}); rebuilt from astropy's "
                               "tables"), stacklevel=2)
    if table is None:
        table = iers.IERS_Auto.open()
        # a read-only or full cache only costs time
        with contextlib.suppress(OSError, TypeError, ValueError):
            write_eop_cache(table, versions, path)
    iers.earth_orientation_table.set(table)

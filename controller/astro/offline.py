"""The one place where astropy is told never to reach the network.

IERS tables come from the ``astropy-iers-data`` package. Importing this module is cheap: it
only sets configuration values and does not import astropy.coordinates.
"""

from astropy.utils import iers

iers.conf.auto_download = False
iers.conf.auto_max_age = None
# Dates beyond the bundled tables (future campaigns) fall back to zero corrections with a
# warning instead of an exception; 1990 is well inside IERS-B.
iers.conf.iers_degraded_accuracy = "warn"


_EOP_READY = False


def use_cached_eop_table() -> None:
    """Make astropy's Earth-orientation table the bundled IERS one, read from a pickle cache
    when there is one: parsing the bundled text tables costs ~0.7 s of every run, the cache
    ~0.04 s. The cache (``$ANTSIM_CACHE`` or ``~/.cache/antsim``) is keyed by the astropy
    and astropy-iers-data versions, so its content is exactly what astropy would read; any
    failure to read or write it falls back to astropy's own loading, silently."""
    global _EOP_READY
    if _EOP_READY:
        return
    _EOP_READY = True
    import os
    import pickle
    from importlib import metadata
    from pathlib import Path

    import astropy

    try:
        data_version = metadata.version("astropy-iers-data")
    except metadata.PackageNotFoundError:
        return  # let astropy find its tables its own way
    base = os.environ.get("ANTSIM_CACHE") or Path(
        os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "antsim"
    path = Path(base) / f"iers-auto-{astropy.__version__}-{data_version}.pickle"
    table = None
    try:
        with path.open("rb") as fh:
            table = pickle.load(fh)
        if not isinstance(table, iers.IERS_Auto):
            table = None
    except Exception:  # a missing, damaged or foreign cache is simply rebuilt
        table = None
    if table is None:
        table = iers.IERS_Auto.open()
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp = path.with_suffix(f".{os.getpid()}.tmp")
            with tmp.open("wb") as fh:
                pickle.dump(table, fh, protocol=pickle.HIGHEST_PROTOCOL)
            os.replace(tmp, path)
        except OSError:
            pass
    iers.earth_orientation_table.set(table)

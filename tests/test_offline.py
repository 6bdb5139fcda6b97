"""The IERS table cache of controller.astro.offline: same table, rebuilt when damaged."""

from __future__ import annotations

import os
import subprocess
import sys

SCRIPT = """
import numpy as np
from astropy.time import Time
from astropy.utils import iers
import controller.astro.offline as offline
offline.use_cached_eop_table()
t = Time(np.linspace(47000.0, 61000.0, 7), format="mjd")
print(type(iers.earth_orientation_table.get()).__name__,
      repr(iers.earth_orientation_table.get().ut1_utc(t).value.tolist()))
"""


def _run(cache_dir) -> str:
    env = {**os.environ, "ANTSIM_CACHE": str(cache_dir)}
    done = subprocess.run([sys.executable, "-c", SCRIPT], env=env, capture_output=True,
                          text=True, check=True)
    return done.stdout.strip()


def _astropy_own() -> str:
    script = SCRIPT.replace("offline.use_cached_eop_table()", "")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          check=True)
    return done.stdout.strip()


def test_cached_table_is_astropys_and_survives_damage(tmp_path):
    own = _astropy_own()
    assert own.startswith("IERS_Auto")
    assert _run(tmp_path) == own  # first use: astropy's loading, then written to the cache
    (cache,) = tmp_path.glob("iers-auto-*.npz")
    assert cache.stat().st_size > 100_000
    assert _run(tmp_path) == own  # read back from the cache: the same numbers
    cache.write_bytes(b"not a cache file")
    assert _run(tmp_path) == own  # damaged: rebuilt
    assert cache.stat().st_size > 100_000

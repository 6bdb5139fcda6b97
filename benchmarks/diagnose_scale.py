"""antsim diagnose on many observations: wall time and peak memory against 20 s and 700 MiB.

    python benchmarks/diagnose_scale.py [--n 200000] [--seed 28] [--keep DIR]

Writes a recordings file of ``--n`` scans (the polarization average only) made the quick way,
not simulated scan by scan: the 1990 run's eight sources at Green Bank, one scan every five
minutes (200,000 scans are 694 days), each of the highest source within 10..85 deg elevation
at its time (ephemeris from controller.astro), the 1990 report's Table 3 as the mount's
errors, an uneven azimuth track of 60" sin 2A in elevation (the demo's hidden effect, so that
diagnose has something to find), Gaussian noise of 20" (cross-elevation) and 30" (elevation),
air temperature and the Sun's elevation in their columns, and ghigo10 with zero coefficients
as the model in use (the baseline diagnose starts from). Then it runs ``antsim diagnose FILE
--no-cache --json`` and ``antsim fit FILE --json`` in child processes and prints each one's
wall time, CPU time (the child's user + system time: what the machine's load moves least) and
peak resident memory (the child's ``ru_maxrss``), and what diagnose named.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

TARGET_S = 20.0
TARGET_MIB = 700.0
TABLE3_ARCMIN = [-1.88, -0.17, -1.54, -2.16, 0.80, 12.24, 1.62, -0.35, -3.35, -1.79]
SCAN_S = 300.0
CHUNK = 100_000  # scans per ephemeris: 347 days
HIDDEN_ARCSEC = 60.0  # dE = 60" sin 2A_N (the demo's azimuth track unevenness)


def write_recordings(path: Path, n: int, seed: int) -> dict:
    """``n`` scans as recordings.ecsv (see the module); returns what was put in."""
    from astropy.table import Table
    from astropy.time import Time, TimeDelta

    from antsim.scenario import load_scenario
    from controller.astro.ephemeris import Ephemeris
    from controller.astro.site import Site
    from controller.astro.sources import FixedSource
    from controller.pointing.model import PointingModel
    from controller.program.recordings import COLUMNS
    from controller.units import ARCSEC_PER_RAD

    rng = np.random.default_rng(seed)
    scenario = load_scenario(ROOT / "scenarios" / "ghigo1990.toml")
    site = Site(scenario.site.latitude_deg, scenario.site.longitude_deg, scenario.site.height_m)
    sources = [FixedSource(s.name, s.ra_deg, s.dec_deg, s.frame) for s in scenario.sources]
    t_s = np.arange(n) * SCAN_S + 60.0
    epoch = Time(scenario.epoch_utc, scale="utc")
    az = np.empty((len(sources), n))
    el = np.empty((len(sources), n))
    sun_el = np.empty(n)
    for start in range(0, n, CHUNK):  # an ephemeris spans a year at most
        part = slice(start, min(n, start + CHUNK))
        t0 = float(t_s[start]) - 60.0
        ephemeris = Ephemeris(site, epoch + TimeDelta(t0, format="sec"),
                              CHUNK * SCAN_S + 120.0, sources)
        for k in range(len(sources)):
            az[k, part], el[k, part] = ephemeris.altaz_rad(k, t_s[part] - t0)
        sun_el[part] = np.degrees(ephemeris.sun_altaz_rad(t_s[part] - t0)[1])
    usable = np.where((el > math.radians(10)) & (el < math.radians(85)), el, -np.inf)
    pick = np.argmax(usable, axis=0)
    keep = np.isfinite(usable[pick, np.arange(n)])
    t_s, pick, sun_el = t_s[keep], pick[keep], sun_el[keep]
    az_rad, el_rad = az[pick, keep.nonzero()[0]], el[pick, keep.nonzero()[0]]
    truth = PointingModel("ghigo10").with_values(np.array(TABLE3_ARCMIN) * 60.0)
    d_az, d_el = truth.offset_rad(az_rad, el_rad)
    xel = d_az * np.cos(el_rad) * ARCSEC_PER_RAD + rng.normal(0.0, 20.0, t_s.size)
    e = (d_el * ARCSEC_PER_RAD + HIDDEN_ARCSEC * np.sin(2.0 * az_rad)
         + rng.normal(0.0, 30.0, t_s.size))
    m = t_s.size
    local_h = (t_s / 3600.0 + 12.0) % 24.0
    columns = {
        "scan": np.arange(m), "time": (epoch + TimeDelta(t_s, format="sec")).isot,
        "t_s": t_s, "source": np.array([s.name for s in sources])[pick],
        "polarization": np.full(m, "AVG"), "az_deg": np.degrees(az_rad) % 360.0,
        "el_deg": np.degrees(el_rad), "model_xel_arcmin": np.zeros(m),
        "model_el_arcmin": np.zeros(m), "applied_xel_arcmin": np.zeros(m),
        "applied_el_arcmin": np.zeros(m), "xel_arcmin": xel / 60.0, "el_arcmin": e / 60.0,
        "xel_width_arcmin": 11.0 + rng.normal(0.0, 0.1, m),
        "el_width_arcmin": 11.0 + rng.normal(0.0, 0.1, m), "good": np.ones(m, dtype=bool),
        "air_temp_c": 5.0 + 8.0 * np.sin(2 * math.pi * (local_h - 9.0) / 24.0),
        "sun_el_deg": sun_el, "slew_az": rng.choice([-1, 1], m),
        "slew_el": rng.choice([-1, 1], m),
    }
    units = {c.name: c.unit for c in COLUMNS}
    table = Table(columns, meta={
        "scenario": "diagnose_scale", "seed": seed,
        "site": {"name": site.name, "latitude_deg": site.latitude_deg,
                 "longitude_deg": site.longitude_deg, "height_m": site.height_m},
        "epoch_utc": scenario.epoch_utc, "duration_s": float(t_s[-1] + SCAN_S),
        "beam_hpbw_arcmin": 11.0,
        "model": {"name": "ghigo10", "terms_arcsec": PointingModel("ghigo10").as_dict(),
                  "w_terms": "Ghigo 1990 (NRAO EDIR 288) section II"},
    })
    for name, unit in units.items():
        if name in table.colnames and unit is not None:
            table[name].unit = unit
    table.write(path, format="ascii.ecsv", overwrite=True)
    return {"scans": m, "days": float(t_s[-1] / 86400.0)}


def run_child(args: list[str]) -> tuple[float, float, float, int, str, str]:
    """Wall time (s), CPU time (s, user + system), peak resident memory (MiB; both this
    child's own, from ``wait4``'s resource usage), exit status, stdout and stderr of
    ``python -m antsim ARGS``."""
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        start = time.perf_counter()
        proc = subprocess.Popen([sys.executable, "-m", "antsim", *args], stdout=out,
                                stderr=err, cwd=ROOT, text=True)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - start
        proc.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        cpu = usage.ru_utime + usage.ru_stime
        return wall, cpu, usage.ru_maxrss / 1024.0, proc.returncode, out.read(), err.read()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--n", type=int, default=200_000)
    parser.add_argument("--seed", type=int, default=28)
    parser.add_argument("--keep", type=Path, default=None,
                        help="write the recordings here (default: a temporary directory)")
    parser.add_argument("--write-only", type=Path, default=None, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.write_only:  # the child that writes the file (see below)
        print(json.dumps(write_recordings(args.write_only, args.n, args.seed)))
        return 0
    folder = args.keep or Path(tempfile.mkdtemp(prefix="diagnose_scale"))
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "recordings.ecsv"
    start = time.perf_counter()
    # written in a child of its own: a child started from this process counts this
    # process's peak memory as its own (exec records the memory it leaves; making 200,000
    # scans peaks at ~740 MiB, which ``antsim fit`` then reported as its peak)
    made = json.loads(subprocess.run(
        [sys.executable, __file__, "--n", str(args.n), "--seed", str(args.seed),
         "--write-only", str(path)], check=True, capture_output=True, text=True).stdout)
    print(f"{path}: {made['scans']} scans over {made['days']:.0f} days "
          f"({path.stat().st_size / 2**20:.0f} MiB), written in "
          f"{time.perf_counter() - start:.1f} s")
    wall, cpu, mib, status, stdout, stderr = run_child(["diagnose", str(path), "--no-cache",
                                                   "--json", "--no-progress"])
    if status != 0:
        print(stderr)
        return 1
    found = json.loads(stdout)
    named = [f["effect"] for f in found["findings"]]
    print(f"antsim diagnose: {wall:.1f} s wall ({cpu:.1f} s CPU), peak {mib:.0f} MiB "
          f"(targets {TARGET_S:g} s, {TARGET_MIB:g} MiB: "
          f"{'met' if wall <= TARGET_S and mib <= TARGET_MIB else 'NOT met'})"
          f"; named {', '.join(named) or 'nothing'}")
    wall, cpu, mib, status, _, stderr = run_child(["fit", str(path), "--json", "--no-progress"])
    print(f"antsim fit:      {wall:.1f} s wall ({cpu:.1f} s CPU), peak {mib:.0f} MiB"
          if status == 0 else stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

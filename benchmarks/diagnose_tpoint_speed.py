"""antsim diagnose on a 100-star TPOINT file: the whole command, its nested validation and
stability resamples included, against 10 s.

    python benchmarks/diagnose_tpoint_speed.py [--stars 100] [--repeats 5]

The file: ``--stars`` positions uniform over the sky between 15 and 85 deg of elevation
(seed 1), TPOINT's eight terms at the MMT's values (examples/README.md), an azimuth track
with two high points (HESA2 1.0", HECA2 0.5": something to find) and 1" of noise per axis,
written as a TPOINT data file. ``antsim diagnose FILE`` runs in a child process
``--repeats`` times (Python's start-up and imports included); printed: the median and the
range of the wall times, and what was named. The real files of examples/ (44 and 80 stars)
are timed the same way.
"""

from __future__ import annotations

import argparse
import math
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from antsim.diagnose.data import Observations  # noqa: E402
from antsim.diagnose.problem import term_columns  # noqa: E402
from controller.pointing.tpoint import RunParameters, TPointData, write_tpoint  # noqa: E402

TARGET_S = 10.0
#: TPOINT's fit of the MMT file (examples/README.md), arcsec, and the hidden track
TERMS = {"IA": 1209.26, "IE": -2.99, "NPAE": -3.47, "CA": -5.95, "AN": 2.50, "AW": -10.33,
         "TF": 21.41, "TX": -2.72, "HESA2": 1.0, "HECA2": 0.5}
LATITUDE_DEG = 31.69


def write_file(path: Path, stars: int, seed: int = 1) -> None:
    """The benchmark's TPOINT file (see the module docstring)."""
    rng = np.random.default_rng(seed)
    az = rng.uniform(0.0, 2 * math.pi, stars)
    el = np.arcsin(rng.uniform(math.sin(math.radians(15.0)), math.sin(math.radians(85.0)),
                               stars))
    geo = Observations(t_s=np.arange(stars, dtype=float), az_rad=az, el_rad=el,
                       xel_arcsec=np.zeros(stars), el_arcsec=np.zeros(stars),
                       good=np.ones(stars, bool), meta={"latitude_deg": LATITUDE_DEG},
                       kind="tpoint")
    err = term_columns(list(TERMS), geo) @ np.array(list(TERMS.values()))
    err += rng.normal(0.0, 1.0, 2 * stars)
    # indicated minus true: the raw (encoder) position is the observed one plus the error
    az_raw = np.degrees(az) + err[:stars] / 3600.0 / np.cos(el)
    el_raw = np.degrees(el) + err[stars:] / 3600.0
    data = TPointData.from_azel("diagnose speed benchmark", RunParameters(LATITUDE_DEG),
                                np.degrees(az), np.degrees(el), az_raw, el_raw,
                                options=("ALTAZ",))
    write_tpoint(data, path)


def timed(path: Path, repeats: int) -> tuple[list[float], str]:
    """Wall times of ``antsim diagnose FILE`` in a child process, and its first finding."""
    times, named = [], "nothing"
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = subprocess.run([sys.executable, "-m", "antsim", "diagnose", str(path)],
                             check=True, capture_output=True, text=True).stdout
        times.append(time.perf_counter() - t0)
        first = [line for line in out.splitlines() if line.startswith("1. ")]
        named = first[0].split(":")[0][3:] if first else "nothing"
    return times, named


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--stars", type=int, default=100)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"stars{args.stars}.dat"
        write_file(path, args.stars)
        files = [(f"{args.stars} stars (made)", path),
                 ("auxtel_20200315.dat (44 stars)", ROOT / "examples" / "auxtel_20200315.dat"),
                 ("mmt_20210821_k_and_e.dat (80 stars)",
                  ROOT / "examples" / "mmt_20210821_k_and_e.dat")]
        for label, p in files:
            times, named = timed(p, args.repeats)
            median = statistics.median(times)
            verdict = f" (target {TARGET_S:.0f} s: {'met' if median <= TARGET_S else 'NOT met'})" \
                if p == path else ""
            print(f"{label}: median {median:.2f} s ({min(times):.2f}-{max(times):.2f} s over "
                  f"{len(times)} runs){verdict}; named {named}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

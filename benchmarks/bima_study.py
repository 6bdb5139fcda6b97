"""BIMA memo 23's study (Wright 1992), reproduced: linear equations against an exact tilt.

    python benchmarks/bima_study.py [--tilt-az DEG] [--el-max DEG]

Generates noise-free pointing data on an azimuth/elevation grid (every 10 deg of azimuth,
elevation 10..85 deg every 5 deg) from an exact azimuth-axis tilt and collimation (rotations,
the memo's equations (3) and (4); antsim.world.effects.optics.ExactTiltCollimation), fits the
memo's linear 7 + 7 term equations (1) and (2) by least squares, and prints the memo's
quantities:

1. the residual rms for 6' of tilt (towards azimuth 90 deg: assumption) and 9' of collimation,
   per axis and in total, and where the residuals grow: rms per elevation band, rms per
   azimuth above 70 deg elevation, and the worst point;
2. the rms for smaller tilts and collimations: a 1' tilt (with the 9' collimation) or 5' of
   collimation (with the 6' tilt) leaves about 1";
3. the interferometer delay D cos(E) of non-intersecting axes for a 1 cm axis offset.

No randomness; it runs in about a second. The figures are checked in tests/test_bima.py.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

# Imported after the path set-up so that the script runs from a source checkout.
from antsim.studies.memo23 import axis_offset_delay_s, memo23_study


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tilt-az", type=float, default=90.0,
                        help="azimuth the axis tilts towards (deg, N = 0; default 90)")
    parser.add_argument("--el-max", type=float, default=85.0,
                        help="highest elevation of the grid (deg; default 85)")
    args = parser.parse_args(argv)
    t0 = time.perf_counter()

    study = memo23_study(6.0, 9.0, args.tilt_az, el_max_deg=args.el_max)
    fit = study.fit
    print("BIMA memo 23 study: exact tilt 6' (towards az "
          f"{args.tilt_az:g} deg) and collimation 9', linear equations (1) and (2) fitted")
    print(f"  grid: {study.az_deg.size} points, az 0..350 every 10 deg, el 10..{args.el_max:g}")
    print(f"  residual rms: xel {fit.xel_rms_arcsec:.2f}\", el {fit.el_rms_arcsec:.2f}\", "
          f"total {fit.sky_rms_arcsec:.2f}\"")
    az_w, el_w, r_w = study.worst()
    print(f"  worst point: az {az_w:.0f} deg, el {el_w:.0f} deg: {r_w:.1f}\"")
    print("  rms by elevation (deg: arcsec):")
    by_el = study.rms_by("el")
    print("    " + "  ".join(f"{e:.0f}: {r:.2f}" for e, r in by_el.items()))
    print("  rms by azimuth above 70 deg elevation (deg: arcsec):")
    by_az = study.rms_by("az", el_min_deg=70.0)
    print("    " + "  ".join(f"{a:.0f}: {r:.1f}" for a, r in by_az.items() if a % 30 == 0))

    print("\nTotal residual rms (arcsec) for other tilts (rows) and collimations (columns):")
    collims = (0.0, 2.0, 5.0, 9.0)
    print("  tilt \\ coll " + "".join(f"{c:>8.0f}'" for c in collims))
    for tilt in (0.0, 1.0, 2.0, 4.0, 6.0):
        cells = [memo23_study(tilt, c, args.tilt_az, el_max_deg=args.el_max).sky_rms_arcsec
                 for c in collims]
        print(f"  {tilt:>10.0f}' " + "".join(f"{v:>9.2f}" for v in cells))
    one = memo23_study(1.0, 9.0, args.tilt_az, el_max_deg=args.el_max).sky_rms_arcsec
    five = memo23_study(6.0, 5.0, args.tilt_az, el_max_deg=args.el_max).sky_rms_arcsec
    print(f"  1' tilt with 9' collimation: {one:.2f}\"; 5' collimation with 6' tilt: "
          f"{five:.2f}\" (memo: about 1\")")

    print("\nInterferometer delay of non-intersecting axes, D cos(E), for D = 1 cm:")
    el = np.array([10.0, 30.0, 50.0, 70.0, 90.0])
    delay = axis_offset_delay_s(0.01, np.radians(el)) * 1e12
    print("  " + "  ".join(f"E {e:.0f}: {d:.2f} ps" for e, d in zip(el, delay, strict=True)))
    print(f"\n({time.perf_counter() - t0:.2f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

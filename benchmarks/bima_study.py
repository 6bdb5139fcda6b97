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
3. the interferometer delay D cos(E) of non-intersecting axes for a 1 cm axis offset;
4. the night of 11-12 May 1992 (the scenario): the 6" rms, Table 1 against the fit, and
   the fit without b(6) (the sin 2Az term) with its F test.

The study has no randomness; the night is the scenario's seed 3. About 3 s. The figures are
checked in tests/end_to_end/test_bima.py.
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
    memo_run()
    print(f"\n({time.perf_counter() - t0:.2f} s)")
    return 0


def memo_run() -> None:
    """The night of 11-12 May 1992 (scenarios/wright1992_bima_ant5.toml) beside the memo."""
    import json
    import tempfile

    from antsim.cli import main as cli
    from antsim.studies.memo23 import TABLE1_ANT5, term_significance
    from controller.pointing.bima import WRIGHT_TERMS
    from controller.pointing.variants import VARIANTS, columns, pointing_data, variant_mask
    from controller.program.recordings import read_recordings

    scenario = Path(__file__).resolve().parents[1] / "scenarios" / "wright1992_bima_ant5.toml"
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        cli(["run", str(scenario), "--out", str(out), "--no-report"])
        fit = json.loads((out / "fit.json").read_text())
        cols = columns(read_recordings(out / "recordings.ecsv"))
    data = pointing_data(cols, variant_mask(cols, VARIANTS[0]))
    print("\nAntenna 5, 11-12 May 1992 (memo | ours):")
    print(f"  rms residual: 6\" | Sky RMS {fit['sky_rms_arcsec']:.1f}\" (xel "
          f"{fit['xel_rms_arcsec']:.1f}\", el {fit['el_rms_arcsec']:.1f}\") on "
          f"{fit['n_used']} stars")
    print("  Table 1 (arcmin) | fitted +- sigma:")
    for name in WRIGHT_TERMS:
        e = fit["terms"][name]
        print(f"    {name.lower()[0]}({name[1]}) {TABLE1_ANT5[name]:7.2f} | "
              f"{e['value_arcsec'] / 60:7.3f} +- {e['sigma_arcsec'] / 60:.3f}")
    t = term_significance(data, WRIGHT_TERMS, "B6", np.sin(2 * data.az_rad))
    print(f"  without b(6) 'significantly worse': el rms {t.el_rms_with_arcsec:.1f}\" -> "
          f"{t.el_rms_without_arcsec:.1f}\", Sky RMS {t.sky_rms_with_arcsec:.1f}\" -> "
          f"{t.sky_rms_without_arcsec:.1f}\", F = {t.f_statistic:.0f} (p {t.p_value:.1e}); "
          f"residual vs sin 2Az: r = {t.correlation:.2f}")
    tilt_a = float(np.hypot(TABLE1_ANT5["A4"], TABLE1_ANT5["A5"]))
    tilt_b = float(np.hypot(TABLE1_ANT5["B4"], TABLE1_ANT5["B5"]))
    print(f"  tilt: text 6' | Table 1 a(4),a(5) {tilt_a:.2f}', b(4),b(5) {tilt_b:.2f}' "
          f"(simulated: {tilt_b:.2f}'); collimation: text 9' | a(2) {TABLE1_ANT5['A2']:.2f}'")


if __name__ == "__main__":
    raise SystemExit(main())

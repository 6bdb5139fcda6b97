"""Crane (1981, NRAO Engineering Memo 147) reproduced: the 140-ft's three calibration runs.

    python benchmarks/crane1981.py [--seed N] [--keep DIR] [--no-coverage]

Runs scenarios/crane1981_140ft_{3245,4990,10500}.toml (72, 96 and 72 simulated hours, a few
seconds each) and prints, beside the memo's numbers:

1. numbers of points (all and night) and rms per point in RA and Dec (Table 4);
2. the fitted C1..C11 with their errors, the injected truth (Table 4) and the pull;
3. the standard-error pattern: our standard errors (the run's schedule and rms, each axis
   weighted by its own rms) over Table 4's, outside the rounding of its last digit, for the
   chosen definitions of C1..C11 and the alternatives (controller.pointing.crane.CANDIDATES);
   the chosen ones fitted as plain least squares (fit A); the best C7..C11 of a search over
   the declination functions; C6's variance inflation, memo and ours; and (unless
   ``--no-coverage``) the three runs again with hour angles to +-7 h;
4. day and night: the night-minus-all differences as a chi-square (memo and ours);
5. the subreflector offset of 4990 MHz: C1 and C6 against the other bands;
6. the declination limit (no data above 72 deg);
7. Table 5's gain curves: ours (per feed at 3245, corrected and uncorrected at 10500) and the
   tipping opacity against the one Table 5 implies (0.0228).
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

# Imported after the path set-up so that the script runs from a source checkout.
from antsim.cli import main as cli
from antsim.scenario import load_scenario
from antsim.studies.crane1981 import (
    BANDS,
    DEC_LIBRARY,
    TABLE4,
    TABLE5,
    Dataset,
    channel_gain,
    difference_chi2,
    good_rows,
    rounding_ratio,
    search_declination_terms,
    sigma_pattern,
    table4_datasets,
    worst_factor,
)
from controller.pointing.crane import CANDIDATES, CRANE_NAMES
from controller.program.recordings import read_recordings
from controller.scans.gaincurve import HARMONIC_NAMES

REPO = Path(__file__).resolve().parents[1]


def scenario_path(band: int) -> Path:
    return REPO / "scenarios" / f"crane1981_140ft_{band}.toml"


def run(band: int, out: Path, seed: int | None, ha_limit_deg: float | None = None) -> dict:
    """Run a band's scenario (``ha_limit_deg``: with the mount's hour angles to +-that)."""
    path = scenario_path(band)
    if ha_limit_deg is not None:
        text = re.sub(r"(\[mount\.ha\][^[]*?)min_deg = -?[0-9.]+\nmax_deg = [0-9.]+",
                      rf"\g<1>min_deg = {-ha_limit_deg}\nmax_deg = {ha_limit_deg}",
                      path.read_text(encoding="utf-8"))
        out.mkdir(parents=True, exist_ok=True)
        path = out.parent / f"{out.name}.toml"
        path.write_text(text, encoding="utf-8")
    args = ["run", str(path), "--out", str(out), "--no-report"]
    if seed is not None:
        args += ["--seed", str(seed)]
    if cli(args) != 0:
        raise SystemExit(f"antsim run failed for {band} MHz")
    table = read_recordings(out / "recordings.ecsv")
    cols = {c: np.asarray(table[c]) for c in table.colnames}
    return {"fit": json.loads((out / "fit.json").read_text()),
            "truth": json.loads((out / "truth.json").read_text()),
            "variants": json.loads((out / "fit_variants.json").read_text()),
            "gain": json.loads((out / "gaincurve.json").read_text()), "cols": cols}


def c_truth(band: int) -> dict[str, float]:
    """Injected C1..C11 in arcmin (C5: the refraction_anomaly's scale)."""
    truth = load_scenario(scenario_path(band)).truth_arcsec(CRANE_NAMES)
    return {n: v / 60.0 for n, v in truth.items()}


def table(title: str, data: list[Dataset], lat: float, **options) -> None:
    """Ours over the memo's standard errors, per data set, and the worst factor."""
    ratios = [rounding_ratio(sigma_pattern(d.ha_rad, d.dec_rad, d.xel_rms_arcsec,
                                           d.dec_rms_arcsec, lat, **options), d.memo_sigma)
              for d in data]
    print(f"   {title}: worst factor {max(worst_factor(r) for r in ratios):.2f}")
    print("                 " + " ".join(f"{n:>4s}" for n in CRANE_NAMES))
    for d, r in zip(data, ratios, strict=True):
        print(f"     {d.label:11s} " + " ".join(f"{x:4.2f}" for x in r))


def c6_needs(data: list[Dataset], lat: float) -> None:
    """C6's variance inflation (its variance over a lone constant's, rms^2 / N) in the memo
    and ours, and the terms it is most correlated with in ours."""
    print("   C6 (dDec = 1): variance inflation memo / ours; ours' largest correlations")
    for d in data:
        n = d.ha_rad.size
        lone = d.dec_rms_arcsec / np.sqrt(n) / 60.0  # a constant alone (arcmin)
        memo_n = TABLE4[int(d.label.split()[0])][d.label.split()[1]]["n"]
        memo_lone = TABLE4[int(d.label.split()[0])][d.label.split()[1]]["rms"][1] \
            / np.sqrt(memo_n) / 60.0
        cov = crane_covariance(d, lat)
        s = np.sqrt(np.diag(cov))
        corr = cov[5] / (s[5] * s)
        top = np.argsort(-np.abs(corr))[1:5]
        print(f"     {d.label:11s} {(d.memo_sigma[5] / memo_lone) ** 2:5.0f} / "
              f"{(s[5] / lone) ** 2:5.0f}; "
              + ", ".join(f"{CRANE_NAMES[j]} {corr[j]:+.2f}" for j in top))


def crane_covariance(d: Dataset, lat: float) -> np.ndarray:
    """The covariance (arcmin^2) of the chosen C1..C11 on a data set (per-axis weights)."""
    from controller.pointing.crane import crane_terms
    from controller.pointing.terms import evaluate_basis

    b_h, b_d = evaluate_basis(crane_terms(lat), d.ha_rad, d.dec_rad)
    a = np.vstack([b_h * np.cos(d.dec_rad)[:, None] / d.xel_rms_arcsec,
                   b_d / d.dec_rms_arcsec])
    return np.linalg.inv(a.T @ a) / 3600.0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=None, help="seed (default: scenarios')")
    parser.add_argument("--keep", type=Path, default=None, help="write the runs here")
    parser.add_argument("--no-coverage", dest="coverage", action="store_false",
                        help="leave out the runs with hour angles to +-7 h")
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        base = args.keep or Path(tmp)
        runs = {b: run(b, base / str(b), args.seed) for b in BANDS}
        report(runs, base, args.seed, args.coverage)
    print(f"\n({time.perf_counter() - t0:.1f} s)")
    return 0


def report(runs: dict, base: Path, seed: int | None, coverage: bool) -> None:
    """Print the comparisons (sections 1-7 of the module docstring)."""
    lat = load_scenario(scenario_path(3245)).site.latitude_deg
    night_deg = {b: load_scenario(scenario_path(b)).controller.night_sun_max_deg for b in BANDS}

    print("1. Points and rms per point (Table 4; night: the scenarios' (Sun below "
          f"{night_deg[3245]:g} deg), [Sun below -12 deg])")
    print("   MHz   N memo/ours   night memo/ours [-12]   RA rms memo/ours   Dec rms memo/ours")
    for b, r in runs.items():
        fit, cols = r["fit"], r["cols"]
        night_12 = int(np.sum(good_rows(cols, -12.0)))
        memo = TABLE4[b]
        night = r["variants"]["E"]
        mn = memo.get("night", {}).get("n", "-")
        print(f"   {b:5d}   {memo['all']['n']:4d} / {fit['n_used']:4d}"
              f"      {mn!s:>4} / {night['n_used']:4d} [{night_12}]"
              f"           {memo['all']['rms'][0]:5.1f} / {fit['xel_rms_arcsec']:5.1f}"
              f"        {memo['all']['rms'][1]:5.1f} / {fit['el_rms_arcsec']:5.1f}")
        if "night" in memo:
            print(f"           night rms: RA {memo['night']['rms'][0]:.1f} / "
                  f"{night['xel_rms_arcsec']:.1f}, Dec {memo['night']['rms'][1]:.1f} / "
                  f"{night['el_rms_arcsec']:.1f}")

    print("\n2. C1..C11 (arcmin): memo (Table 4, all) | ours +- TPOINT sigma | truth | pull")
    for b, r in runs.items():
        truth = c_truth(b)
        print(f"   {b} MHz")
        for name, (mv, ms) in zip(CRANE_NAMES, TABLE4[b]["all"]["c"], strict=True):
            e = r["fit"]["terms"][name]
            v, s = e["value_arcsec"] / 60.0, e["sigma_arcsec"] / 60.0
            print(f"     {name:4s} {mv:6.2f} +- {ms:.2f} | {v:7.3f} +- {s:.3f} | "
                  f"{truth[name]:6.2f} | {(v - truth[name]) / s:5.2f}")

    print("\n3. Standard errors against Table 4's (ours / memo's rounding interval; 1 = inside)")
    data = table4_datasets(runs, night_deg)
    for definition in CANDIDATES:
        table(f"{definition}", data, lat, definition=definition)
    table("crane1981 fitted as plain least squares (fit A: both axes alike)", data, lat,
          weighted=False)
    print("   Declination terms C7..C11 searched over "
          f"{', '.join(DEC_LIBRARY)} (C1..C6 as chosen); best:")
    for worst, definition in search_declination_terms(data, lat):
        print(f"     worst factor {worst:.2f}: C7..C11 = {', '.join(definition[6:])}")
    c6_needs(data, lat)
    if coverage:
        print("   Hour angles to +-7 h (the memo's maps span -7..+7 h; ours +-6 h):")
        wide = {b: run(b, base / f"{b}-ha7", seed, ha_limit_deg=105.0) for b in BANDS}
        table("crane1981, HA +-7 h", table4_datasets(wide, night_deg), lat)

    print("\n4. Day and night: night minus all, chi-square (11 dof) and P(larger)")
    for b, r in runs.items():
        if "night" not in TABLE4[b]:
            print(f"   {b}: the memo has no night fit (too few night points)")
            continue
        memo = difference_chi2(TABLE4[b]["all"]["c"], TABLE4[b]["night"]["c"])
        ours_all = [(r["fit"]["terms"][n]["value_arcsec"] / 60, r["fit"]["terms"][n]
                     ["sigma_arcsec"] / 60) for n in CRANE_NAMES]
        e = r["variants"]["E"]["terms"]
        ours_night = [(e[n]["value_arcsec"] / 60, e[n]["sigma_arcsec"] / 60)
                      for n in CRANE_NAMES]
        ours = difference_chi2(ours_all, ours_night)
        print(f"   {b}: memo chi2 {memo[0]:.1f} (P {memo[2]:.2f}); ours {ours[0]:.1f} "
              f"(P {ours[2]:.2f})")

    print("\n5. The 4990 MHz subreflector offset: C1 and C6 (arcmin)")
    for b, r in runs.items():
        t = r["fit"]["terms"]
        m = TABLE4[b]["all"]["c"]
        print(f"   {b:5d}: memo C1 {m[0][0]:5.2f} C6 {m[5][0]:6.2f}; ours C1 "
              f"{t['C1']['value_arcsec'] / 60:5.2f} C6 {t['C6']['value_arcsec'] / 60:6.2f}")

    print("\n6. No data above +72 deg (the control program's limit)")
    for b, r in runs.items():
        cols = r["cols"]
        above = sorted({str(s) for s, d in zip(cols["source"], cols["dec_deg"], strict=True)
                        if float(d) > 72.0})
        listed = [s.name for s in load_scenario(scenario_path(b)).sources if s.dec_deg > 72.0]
        print(f"   {b}: highest declination pointed {np.max(cols['dec_deg'].astype(float)):.2f}"
              f" deg; sources above 72 listed {len(listed)}, pointed {len(above)}")

    print("\n7. Gain curves (K/Jy): Table 5 | ours")
    r = runs[3245]
    flux = {s.name: s.flux_jy for s in load_scenario(scenario_path(3245)).sources}
    for memo_key, channel in (("3245 feed 1", "F2"), ("3245 feed 2", "F1")):
        g = channel_gain(r["cols"], channel, flux, 8.93)
        memo = TABLE5[memo_key]["y"][0]
        print(f"   {memo_key} (channel {channel}): Y00 {memo[0]:.4f} +- {memo[1]:.4f} | "
              f"{g.values[0]:.4f} +- {g.sigma[0]:.4f} (Y10..Y11O {np.round(g.values[1:], 4)})")
    for b, memo_key in ((4990, "4990"), (10500, "10500 corrected")):
        gain = runs[b]["gain"]["gain_curve"]
        memo = TABLE5[memo_key]["y"]
        cells = [f"{n} {m[0]:.4f}+-{m[1]:.4f} | {gain['coefficients_k_per_jy'][n]:.4f}+-"
                 f"{gain['sigma_k_per_jy'][n]:.4f}" for n, m in zip(HARMONIC_NAMES, memo,
                                                                    strict=True)]
        print(f"   {memo_key}: " + "; ".join(cells))
    r = runs[10500]
    flux = {s.name: s.flux_jy for s in load_scenario(scenario_path(10500)).sources}
    unc = channel_gain(r["cols"], "AVG", flux, 2.76, 0.0)
    memo = TABLE5["10500 uncorrected"]["y"]
    print("   10500 uncorrected: " + "; ".join(
        f"{n} {m[0]:.4f}+-{m[1]:.4f} | {v:.4f}+-{s:.4f}"
        for n, m, v, s in zip(HARMONIC_NAMES, memo, unc.values, unc.sigma, strict=True)))
    tau = r["gain"]["zenith_opacity"]
    print(f"   10500 tipping opacity {tau['value']:.4f} +- {tau['sigma']:.4f} from "
          f"{tau['from']}; Table 5 implies 0.0228; injected {r['truth']['zenith_opacity']}")


if __name__ == "__main__":
    raise SystemExit(main())

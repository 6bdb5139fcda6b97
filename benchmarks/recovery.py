"""Recovery of the injected W1..W10 over many seeds: are the error bars honest?

    python benchmarks/recovery.py [--seeds 200] [--first 1] [--jobs 2] [--scenario PATH]
                                  [--sensors PATH]

For seeds FIRST..FIRST+N-1 (default 1..200) of the scenario (default
``scenarios/ghigo1990.toml``), each seed another antenna of the kind (its own pattern of
repeatable irregularities, :func:`antenna_of`), it simulates the campaign, fits fit A, and
prints per term against the truth (the mount's W's plus what the terms make of the
atmosphere's refraction, which the controller does not correct): the bias (mean of fitted -
true), the seed-to-seed standard deviation, the mean of TPOINT's sigma
and of the honest (cluster-robust) sigma, the spread of the pulls (fitted - true)/sigma and
the fraction within 3 sigma, for both sigma
definitions. Targets: pull spread within 0.85..1.15 and >= 99% within 3 sigma.

It runs three cases. (1) The scenario as calibrated. The thermal distortion of a sunny day is
nearly the same every day, so it shifts some W's identically in every seed: the fitted W's
are then the pointing model of a clear February day, not the bare mount geometry, and no error
bar computed from one campaign can cover that shift. (2) The same with its thermal effect
removed: the fitter's statistics where the model is complete. (3) The scenario as calibrated,
with the heating modelled: each scan's systematic error (total error minus the true mount
geometry, averaged over calibration campaigns of other seeds; the schedule is deterministic,
so scans match one to one) is subtracted before the fit, as an observatory subtracts a
thermal model driven by structure temperatures. The average is over 64 campaigns: an
observatory's thermal model carries no scan's measurement noise, and the mean of 8 carried
1/8 of one campaign's into every fitted seed alike, which the jackknife counts as error but
the seed-to-seed spread does not (W6 and W10 then spread by 0.84 for an error bar 16% too
large; with 64, 0.90-0.91).

Then the two ways an observatory has. (4) The scenario with structure temperature
sensors (default ``scenarios/ghigo1990_sensors.toml``: the same world, noise and seeds, plus
thermometers with noise, resolution, lag and a partial view): fit T, fit A with the thermal
terms the data support in the sensors' temperatures, corrected for their response time: the
six pair terms as one group, entering together when an F test of the group says the data
support them (``controller.pointing.variants.thermal_fit`` says why). Targets: every W
within 3 honest sigma in >= 99% of seeds, mean pull within +-0.3, pull spread 0.85-1.15;
fit D's elevation rms (with fit T's terms) within 15% of fit E's. The same scenario without
thermal bending, twice (without the thermal effect: an isothermal structure; and heated as
before with every arcsec per kelvin 0): how often the group enters where it should not (the
test's nominal false-alarm rate is 0.5%), and fit D / fit E there, the floor that the wind by
day sets (the scenario's wind is stronger by day), beside the ratio without heating of case
(2). It also fits the thermal terms without the response-time correction (what the sensors'
lag alone does) and with all six pair terms fitted without any test, and prints how often
the thermal terms were selected and how well their coefficients are recovered. (5) Without
sensors, fit T on case (1)'s campaigns, with proxies (the Sun, the air temperature): the bias
per W before (fit A) and after, and how often each proxy enters on case (2)'s campaigns
(no heating). (6) Fit A's day-minus-night warning (fits D - E beyond 3 sigma): how often it
fires per term with the heating (case 1) and without (case 2).
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from multiprocessing import Pool
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from antsim.run.outputs import run_fits  # noqa: E402
from antsim.scenario import Scenario, load_scenario  # noqa: E402
from antsim.simulate.equivalents import refraction_equivalent_arcsec  # noqa: E402
from antsim.simulate.runner import simulate  # noqa: E402
from controller.pointing.fitting import fit_model  # noqa: E402
from controller.pointing.model import named_model_terms  # noqa: E402
from controller.pointing.selection import ALPHA  # noqa: E402
from controller.pointing.thermal import SENSOR_FAMILY, THERMAL_TERMS  # noqa: E402
from controller.pointing.variants import (  # noqa: E402
    VARIANTS,
    columns,
    pointing_data,
    thermal_fit,
    variant_mask,
)


def without(scenario: Scenario, effect: str) -> Scenario:
    return replace(scenario, effects=tuple(e for e in scenario.effects if e.name != effect))


def antenna_of(scenario: Scenario, seed: int) -> Scenario:
    """The scenario with an antenna of its own for campaign ``seed``: its repeatable
    irregularities (encoders, gears, track) drawn for the seed (``pattern_seed``). One
    antenna's pattern is the same in every campaign, a bias no error bar of one campaign can
    reveal by repeating it; over antennas of the kind it is a random error, and an honest
    error bar covers it: each seed here is another antenna."""
    def own(e):
        return replace(e, params={**e.params, "pattern_seed": 10_000.0 + seed})
    return replace(scenario, effects=tuple(own(e) if e.name == "irregularities" else e
                                           for e in scenario.effects))


def unbent(scenario: Scenario) -> Scenario:
    """The scenario with its structure heated as before but not bending: the steel's
    expansion 0, so every pointing per kelvin is 0 (the sensors read the same
    temperatures)."""
    def zero(e):
        return replace(e, params={**e.params, "expansion_per_k": 0.0})
    return replace(scenario, effects=tuple(zero(e) if e.name == "thermal" else e
                                           for e in scenario.effects))


CALIBRATION_SEEDS = range(100_001, 100_065)


def systematic_errors(rows, truth) -> dict[int, tuple[float, float]]:
    """Per scan (AVG row): total pointing error minus the true geometric model (arcsec)."""
    out = {}
    for r in rows:
        if r["polarization"] != "AVG":
            continue
        az, el = np.radians(r["az_deg"]), np.radians(r["el_deg"])
        d_az, d_el = truth.offset_rad(az, el)
        xel = 60.0 * (r["xel_arcmin"] + r["model_xel_arcmin"] + r["applied_xel_arcmin"])
        eln = 60.0 * (r["el_arcmin"] + r["model_el_arcmin"] + r["applied_el_arcmin"])
        out[r["scan"]] = (xel - float(d_az) * np.cos(el) * 206264.806,
                          eln - float(d_el) * 206264.806)
    return out


def calibrate(scenario: Scenario, workers: int,
              seeds: range = CALIBRATION_SEEDS) -> dict[int, tuple[float, float]]:
    """Mean systematic error per scan over the calibration campaigns."""
    jobs = [(scenario, s) for s in seeds]
    if workers > 1:
        with Pool(workers) as pool:
            per_seed = pool.map(_systematics_of_seed, jobs)
    else:
        per_seed = [_systematics_of_seed(j) for j in jobs]
    scans = set.intersection(*(set(p) for p in per_seed))
    return {k: tuple(np.mean([p[k] for p in per_seed], axis=0)) for k in scans}


def _systematics_of_seed(args):
    scenario, seed = args
    scenario = antenna_of(scenario, seed)
    return systematic_errors(simulate(scenario, seed=seed).rows, scenario.truth_model)


def terms_of(terms) -> tuple[str, ...]:
    """Term names of a named model or a list."""
    return named_model_terms(terms) if isinstance(terms, str) else tuple(terms)


def fit_seed(args) -> dict:
    """One campaign: fit A's values and sigmas; without a correction also fit T's, the
    terms fit A warns of (day minus night), fits D and E's elevation rms, and with sensors
    fit D with fit T's terms and fit T without the sensors' response-time correction."""
    scenario, seed, correction = args
    scenario = antenna_of(scenario, seed)
    result = simulate(scenario, seed=seed)
    names = scenario.truth_model.names
    truth = scenario.truth_model.as_dict()
    if correction is None:  # and what the ten terms make of the atmosphere's refraction
        refraction = refraction_equivalent_arcsec(result.rows, names,
                                                  scenario.receiver.frequency_ghz)
        recoverable = np.array([truth[n] + refraction[n] for n in names])
    else:  # the correction took it out with the rest of each scan's mean systematic error
        recoverable = np.array([truth[n] for n in names])
    if correction is not None:
        rows = []
        for r in result.rows:
            if r["scan"] not in correction:
                continue
            s_xel, s_el = correction[r["scan"]]
            rows.append({**r, "xel_arcmin": r["xel_arcmin"] - s_xel / 60.0,
                         "el_arcmin": r["el_arcmin"] - s_el / 60.0})
        result.rows = rows
    fits = run_fits(result)
    a = fits["A"]
    out = {"A": (a.values_arcsec, a.sigma_arcsec, a.sigma_honest_arcsec),
           "recoverable": recoverable}
    if correction is not None:
        return out
    m = len(scenario.truth_model.names)
    t = fits["T"]
    out["T"] = (t.values_arcsec[:m], t.sigma_arcsec[:m], t.sigma_honest_arcsec[:m])
    out["thermal"] = {n: (float(v), float(h)) for n, v, h in
                      zip(t.names[m:], t.values_arcsec[m:], t.sigma_honest_arcsec[m:],
                          strict=True)}
    out["warned"] = [w.split(":")[0] for w in a.warnings if "day minus night" in w]
    out["rms"] = (fits["D"].el_rms_arcsec, fits["E"].el_rms_arcsec)
    c = scenario.controller
    if c.structure_sensors:
        cols = columns(result.rows)
        day = variant_mask(cols, VARIANTS[3], c.night_sun_max_deg)
        d_t = fit_model(pointing_data(cols, day, c.structure_lag_s), t.names)
        out["rms_dt"] = d_t.el_rms_arcsec
        terms, name = c.fit_spec()
        raw = thermal_fit(cols, variant_mask(cols, VARIANTS[0]), terms, name,
                          dict(c.fit_fixed), {"sensor_lag_s": 0.0})
        out["T_raw"] = (raw.values_arcsec[:m], raw.sigma_arcsec[:m],
                        raw.sigma_honest_arcsec[:m])
        every = fit_model(pointing_data(cols, variant_mask(cols, VARIANTS[0]),
                                        c.structure_lag_s), [*terms_of(terms), *SENSOR_FAMILY])
        out["T_all"] = (every.values_arcsec[:m], every.sigma_arcsec[:m],
                        every.sigma_honest_arcsec[:m])
    return out


def recovery(scenario: Scenario, seeds: range, workers: int,
             correction: dict | None = None) -> dict:
    """Per seed (rows) and term: fitted values and both sigmas of fit A, and (without a
    correction) of fit T and the rest of :func:`fit_seed`."""
    jobs = [(scenario, s, correction) for s in seeds]
    if workers > 1:
        with Pool(workers) as pool:
            results = pool.map(fit_seed, jobs, chunksize=4)
    else:
        results = [fit_seed(j) for j in jobs]
    out = {"truth": np.array([r["recoverable"] for r in results]),
           "names": scenario.truth_model.names, "per_seed": results}
    for key in ("A", "T", "T_raw", "T_all"):
        if key in results[0]:
            values, tpoint, honest = (np.array(x) for x in zip(*(r[key] for r in results),
                                                                strict=True))
            out[key] = {"values": values, "tpoint": tpoint, "honest": honest,
                        "truth": out["truth"], "names": out["names"]}
    return out


def summarize(r: dict[str, np.ndarray]) -> dict[str, dict[str, np.ndarray]]:
    error = r["values"] - r["truth"]
    out = {"bias": error.mean(axis=0), "sd": error.std(axis=0, ddof=1)}
    for key in ("tpoint", "honest"):
        pull = error / r[key]
        out[key] = {"sigma": r[key].mean(axis=0), "spread": pull.std(axis=0, ddof=1),
                    "mean": pull.mean(axis=0), "within3": np.mean(np.abs(pull) <= 3, axis=0)}
    return out


def print_table(title: str, r: dict[str, np.ndarray], seeds: range) -> None:
    s = summarize(r)
    print(f"\n{title} (seeds {seeds.start}..{seeds.stop - 1}; arcsec)")
    print(f"{'term':<5}{'bias':>7}{'sd':>7} | {'TPOINT sigma':>12}{'spread':>7}{'in 3s':>7}"
          f" | {'honest sigma':>12}{'spread':>7}{'mean':>7}{'in 3s':>7}  verdict")
    for j, name in enumerate(r["names"]):
        t, h = s["tpoint"], s["honest"]
        ok = 0.85 <= h["spread"][j] <= 1.15 and h["within3"][j] >= 0.99
        print(f"{name:<5}{s['bias'][j]:>+7.1f}{s['sd'][j]:>7.1f} | {t['sigma'][j]:>12.1f}"
              f"{t['spread'][j]:>7.2f}{t['within3'][j] * 100:>6.0f}% | {h['sigma'][j]:>12.1f}"
              f"{h['spread'][j]:>7.2f}{h['mean'][j]:>+7.2f}{h['within3'][j] * 100:>6.0f}%  "
              f"{'honest' if ok else 'NOT honest'}")


def print_thermal(r: dict, truth: dict[str, float]) -> None:
    """How often each thermal term entered fit T, and its recovery where it did."""
    seeds = r["per_seed"]
    print(f"\n{'term':<7}{'selected':>9}{'truth':>8}{'mean':>8}{'sd':>7}{'honest':>8}"
          f"{'mean pull':>10}   (honest: the median honest sigma)")
    names = [n for n in THERMAL_TERMS if any(n in x["thermal"] for x in seeds)]
    infinite = []
    for name in names:
        got = np.array([x["thermal"][name] for x in seeds if name in x["thermal"]])
        line = f"{name:<7}{len(got) / len(seeds) * 100:>8.0f}%"
        if name in truth:
            line += f"{truth[name]:>8.1f}"
        else:
            line += f"{'':>8}"
        sd = got[:, 0].std(ddof=1) if len(got) > 1 else float("nan")
        # the jackknife's honest sigma is infinite where it has <= 2 degrees of freedom for
        # a term (a few seeds of the weak yoke's): the median is finite, and the pulls are
        # averaged over the other seeds
        finite = np.isfinite(got[:, 1])
        if not finite.all():
            infinite.append(f"{name} {np.count_nonzero(~finite)} of {len(got)}")
        line += f"{got[:, 0].mean():>8.1f}{sd:>7.1f}{np.median(got[:, 1]):>8.1f}"
        if name in truth:
            pull = (got[finite, 0] - truth[name]) / got[finite, 1]
            line += f"{pull.mean() if pull.size else float('nan'):>+10.2f}"
        print(line)
    if infinite:
        print("honest sigma infinite (jackknife <= 2 dof; left out of the mean pull): "
              + ", ".join(infinite) + " seeds")


def print_before_after(before: dict, after: dict, seeds: range) -> None:
    """Bias per W of fit A and of fit T on the same campaigns."""
    b, a = summarize(before), summarize(after)
    print(f"\nbias per W, fit A (no thermal terms) -> fit T (proxies), seeds {seeds.start}.."
          f"{seeds.stop - 1}; arcsec, and mean honest pull")
    print(f"{'term':<5}{'bias A':>8}{'bias T':>8} | {'pull A':>7}{'pull T':>7}")
    for j, name in enumerate(before["names"]):
        print(f"{name:<5}{b['bias'][j]:>+8.1f}{a['bias'][j]:>+8.1f} | "
              f"{b['honest']['mean'][j]:>+7.2f}{a['honest']['mean'][j]:>+7.2f}")


def print_warnings(heated: dict, cold: dict) -> None:
    """How often fit A warns of each term's day-minus-night difference."""
    def share(r):
        counts = {n: 0 for n in r["names"]}
        for x in r["per_seed"]:
            for n in x["warned"]:
                counts[n] += 1
        return {n: c / len(r["per_seed"]) for n, c in counts.items()}

    h, c = share(heated), share(cold)
    print("\nfit A's day-minus-night warning (fits D - E beyond 3 sigma), share of seeds per "
          "term: with the heating / without")
    print("  ".join(f"{n} {h[n] * 100:.0f}%/{c[n] * 100:.0f}%" for n in heated["names"]))
    any_h = np.mean([bool(x["warned"]) for x in heated["per_seed"]])
    any_c = np.mean([bool(x["warned"]) for x in cold["per_seed"]])
    print(f"campaigns with at least one warning: {any_h * 100:.0f}% with the heating, "
          f"{any_c * 100:.0f}% without")


def selected_share(r: dict) -> tuple[int, int]:
    """Campaigns whose fit T has any thermal term, and campaigns."""
    return sum(bool(x["thermal"]) for x in r["per_seed"]), len(r["per_seed"])


def ratio_line(label: str, ratios: np.ndarray) -> str:
    return (f"{label}: median {np.median(ratios):.3f}, mean {ratios.mean():.3f}, "
            f"within 15% in {np.mean(ratios <= 1.15) * 100:.0f}% of seeds")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=200)
    parser.add_argument("--first", type=int, default=1,
                        help="first seed (e.g. 201 for fresh seeds beyond the target's 1..200)")
    parser.add_argument("--jobs", "--workers", dest="workers", type=int, default=2)
    parser.add_argument("--scenario", default=str(ROOT / "scenarios" / "ghigo1990.toml"))
    parser.add_argument("--sensors", default=str(ROOT / "scenarios" / "ghigo1990_sensors.toml"))
    parser.add_argument("--calibration", type=int, default=len(CALIBRATION_SEEDS),
                        help="calibration campaigns of case (3) (fewer: a quick check only)")
    args = parser.parse_args()
    scenario = load_scenario(args.scenario)
    seeds = range(args.first, args.first + args.seeds)
    t0 = time.perf_counter()
    heated = recovery(scenario, seeds, args.workers)
    print_table(f"{scenario.name} as calibrated", heated["A"], seeds)
    cold = recovery(without(scenario, "thermal"), seeds, args.workers)
    print_table(f"{scenario.name} without its thermal effect", cold["A"], seeds)
    calibration = CALIBRATION_SEEDS[:args.calibration]
    correction = calibrate(scenario, args.workers, calibration)
    print_table(f"{scenario.name} as calibrated, heating modelled (systematic of "
                f"{len(calibration)} calibration campaigns subtracted)",
                recovery(scenario, seeds, args.workers, correction)["A"], seeds)

    sensed = load_scenario(args.sensors)
    with_sensors = recovery(sensed, seeds, args.workers)
    print_table(f"{sensed.name}, fit T (thermal terms in the structure temperatures)",
                with_sensors["T"], seeds)
    truth = thermal_truth(sensed)
    print_thermal(with_sensors, truth)
    # no thermal bending: the group test's false alarms, and the floor of fit D / fit E
    isothermal = recovery(without(sensed, "thermal"), seeds, args.workers)
    straight = recovery(unbent(sensed), seeds, args.workers)
    print(f"\nfit T's sensor family entered, on campaigns without thermal bending (seeds "
          f"{seeds.start}..{seeds.stop - 1}; the group test's false-alarm rate: {ALPHA:.1%}):")
    for label, r in (("without the thermal effect (an isothermal structure)", isothermal),
                     ("the structure heated, not bending (every arcsec per kelvin 0)", straight)):
        k, n = selected_share(r)
        print(f"  {sensed.name} {label}: {k} of {n} campaigns ({k / n:.1%})")

    def d_over_e(r):
        return np.array([x["rms_dt"] / x["rms"][1] for x in r["per_seed"]])

    d_t, d_floor = d_over_e(with_sensors), d_over_e(straight)
    floor = np.array([x["rms"][0] / x["rms"][1] for x in cold["per_seed"]])
    print("\nfit D's elevation rms / fit E's:")
    print(ratio_line("  with sensors, fit D with fit T's terms", d_t))
    print(ratio_line("  without heating, fits D and E of the W's alone (the floor: the wind "
                     "by day)", floor))
    print(ratio_line("  with sensors, the structure not bending (the floor with sensors)",
                     d_floor))
    print(ratio_line("  with sensors, each seed's ratio over its floor with sensors (what the "
                     "heating adds)", d_t / d_floor))
    within = np.mean(d_t <= 1.15)
    print(f"  the target (fit D's within 15% of fit E's, with sensors): "
          f"{'met' if within >= 0.5 else 'not met'} in the median seed ({within:.0%} of seeds "
          f"within); without any heating the median ratio is {np.median(floor):.3f}")
    print_table(f"{sensed.name}, fit T without the sensors' response-time correction",
                with_sensors["T_raw"], seeds)
    print_table(f"{sensed.name}, the W's with all six pair terms (no selection)",
                with_sensors["T_all"], seeds)

    print_table(f"{scenario.name} as calibrated, fit T (thermal terms in proxies)",
                heated["T"], seeds)
    print_thermal(heated, {})
    print(f"\nthe same on {scenario.name} without its thermal effect (case 2's campaigns):")
    print_thermal(cold, {})
    k, n = selected_share(cold)
    print(f"campaigns with any proxy term: {k} of {n} ({k / n:.1%}; the family's false-alarm "
          f"rate: {ALPHA:.1%})")
    print_before_after(heated["A"], heated["T"], seeds)
    print_warnings(heated, cold)
    print(f"\n{time.perf_counter() - t0:.0f} s wall with {args.workers} workers")


def thermal_truth(scenario: Scenario) -> dict[str, float]:
    """The sensor scenario's thermal coefficients as fit T's terms express them."""
    import simpy

    from antsim.world.world import World

    return World(scenario, simpy.Environment()).sensors.true_coefficients()


if __name__ == "__main__":
    main()

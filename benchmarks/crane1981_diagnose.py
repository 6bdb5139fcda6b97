"""Crane (1981)'s open question as a diagnose case, with its figures.

    python benchmarks/crane1981_diagnose.py [--seeds 6] [--nulls 4] [--sims 8] [--jobs 2]

Crane, NRAO Engineering Memo 147, summary item 3: "The rms error in right ascension is twice
as large (~20") and the behavior sometimes seems non-random, as if the pointing equation used
does not describe the pointing". A hypothesis (the memo names no cause): a polar-drive
torsion under the dish's imbalance (``antsim/world/effects/equatorial.py``), carried by
``scenarios/crane1981_140ft_4990_torsion.toml``. Printed, the memo's numbers beside ours:

1. the variant at its seed (3): fit A's RA/Dec rms per point and C1..C11 against Table 4;
2. the choice of the imbalance's direction psi: per direction, what a fit of C1..C11 leaves
   of a unit torsion in right ascension and in declination, the refraction scale C5 it
   shifts, and how closely the library's nearest candidates mimic what is left;
3. ``antsim diagnose`` of the variant's recordings (``--seeds`` seeds from 3) with the 11-term
   model as the belief (the plain 4990 MHz scenario as ``--scenario``): the named effect, its
   amplitude and direction against the truth, RA/Dec rms before and after, in sample and on
   nights held out; the amplitudes' mean and scatter over the seeds;
4. the false alarms: every plain Crane scenario's own recordings (``--nulls`` seeds each,
   from 1), diagnosed against that scenario (with the simulations' noise, or the data's
   where the schedules diverged: ``antsim.diagnose.core.MIN_MATCHED_FRACTION``);
5. the degenerate direction: the same torsion along the boresight (psi = 0), one seed.

Runs the 96-hour (and 72-hour) campaigns in full: about 2-4 minutes on two cores with a warm
cache ($ANTSIM_CACHE), longer cold.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from antsim.diagnose import diagnose  # noqa: E402
from antsim.diagnose.baseline import SimulatedBaseline  # noqa: E402
from antsim.diagnose.data import from_rows  # noqa: E402
from antsim.scenario import EffectSpec, load_scenario  # noqa: E402
from antsim.simulate.runner import recording_meta, simulate  # noqa: E402
from antsim.studies.crane1981 import BANDS, TABLE4, absorbed_by_crane  # noqa: E402
from controller.pointing.crane import CRANE_NAMES  # noqa: E402

SCENARIOS = ROOT / "scenarios"
TORSION = SCENARIOS / "crane1981_140ft_4990_torsion.toml"


def _plain(band: int):
    return load_scenario(SCENARIOS / f"crane1981_140ft_{band}.toml")


def _recordings(scenario, seed: int):
    res = simulate(scenario, seed)
    return from_rows(res.rows, recording_meta(scenario, seed, res.model))


def _torsion_params(scenario) -> dict:
    return next(e.params for e in scenario.effects if e.name == "polar_torsion")


def variant(torsion) -> None:
    """1. The variant at its own seed against Table 4."""
    from controller.pointing.data import PointingData
    from controller.pointing.fitting import fit_model

    obs = _recordings(torsion, torsion.seed)
    good = obs.good
    data = PointingData(obs.az_rad[good], obs.el_rad[good], obs.xel_arcsec[good],
                        obs.el_arcsec[good], t_s=obs.t_s[good])
    fit = fit_model(data, obs.terms(CRANE_NAMES), robust=True)
    memo = TABLE4[4990]["all"]
    print(f"1. {torsion.name}, seed {torsion.seed} (fit A of C1..C11, arcmin)")
    print(f"   points {fit.n_used} (Table 4: {memo['n']}); RA/Dec rms per point "
          f"{fit.xel_rms_arcsec:.1f}/{fit.el_rms_arcsec:.1f}\" (Table 4: {memo['rms'][0]}/"
          f"{memo['rms'][1]}\"; the plain scenario gets its RA from RA noise)")
    print("   term   ours +- sigma    Table 4      (ours - Table 4) / sigma")
    worst = 0.0
    for j, name in enumerate(CRANE_NAMES):
        value, sigma = fit.values_arcsec[j] / 60.0, fit.sigma_arcsec[j] / 60.0
        t_value, t_sigma = memo["c"][j]
        pull = (value - t_value) / sigma
        worst = max(worst, abs(pull))
        print(f"   {name:<5} {value:+7.2f} +- {sigma:.2f}   {t_value:+6.2f} +- {t_sigma:.2f}   "
              f"{pull:+5.1f}")
    print(f"   largest |pull| {worst:.1f}")
    torsion_terms = next(e.truth()["coefficients_arcsec"] for e in _effects(torsion)
                         if e.name == "polar_torsion")
    absorbed = absorbed_by_crane(obs.az_rad[good], obs.el_rad[good],
                                 math.degrees(obs.latitude_rad), torsion_terms)
    print("   the torsion's part that C1..C11 take (the truth is Table 4 less it): "
          + " ".join(f"{n} {v:+.2f}" for n, v in absorbed.items()))


def _effects(scenario):
    from antsim.world.effects import EFFECTS

    return [EFFECTS[e.name](**e.params) for e in scenario.effects]


def psi_choice(torsion) -> None:
    """2. What C1..C11 leave of a unit torsion per direction psi, on the variant's scans."""
    from antsim.diagnose.problem import term_columns

    obs = _recordings(torsion, torsion.seed)
    used = obs.good
    base = term_columns(CRANE_NAMES, obs)[np.concatenate([used, used])]
    lat = math.degrees(obs.latitude_rad)

    def orthogonal(cols):
        coef, *_ = np.linalg.lstsq(base, cols, rcond=None)
        return cols - base @ coef

    def mimic(sig, names):  # how much of sig's orthogonal part the names' span reproduces
        other = orthogonal(term_columns(names, obs)[np.concatenate([used, used])])
        coef, *_ = np.linalg.lstsq(other, sig, rcond=None)
        return float(np.linalg.norm(other @ coef) / np.linalg.norm(sig))

    pair = term_columns(("HHSHCD", "HHSHSD"), obs)[np.concatenate([used, used])]
    k = int(used.sum())
    print("2. the imbalance's direction psi: what C1..C11 leave of W = 1\" (fit A, the "
          "variant's scans)")
    print("   psi   RA left  Dec left  C5 shift   mimicked by: HCES   MA,ME   HHSH2,HHCH2")
    for psi in range(0, 360, 45):
        p = math.radians(psi)
        unit = {"HHSHCD": math.cos(p), "HHSHSD": -math.sin(p)}
        sig = orthogonal(pair @ np.array(list(unit.values())))
        shift = absorbed_by_crane(obs.az_rad[used], obs.el_rad[used], lat, unit)["C5"]
        print(f"   {psi:3d}   {np.sqrt(np.mean(sig[:k] ** 2)):.3f}    "
              f"{np.sqrt(np.mean(sig[k:] ** 2)):.3f}   {shift:+.5f}            "
              f"{mimic(sig, ['HCES']):.2f}    {mimic(sig, ['MA', 'ME']):.2f}    "
              f"{mimic(sig, ['HHSH2', 'HHCH2']):.2f}")


def named_cases(torsion, plain, seeds, n_sims, jobs) -> None:
    """3. diagnose on the variant's recordings with the plain scenario as the belief."""
    truth = _torsion_params(torsion)
    base = SimulatedBaseline(plain, plain.controller.fit_terms, n_sims, jobs=jobs)
    print(f"3. antsim diagnose {TORSION.name}'s recordings --scenario "
          f"{plain.name}.toml ({n_sims} baseline simulations); truth W = "
          f"{truth['amplitude_arcsec']:.0f}\", psi = {truth['phase_deg']:.0f} deg")
    print("   seed  named (sigma)            W +- sigma     psi     RA/Dec in sample       "
          "RA/Dec held out (nights)")
    amplitudes, named, within, plain_fits = [], 0, 0, []
    for seed in seeds:
        obs = _recordings(torsion, seed)
        plain_fits.append(_lsq_amplitude(obs))
        t0 = time.perf_counter()
        d = diagnose(obs, plain, sim_baseline=base)
        dt = time.perf_counter() - t0
        s = d.summary
        first = d.findings[0] if d.findings else None
        name = first.effect if first else "nothing"
        if first is not None and name == "polar_torsion":
            r = first.result
            named += 1
            amplitudes.append(r.amplitude)
            ok = abs(r.amplitude - truth["amplitude_arcsec"]) < 3 * r.amplitude_sigma
            within += ok
            fitted = f"{r.amplitude:5.1f} +- {r.amplitude_sigma:4.1f}  {r.params['phase_deg']:5.1f}"
            sigma = f"({first.step.significance:.1f})"
        else:
            fitted, sigma = " " * 21, ""
        (a0, d0), (a1, d1) = s["axis_rms_before_arcsec"], s["axis_rms_after_arcsec"]
        (h0, e0), (h1, e1) = s["cv_axis_rms_before_arcsec"], s["cv_axis_rms_after_arcsec"]
        extra = f" + {', '.join(f.effect for f in d.findings[1:])}" if len(d.findings) > 1 \
            else ""
        print(f"   {seed:4d}  {name + ' ' + sigma:<22} {fitted}   {a0:4.1f}/{d0:4.1f} -> "
              f"{a1:4.1f}/{d1:4.1f}\"   {h0:4.1f}/{e0:4.1f} -> {h1:4.1f}/{e1:4.1f}\"{extra}"
              f"  ({dt:.1f} s)")
    print(f"   named polar_torsion first in {named}/{len(seeds)}; amplitude within 3 sigma "
          f"in {within}/{named}")
    if len(amplitudes) > 1:
        print(f"   amplitude over the seeds {statistics.mean(amplitudes):.1f} +- "
              f"{statistics.stdev(amplitudes):.1f}\" (truth {truth['amplitude_arcsec']:.0f}\"); "
              f"plain least squares of C1..C11 and HHSHCD, HHSHSD on the same recordings "
              f"{statistics.mean(plain_fits):.1f} +- {statistics.stdev(plain_fits):.1f}\"")


def _lsq_amplitude(obs) -> float:
    """W from an unweighted least-squares fit of C1..C11 with the torsion's two terms."""
    from controller.pointing.data import PointingData
    from controller.pointing.fitting import fit_model

    g = obs.good
    data = PointingData(obs.az_rad[g], obs.el_rad[g], obs.xel_arcsec[g], obs.el_arcsec[g])
    fit = fit_model(data, obs.terms([*CRANE_NAMES, "HHSHCD", "HHSHSD"]), robust=False)
    return math.hypot(*fit.values_arcsec[-2:])


def false_alarms(seeds, n_sims, jobs) -> None:
    """4. Each plain scenario's own recordings, diagnosed against it."""
    print("4. false alarms: the plain scenarios' own recordings (RA scatter as noise)")
    total = alarms = 0
    for band in BANDS:
        plain = _plain(band)
        base = SimulatedBaseline(plain, plain.controller.fit_terms, n_sims, jobs=jobs)
        found = []
        for seed in seeds:
            obs = _recordings(plain, seed)
            d = diagnose(obs, plain, sim_baseline=base)
            total += 1
            alarms += bool(d.findings)
            noise = "simulated" if d.prediction.known_noise else \
                f"data's noise, {int(np.sum(base.predict(obs).matched))}/{obs.n} matched"
            found.append(f"seed {seed}: " + (", ".join(f.effect for f in d.findings)
                                             or "nothing") + f" ({noise})")
        print(f"   {band} MHz: " + "\n              ".join(found))
    print(f"   findings in {alarms} of {total} recordings without the effect")


def boresight(torsion, plain, n_sims, jobs) -> None:
    """5. The torsion along the boresight (psi = 0): an hour-angle encoder eccentricity on
    this sky."""
    params = dict(_torsion_params(torsion), phase_deg=0.0)
    effects = tuple(EffectSpec(e.name, params) if e.name == "polar_torsion" else e
                    for e in torsion.effects)
    along = torsion.with_effects(effects)
    base = SimulatedBaseline(plain, plain.controller.fit_terms, n_sims, jobs=jobs)
    obs = _recordings(along, torsion.seed)
    d = diagnose(obs, plain, sim_baseline=base)
    print(f"5. the same torsion along the boresight (psi = 0), seed {torsion.seed}:")
    for f in d.findings:
        alts = "; ".join(a.reason for a in f.step.alternatives)
        print(f"   {f.effect} ({f.step.significance:.1f} sigma){': ' + alts if alts else ''}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=6, help="variant seeds (from 3)")
    ap.add_argument("--nulls", type=int, default=4, help="seeds per plain scenario (from 1)")
    ap.add_argument("--sims", type=int, default=8, help="baseline simulations")
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args()
    t0 = time.perf_counter()
    torsion = load_scenario(TORSION)
    plain = _plain(4990)
    variant(torsion)
    psi_choice(torsion)
    named_cases(torsion, plain, list(range(3, 3 + args.seeds)), args.sims, args.jobs)
    false_alarms(list(range(1, 1 + args.nulls)), args.sims, args.jobs)
    boresight(torsion, plain, args.sims, args.jobs)
    print(f"total {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()

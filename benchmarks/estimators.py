"""Accuracy of the five-point estimators against the Cramér-Rao bound (Monte Carlo).

    python benchmarks/estimators.py [--trials N] [--seed S] [--save FILE.json]

For each true offset (0 .. 5 arcmin) and S/N (= A / sigma per point, 10 .. 1000) it simulates
N five-point scans with white Gaussian noise on each point (amplitude 1 K on a constant 30 K
baseline, integrations every 20 s), reduces them with Clark's method and the least-squares
fit (:mod:`controller.scans.reduction`) and prints, per estimator:

- std(offset) / CRB for the constant-baseline bound and the linear-in-time bound (the LSQ
  model's own bound); std and bias over the scans with a defined offset, all flags ignored,
  so the figures describe the estimator and not the flag policy;
- the bias (arcmin) and the fraction of scans flagged (any flag) or undefined (NaN offset);
- for LSQ, PASS/FAIL per cell: std within 1.15 of its own (linear-in-time) bound;
- Clark's efficiency (CRB / std)^2 at the highest S/N, and linearized for both readings of
  its baseline, next to docs/physics.md's 0.67, 0.27, 0.10.

A ratio from N trials carries a relative sampling error of about 1/sqrt(2N) (1.1% at 4000).
Nothing is written unless --save is given. One batch per estimator: vectorized, no loop over
scans.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

# Imported after the path set-up so that the script runs from a source checkout.
from controller.scans.reduction import (
    ESTIMATORS,
    FWHM_PER_SIGMA,
    OFFSETS_N,
    cramer_rao_offset_arcmin,
    reduce_clark,
)

TRUE_OFFSETS_ARCMIN = np.array([0.0, 0.5, 1.0, 2.0, 3.0, 4.0, 5.0])
SNRS = np.array([10.0, 20.0, 50.0, 100.0, 300.0, 1000.0])
STEP_ARCMIN = 7.0
HPBW_ARCMIN = 11.0
AMPLITUDE_K = 1.0
BASELINE_K = 30.0
TIMES_S = np.arange(OFFSETS_N.size) * 20.0  # 15 s integrations + 5 s moves, in n order
LSQ_TARGET = 1.15  # std / own bound
#: Clark's efficiency at offsets of 1', 2', 3' (docs/physics.md, Scan reduction)
QUOTED_CLARK_EFFICIENCY = {1.0: 0.67, 2.0: 0.27, 3.0: 0.10}


def simulate_clean() -> np.ndarray:
    """Noise-free powers (offsets, 5) in K."""
    sigma_beam = HPBW_ARCMIN / FWHM_PER_SIGMA
    x = OFFSETS_N * STEP_ARCMIN
    beam = np.exp(-((x - TRUE_OFFSETS_ARCMIN[:, None]) ** 2) / (2.0 * sigma_beam**2))
    return BASELINE_K + AMPLITUDE_K * beam


def simulate(trials: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Powers (offsets, snrs, trials, 5) in K and the matching per-point sigma (K)."""
    clean = simulate_clean()[:, None, None, :]
    sigma = (AMPLITUDE_K / SNRS)[None, :, None, None]
    noise = rng.standard_normal((TRUE_OFFSETS_ARCMIN.size, SNRS.size, trials, OFFSETS_N.size))
    power = clean + sigma * noise
    return power, np.broadcast_to(sigma, power.shape)


def statistics(offset: np.ndarray, flags: np.ndarray) -> dict[str, np.ndarray]:
    """Per-cell std, bias, flagged and undefined fractions over the trial axis (-1)."""
    defined = np.isfinite(offset)
    count = defined.sum(axis=-1)
    values = np.where(defined, offset, 0.0)
    mean = values.sum(axis=-1) / np.maximum(count, 1)
    variance = (np.where(defined, offset - mean[..., None], 0.0) ** 2).sum(axis=-1)
    std = np.sqrt(variance / np.maximum(count - 1, 1))
    std = np.where(count > 1, std, np.nan)
    return {
        "std_arcmin": std,
        "bias_arcmin": np.where(count > 0, mean - TRUE_OFFSETS_ARCMIN[:, None], np.nan),
        "flagged": (flags != 0).mean(axis=-1),
        "undefined": 1.0 - defined.mean(axis=-1),
    }


def table(title: str, cells: np.ndarray, fmt: str, marks: np.ndarray | None = None) -> str:
    """Rows = true offsets, columns = S/N."""
    header = f"{'offset':>7} |" + "".join(f"{f'S/N {s:g}':>13}" for s in SNRS)
    lines = [title, header, "-" * len(header)]
    for i, offset in enumerate(TRUE_OFFSETS_ARCMIN):
        row = f"{offset:6.1f}' |"
        for j in range(SNRS.size):
            text = format(cells[i, j], fmt)
            if marks is not None:
                text += " " + ("PASS" if marks[i, j] else "FAIL")
            row += f"{text:>13}"
        lines.append(row)
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--trials", type=int, default=4000, help="scans per cell (>= 2)")
    parser.add_argument("--seed", type=int, default=19900208, help="RNG seed")
    parser.add_argument("--save", type=Path, help="write the figures as JSON to this file")
    args = parser.parse_args(argv)
    if args.trials < 2:
        parser.error("--trials must be >= 2")

    rng = np.random.default_rng(args.seed)
    power, sigma = simulate(args.trials, rng)
    offsets_grid, snr_grid = np.meshgrid(TRUE_OFFSETS_ARCMIN, SNRS, indexing="ij")
    bounds = {
        name: cramer_rao_offset_arcmin(
            snr_grid,
            offsets_grid,
            step_arcmin=STEP_ARCMIN,
            hpbw_arcmin=HPBW_ARCMIN,
            baseline=name,
            times_s=TIMES_S,
        )
        for name in ("constant", "linear_time")
    }
    print(
        f"{args.trials} trials per cell, seed {args.seed}; D = {STEP_ARCMIN}', HPBW = "
        f"{HPBW_ARCMIN}'; ratio sampling error ~{100 / np.sqrt(2 * args.trials):.1f}%\n"
    )
    print(table("CRB, constant baseline (arcmin)", bounds["constant"], ".4f"), "\n")
    print(table("CRB, baseline linear in time (arcmin)", bounds["linear_time"], ".4f"), "\n")

    results: dict[str, dict[str, list]] = {}
    for name, estimator in ESTIMATORS.items():
        start = time.perf_counter()
        reduced = estimator(power, sigma, TIMES_S, step_arcmin=STEP_ARCMIN, hpbw_arcmin=HPBW_ARCMIN)
        elapsed = time.perf_counter() - start
        stats = statistics(reduced.offset_arcmin, reduced.flags)
        ratio_constant = stats["std_arcmin"] / bounds["constant"]
        ratio_time = stats["std_arcmin"] / bounds["linear_time"]
        print(f"=== {name}: {power[..., 0].size} scans reduced in {elapsed:.2f} s ===\n")
        own = None
        if name == "lsq":
            own = ratio_time <= LSQ_TARGET
        print(table(f"{name}: std / CRB(constant baseline)", ratio_constant, ".3f"), "\n")
        print(table(f"{name}: std / CRB(linear in time)", ratio_time, ".3f", own), "\n")
        print(table(f"{name}: bias (arcmin)", stats["bias_arcmin"], "+.4f"), "\n")
        print(table(f"{name}: fraction flagged (any flag)", stats["flagged"], ".3f"), "\n")
        print(table(f"{name}: fraction with undefined offset", stats["undefined"], ".3f"), "\n")
        if name == "clark":
            # Monte Carlo at the highest S/N, and the linearized (formal, noise-free) value for
            # both readings of "baseline from the +-4D points".
            top = SNRS.size - 1
            efficiency = (bounds["constant"][:, top] / stats["std_arcmin"][:, top]) ** 2
            clean = simulate_clean()
            linear = {
                reading: (
                    bounds["constant"][:, top]
                    / reduce_clark(clean, sigma[:, top, 0], baseline=reading).sigma_offset_arcmin
                )
                ** 2
                for reading in ("line", "mean")
            }
            print(f"clark efficiency (CRB_constant / std)^2: Monte Carlo at S/N {SNRS[top]:g};")
            print("linearized for the straight-line baseline (used) and the mean of +-4D:")
            print(f"{'offset':>7} {'MC line':>8} {'lin line':>9} {'lin mean':>9} {'quoted':>7}")
            for i, offset in enumerate(TRUE_OFFSETS_ARCMIN):
                design = QUOTED_CLARK_EFFICIENCY.get(float(offset))
                print(
                    f"{offset:6.1f}' {efficiency[i]:8.3f} {linear['line'][i]:9.3f}"
                    f" {linear['mean'][i]:9.3f} {'' if design is None else f'{design:.2f}':>7}"
                )
            print()
        if own is not None:
            verdict = "PASS" if own.all() else "FAIL"
            print(
                f"lsq within {LSQ_TARGET} of its own bound in {own.sum()}/{own.size} cells:"
                f" {verdict}\n"
            )
        results[name] = {
            "std_over_crb_constant": ratio_constant.tolist(),
            "std_over_crb_linear_time": ratio_time.tolist(),
            **{key: value.tolist() for key, value in stats.items()},
        }

    if args.save is not None:
        payload = {
            "trials": args.trials,
            "seed": args.seed,
            "true_offsets_arcmin": TRUE_OFFSETS_ARCMIN.tolist(),
            "snr": SNRS.tolist(),
            "crb_constant_arcmin": bounds["constant"].tolist(),
            "crb_linear_time_arcmin": bounds["linear_time"].tolist(),
            "estimators": results,
        }
        args.save.write_text(json.dumps(payload, indent=1) + "\n")
        print(f"wrote {args.save}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

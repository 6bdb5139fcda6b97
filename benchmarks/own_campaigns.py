"""antsim diagnose on the project's own campaigns without a scenario: what it names beyond the
model in use, against what the campaign's truth holds.

    python benchmarks/own_campaigns.py [--scenario ghigo1990] [--seeds 20] [--first 1]

Each seed runs the campaign as a user would (``antsim run SCENARIO --seed N --out DIR``) and
diagnoses its recordings without ``--scenario`` (``antsim diagnose DIR/recordings.ecsv``:
the model in the recordings' metadata is the baseline, the noise is estimated from the
data). The truth (``truth.json``) holds the baseline's terms and the scenario's effects; a
finding names an effect the truth holds when its candidate reproduces one of them (its
simulator effect; the Sun's heating, ``thermal``, is what the thermal candidates name: a
drift after sunset, a transient, a drift with the air temperature, the dish heated on the
side the Sun faces, the structure sensors' terms: ``candidates.library.naming``). Target:
over 20 seeds, at most one finding of an effect the truth does not hold. The output is kept
in docs/results/own_campaigns.txt.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from antsim.cli import main as cli  # noqa: E402
from antsim.diagnose import diagnose, load_observations  # noqa: E402
from antsim.diagnose.candidates.library import naming  # noqa: E402

#: at most this many findings of effects the truth does not hold, over all seeds
MAX_FALSE = 1


def truth_effects(truth: dict) -> set[str]:
    """The candidates whose findings name an effect the campaign's truth holds."""
    return set().union(*(naming(e["effect"]) for e in truth.get("effects", [])))


def one_seed(scenario: str, seed: int, folder: Path) -> dict:
    """One campaign and its diagnosis: the findings, each said to be of the truth or not."""
    out = folder / f"seed{seed}"
    with contextlib.redirect_stdout(io.StringIO()):  # the run's own summary: not ours
        status = cli(["run", scenario, "--seed", str(seed), "--out", str(out), "--no-report",
                      "--no-progress"])
    if status != 0:
        raise SystemExit(f"antsim run {scenario} --seed {seed} failed")
    truth = truth_effects(json.loads((out / "truth.json").read_text(encoding="utf-8")))
    t0 = time.perf_counter()
    d = diagnose(load_observations(out / "recordings.ecsv"))
    seconds = time.perf_counter() - t0
    found = [(f.result.candidate.name, f.step.significance, f.step.stability)
             for f in d.findings]
    return {"seed": seed, "found": found, "truth": truth, "seconds": seconds,
            "false": [name for name, _, _ in found if name not in truth],
            "refused": [r.name for r in d.selection.refused],
            "held_out": (d.summary["cv_sky_rms_before_arcsec"],
                         d.summary["cv_sky_rms_after_arcsec"])}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenario", default="ghigo1990")
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--first", type=int, default=1)
    args = parser.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for seed in range(args.first, args.first + args.seeds):
            r = one_seed(args.scenario, seed, Path(tmp))
            rows.append(r)
            said = ", ".join(f"{name} ({sigma:.1f} sigma, stable {100 * stab:.0f}%)"
                             for name, sigma, stab in r["found"]) or "nothing"
            before, after = r["held_out"]
            print(f"seed {seed:3d}: {said}; held out {before:.2f}\" -> {after:.2f}\"; "
                  f"refused {', '.join(r['refused']) or 'none'} ({r['seconds']:.1f} s)",
                  flush=True)
    false = sum(len(r["false"]) for r in rows)
    right = sum(len(r["found"]) - len(r["false"]) for r in rows)
    silent = sum(not r["found"] for r in rows)
    print(f"{args.scenario}, {len(rows)} seeds without --scenario: findings of an effect the "
          f"truth holds {right}, of one it does not hold {false} (target at most "
          f"{MAX_FALSE}: {'met' if false <= MAX_FALSE else 'NOT met'}); nothing named on "
          f"{silent} of {len(rows)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

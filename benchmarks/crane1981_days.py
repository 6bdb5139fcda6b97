"""How many days the 140-ft needs (Crane 1981, summary 7 and 8), answered by ``antsim plan``.

    python benchmarks/crane1981_days.py [--members N] [--workers N] [--out DIR]

Runs scenarios/plans/crane1981_days.toml (the three runs of 1981 as made, and the 10500 MHz
run without its tipping scans; a few minutes on two cores: its Monte Carlo members are
simulated in full) and prints, beside the memo's "three days ... at 5 GHz and lower" and
"a minimum of 3 days and probably 4" above 10 GHz:

1. per band, the 24-hour days after which every C1..C11's predicted error (the observatory's
   fit A) is within Table 4's, and each term's own first day;
2. the days after which the hour-angle and declination cells below +20 deg that the
   calibrators reach are all observed;
3. the tipping scans' cost at 10500 MHz: scans made in three days with and without them;
4. the check of the prediction: Monte Carlo over Fisher sigma per variant (median and range
   over the eleven terms; with 20 members each sigma is known to ~16%).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

# Imported after the path set-up so that the script runs from a source checkout.
from antsim.plan.planfile import load_plan
from antsim.plan.study import run_plan

PLAN = Path(__file__).resolve().parents[1] / "scenarios" / "plans" / "crane1981_days.toml"
#: what the memo says, per variant the duration questions are based on
MEMO = {"4990 as run": "3 days (5 GHz and lower)", "3245 as run": "3 days (5 GHz and lower)",
        "10500 as run": "at least 3, probably 4 days (tipping)",
        "10500 without tipping": "(the tipping's cost)"}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--members", type=int, default=None, help="members per variant")
    parser.add_argument("--workers", type=int, default=None, help="worker processes")
    parser.add_argument("--out", type=Path, default=None, help="write plan.json and plan.txt")
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    plan = load_plan(PLAN)
    result = run_plan(plan, workers=args.workers, members=args.members, progress=False)
    if args.out is not None:
        import json

        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "plan.json").write_text(json.dumps(result.to_json(), indent=2) + "\n")
        (args.out / "plan.txt").write_text(result.text())
    answers = result.answers

    print("1. Days for every C to reach Table 4's error (fit A, predicted), beside the memo")
    print(f"   {'variant':<24}{'memo':<40}{'ours':>6}   each term's first day (C1..C11)")
    for a in answers["duration"]:
        ours = a["answer"]["count"] if a["reached"] else f">{a['max_days']:g}"
        first = " ".join(str(c) if c is not None else "-" for c in a["first_count"].values())
        print(f"   {a['based_on']:<24}{MEMO.get(a['based_on'], ''):<40}{ours!s:>6}   {first}")
        if not a["reached"] and a["extrapolated"]:
            print(f"   {'':<64}about {a['extrapolated']['count']} days by 1/sqrt(time)")

    print("\n2. Coverage below +20 deg: cells (1 h x 10 deg) the calibrators reach, filled per day")
    for a in answers["coverage"]:
        per_day = " ".join(f"{c['filled']}" for c in a["curve"])
        done = a["answer_days"] if a["answer_days"] is not None else f">{a['max_days']:g}"
        print(f"   {a['based_on']:<24} memo: 3 days; ours {done!s:>3} ({a['cells']} cells; "
              f"filled after day 1..: {per_day})")
        for m in a["missing_at_max_days"][:6]:
            print(f"     never filled: HA {m['ha_h'][0]:+.0f}..{m['ha_h'][1]:+.0f} h, "
                  f"Dec {m['dec_deg'][0]:+.0f}..{m['dec_deg'][1]:+.0f} deg")

    print("\n3. The tipping scans' cost at 10500 MHz (three days)")
    for v in result.variants:
        if v.spec.name.startswith("10500"):
            print(f"   {v.spec.name:<24}{v.shared.n_scans:4d} scans, "
                  f"{v.shared.scan_span_s / 3600:.1f} h scanning")

    print("\n4. Monte Carlo over Fisher sigma (median, range over C1..C11)")
    for v in result.variants:
        ratio = v.sigma_mc() / v.prediction.sigma_arcsec
        print(f"   {v.spec.name:<24}{int(v.ok.sum()):3d} members: {np.median(ratio):.2f} "
              f"({np.min(ratio):.2f}-{np.max(ratio):.2f})")
    print(f"\n({time.perf_counter() - t0:.1f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

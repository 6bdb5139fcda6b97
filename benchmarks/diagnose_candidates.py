"""Each diagnose candidate's test on one recordings file: where diagnose's first round goes.

    python benchmarks/diagnose_candidates.py FILE [--only NAME,NAME...]

Builds the problem as ``antsim diagnose FILE`` does without a scenario (the recordings' own
model as the baseline, white noise), then times each applicable candidate's test against it
in turn and prints its wall time, chi^2 decrease and best shape. With the 200,000-scan file
of ``benchmarks/diagnose_scale.py --keep DIR`` it shows which candidates the whole run's
time goes to (``--only`` the named ones; the caches of one candidate serve the next, as in
diagnose). Note ``uptime`` with the figures: the machine's load moves them.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("file", type=Path, help="a recordings.ecsv")
    parser.add_argument("--only", default="", help="comma-separated candidate names")
    args = parser.parse_args()
    from antsim.diagnose.baseline import offset_scale, resolve_baseline, white_prediction
    from antsim.diagnose.candidates.library import CANDIDATES
    from antsim.diagnose.data import load_observations
    from antsim.diagnose.problem import Problem

    only = {name for name in args.only.split(",") if name}
    unknown = only - {c.name for c in CANDIDATES}
    if unknown:
        print(f"--only: no candidate named {', '.join(sorted(unknown))}", file=sys.stderr)
        return 2
    start = time.perf_counter()
    try:
        obs = load_observations(args.file)
    except (OSError, ValueError) as exc:  # the reader's one line names the file and field
        print(exc, file=sys.stderr)
        return 2
    problem = Problem(obs, white_prediction(obs), resolve_baseline(obs).terms,
                      offset_scale=offset_scale(obs))
    problem.update_outliers()
    perp, z_perp = problem.perp_for(problem.used)
    print(f"{args.file}: {obs.n} scans, problem in {time.perf_counter() - start:.1f} s")
    total = 0.0
    for c in CANDIDATES:
        if (only and c.name not in only) or not c.applicable(obs, False):
            continue
        start = time.perf_counter()
        res = c.test(problem, perp, z_perp, float(z_perp @ z_perp))
        took = time.perf_counter() - start
        total += took
        shape = res.theta if isinstance(res.theta, tuple) else (res.theta,)
        theta = ", ".join(f"{v:.6g}" if isinstance(v, float) else str(v) for v in shape)
        print(f"{c.name:28s} {took:7.2f} s  chi2 decrease {res.delta_chi2:.6g}  shape {theta}",
              flush=True)
    print(f"{'all':28s} {total:7.2f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Throughput of Monte Carlo ensembles of the 24-hour campaign (scenarios/ghigo1990.toml).

    python benchmarks/ensemble_throughput.py [--members 1000] [--scaling-members 256]

Prints:

* members per second per core on the shared schedule (blocks of members: simulation,
  reduction and fit A), with a local pool of 1 worker and of 2 workers, and
  the scaling efficiency from 1 to 2 workers (speed-up / 2);
* the same end to end for the whole ``antsim plan`` machinery of a one-variant plan;
* the wall time of a ``--members`` ensemble on 2 workers, everything included (pool start-up,
  the deterministic run, the noise model, members simulated in full where the shared schedule
  does not hold). Target: 1000 members in at most 60 s on this 2-core machine.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from antsim.plan.planfile import load_plan  # noqa: E402
from antsim.plan.study import block_size, run_plan  # noqa: E402
from antsim.simulate.ensemble import Job, make_executor, task_block, task_record  # noqa: E402
from antsim.simulate.vectorized import quiet_scenario  # noqa: E402

PLAN = """name = "throughput"
scenario = "{scenario}"
seed = 2024
members = {members}
[[variants]]
name = "ghigo1990"
"""


def plan_for(members: int, directory: Path):
    path = directory / f"throughput_{members}.toml"
    path.write_text(PLAN.format(scenario=(ROOT / "scenarios" / "ghigo1990.toml").as_posix(),
                                members=members), encoding="utf-8")
    return load_plan(path)


def blocks_time(job: Job, members: int, workers: int) -> float:
    """Wall time of the member blocks alone (workers started and warmed first)."""
    size = block_size(job.scenario.duration_s)
    blocks = [tuple(range(s, min(members, s + size))) for s in range(0, members, size)]
    with make_executor(workers) as ex:
        handle = ex.share(job)
        warm = [ex.submit(task_block, handle, (members + k,)) for k in range(workers)]
        for f in warm:
            f.result()
        t0 = time.perf_counter()
        futures = [ex.submit(task_block, handle, b) for b in blocks]
        for f in futures:
            f.result()
        return time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--members", type=int, default=1000)
    parser.add_argument("--scaling-members", type=int, default=256)
    args = parser.parse_args()
    n = args.scaling_members

    with tempfile.TemporaryDirectory() as tmp:
        plan = plan_for(n, Path(tmp))
        scenario = plan.scenarios[0]
        quiet = quiet_scenario(scenario)
        t0 = time.perf_counter()
        shared = task_record(quiet)
        t_record = time.perf_counter() - t0
        terms, fit_name = scenario.controller.fit_spec()
        job = Job("throughput", scenario, quiet, shared, tuple(terms), fit_name, plan.seed)
        print(f"24-hour campaign: {shared.n_scans} scans, {shared.n_integrations} integrations; "
              f"deterministic run {t_record:.1f} s")
        t1 = blocks_time(job, n, 1)
        t2 = blocks_time(job, n, 2)
        print(f"members on the shared schedule ({n} members, blocks of "
              f"{block_size(scenario.duration_s)}; simulation, reduction and fit A):")
        print(f"  1 worker : {t1:6.1f} s  {n / t1:6.2f} members/s per core")
        print(f"  2 workers: {t2:6.1f} s  {n / t2 / 2:6.2f} members/s per core")
        print(f"  scaling efficiency 1 -> 2 workers: {t1 / t2 / 2:.0%} (speed-up {t1 / t2:.2f})")

        e1 = time.perf_counter()
        r1 = run_plan(plan, workers=1, answers=False, progress=False)
        e1 = time.perf_counter() - e1
        e2 = time.perf_counter()
        r2 = run_plan(plan, workers=2, answers=False, progress=False)
        e2 = time.perf_counter() - e2
        same = r1.to_json() == r2.to_json()
        print(f"whole plan of {n} members (deterministic run, noise model, members): 1 worker "
              f"{e1:.1f} s, 2 workers {e2:.1f} s (pool start-up included); efficiency "
              f"{e1 / e2 / 2:.0%}; identical results: {same}")

        big = plan_for(args.members, Path(tmp))
        t0 = time.perf_counter()
        result = run_plan(big, workers=2, answers=False, progress=False)
        wall = time.perf_counter() - t0
        p = result.to_json()["plans"][0]
        print(f"{args.members} members on 2 workers, everything included ({p['n_full_simulation']} "
              f"members simulated in full): {wall:.1f} s = {args.members / wall / 2:.2f} "
              f"members/s per core; target <= 60 s: {'met' if wall <= 60.0 else 'NOT met'}")


if __name__ == "__main__":
    main()

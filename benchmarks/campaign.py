"""Wall time of simulated campaigns (simulation + reduction, after imports).

    python benchmarks/campaign.py [--days 30] [--repeats 3]

Prints the 24-hour campaign of ``scenarios/ghigo1990.toml`` (target: at most 1 s, i.e.
86,400 times faster than real time), a 30-day campaign (cost should grow linearly with the
duration: its cost per day against the 24-hour one, and the wall time per simulated day in
each third of it), and the whole ``antsim run`` command with Python start-up (no target: the
3 s target for it was withdrawn with the output process that met it).
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from antsim.scenario import load_scenario  # noqa: E402
from antsim.simulate.runner import simulate  # noqa: E402


def campaign_seconds(scenario, repeats: int) -> tuple[list[float], int]:
    times, scans = [], 0
    for i in range(repeats):
        t0 = time.perf_counter()
        result = simulate(scenario, seed=scenario.seed + i)
        times.append(time.perf_counter() - t0)
        scans = result.n_scans
    return times, scans


def spread(times: list[float]) -> str:
    """The runs' range: this shared machine's speed for the same code varies from hour to
    hour (and run to run), which the median alone hides."""
    if len(times) < 2:
        return ""
    return f" (min {min(times):.2f}, max {max(times):.2f} over {len(times)} runs)"


def thirds(t0: float, day_marks: list[float]) -> str:
    """The wall time per simulated day in each third of a long campaign: a cost that grew
    with the campaign's length would show as a rising sequence (within one run, so the
    machine's hour-to-hour speed does not enter)."""
    per_day = np.diff([t0, *day_marks])
    if per_day.size < 3:
        return "  (too few days for thirds)"
    parts = np.array_split(per_day, 3)
    means = ", ".join(f"{p.mean():.2f}" for p in parts)
    return (f"  wall time per simulated day, first/middle/last third: {means} s "
            f"(last / first = {parts[-1].mean() / parts[0].mean():.2f})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--days", type=float, default=30.0)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()

    base = load_scenario(ROOT / "scenarios" / "ghigo1990.toml")
    simulate(replace(base, duration_s=3600.0,
                     controller=replace(base.controller, duration_s=3600.0)))  # warm caches

    day_times, day_scans = campaign_seconds(base, args.repeats)
    day_s = statistics.median(day_times)
    print(f"24-hour campaign: median {day_s:.2f} s wall{spread(day_times)} ({day_scans} "
          f"scans), {86400.0 / day_s:,.0f}x real time; target <= 1 s: "
          f"{'met' if day_s <= 1.0 else 'NOT met'}")

    long_s = args.days * 86400.0
    long = replace(base, duration_s=long_s, controller=replace(base.controller,
                                                                duration_s=long_s))
    day_marks: list[float] = []

    def mark_days(t_s: float) -> None:
        while t_s >= 86400.0 * (len(day_marks) + 1):
            day_marks.append(time.perf_counter())

    t0 = time.perf_counter()
    long_scans = simulate(long, seed=long.seed, progress=mark_days).n_scans
    long_t = time.perf_counter() - t0
    per_day = long_t / args.days
    print(f"{args.days:g}-day campaign: {long_t:.1f} s wall ({long_scans} scans), "
          f"{per_day:.2f} s per day = {per_day / day_s:.2f}x the 24-hour cost per day "
          f"(1.00 = linear)")
    print(thirds(t0, day_marks))

    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "antsim", "run", str(ROOT / "scenarios" / "ghigo1990.toml"),
               "--no-progress"]
        for label, extra in (("with the report", []), ("--no-report", ["--no-report"])):
            runs = []
            for i in range(args.repeats):
                t0 = time.perf_counter()
                subprocess.run([*cmd, *extra, "--out", f"{tmp}/run{label[:4]}{i}"],
                               check=True, capture_output=True)
                runs.append(time.perf_counter() - t0)
            whole = statistics.median(runs)
            print(f"whole `antsim run scenarios/ghigo1990.toml` {label} (Python start-up, fit, "
                  f"files): median {whole:.2f} s{spread(runs)}")


if __name__ == "__main__":
    main()

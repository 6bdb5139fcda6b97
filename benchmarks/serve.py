"""Wall time of the project's controller driving `antsim serve` (virtual clock) against the
same campaign in process, in interleaved rounds.

    python benchmarks/serve.py [--scenario scenarios/ghigo1990.toml] [--rounds 3]

Each round runs, one after the other: the campaign in process (``run_campaign``, in this
process, after imports), the campaign over the wire (a fresh ``antsim serve`` started
before the clock starts, ``run_campaign`` with :class:`controller.wire.KatcpAntenna`), and
the two whole commands (``antsim run --no-report``, and ``antsim run --no-report --connect``
against a server already listening). Every wire campaign's recordings.ecsv is checked to be
byte-identical to the in-process one. Target: the wire at most 2x the in-process run.

Also printed, for the wire: the controller's own time, the time it waited for the
antenna's replies, how much of that the server spent serving the requests (the world's work
and the request handling) and the rest, in transit between the two processes, per request;
and the round trip of one trivial request (``?channels``) sent back to back. The transit of
about 27 sequential requests per scan is the part no server or client code can remove.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from antsim.run.runner import run_campaign  # noqa: E402
from antsim.scenario import load_scenario  # noqa: E402
from antsim.serve.process import ServerProcess  # noqa: E402
from antsim.serve.remote import connect  # noqa: E402


def _env() -> dict:
    env = os.environ.copy()
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    return env


def _command_s(args: list[str]) -> float:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "antsim", *args], check=True, env=_env(),
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t0


def round_trip_us(port: int, n: int = 2000) -> float:
    """Median time of one trivial request (us)."""
    import simpy

    from controller.wire import KatcpAntenna

    with KatcpAntenna("127.0.0.1", port, simpy.Environment()) as antenna:
        times = []
        for _ in range(n):
            t0 = time.perf_counter()
            antenna._request("channels")
            times.append(time.perf_counter() - t0)
    return statistics.median(times) * 1e6


def one_round(path: str, tmp: Path, k: int) -> dict:
    scenario = load_scenario(path)
    out: dict = {}
    t0 = time.perf_counter()
    run_campaign(scenario, tmp / f"in{k}", show_progress=False)
    out["campaign_in"] = time.perf_counter() - t0
    with ServerProcess(path) as server:
        antenna, seed = connect(scenario, f"127.0.0.1:{server.port}")
        requests, waited = antenna.requests, antenna.waited_s
        t0 = time.perf_counter()
        run_campaign(scenario, tmp / f"wire{k}", seed=seed, show_progress=False,
                     antenna=antenna)
        out["campaign_wire"] = time.perf_counter() - t0
        out["requests"] = antenna.requests - requests
        out["waited"] = antenna.waited_s - waited
        antenna.close()
        server.stop()
        out["serving"] = next(float(line.split(" requests (")[1].split()[0])
                              for line in server.lines if " s serving them)" in line)
    same = ((tmp / f"in{k}" / "recordings.ecsv").read_bytes()
            == (tmp / f"wire{k}" / "recordings.ecsv").read_bytes())
    out["identical"] = same
    out["command_in"] = _command_s(["run", path, "--out", str(tmp / f"cin{k}"), "--no-report"])
    with ServerProcess(path) as server:
        out["command_wire"] = _command_s(["run", path, "--out", str(tmp / f"cwire{k}"),
                                          "--no-report", "--connect",
                                          f"127.0.0.1:{server.port}"])
    with ServerProcess(path) as server:
        out["round_trip_us"] = round_trip_us(server.port)
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default=str(ROOT / "scenarios" / "ghigo1990.toml"))
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    print(f"load average before: {os.getloadavg()[0]:.2f} (2 cores shared)")
    rounds = []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(args.rounds):
            r = one_round(args.scenario, Path(tmp), k)
            rounds.append(r)
            print(f"round {k + 1}: campaign in process {r['campaign_in']:.2f} s, over the wire "
                  f"{r['campaign_wire']:.2f} s (x{r['campaign_wire'] / r['campaign_in']:.2f}); "
                  f"whole command {r['command_in']:.2f} s vs {r['command_wire']:.2f} s "
                  f"(x{r['command_wire'] / r['command_in']:.2f}); recordings identical: "
                  f"{r['identical']}", flush=True)
            print(f"  over the wire: the controller {r['campaign_wire'] - r['waited']:.2f} s, "
                  f"waiting for {r['requests']} replies {r['waited']:.2f} s (the server "
                  f"serving them {r['serving']:.2f} s, the rest {r['waited'] - r['serving']:.2f}"
                  f" s = {(r['waited'] - r['serving']) / r['requests'] * 1e6:.0f} us per "
                  f"request in transit); back-to-back round trip {r['round_trip_us']:.0f} us",
                  flush=True)
    med = {key: statistics.median(r[key] for r in rounds)
           for key in ("campaign_in", "campaign_wire", "command_in", "command_wire",
                       "round_trip_us", "requests", "waited", "serving")}
    campaign = med["campaign_wire"] / med["campaign_in"]
    command = med["command_wire"] / med["command_in"]
    print(f"median of {len(rounds)} rounds: campaign {med['campaign_in']:.2f} s in process, "
          f"{med['campaign_wire']:.2f} s over the wire (x{campaign:.2f}, target x2); whole "
          f"command {med['command_in']:.2f} s vs {med['command_wire']:.2f} s (x{command:.2f})")
    controller = statistics.median(r["campaign_wire"] - r["waited"] for r in rounds)
    transit = statistics.median(r["waited"] - r["serving"] for r in rounds)
    print(f"median split of the wire campaign: the controller {controller:.2f} s, the server "
          f"{med['serving']:.2f} s, in transit {transit:.2f} s for {med['requests']:.0f} "
          f"requests ({transit / med['requests'] * 1e6:.0f} us each)")
    print(f"recordings byte-identical in every round: {all(r['identical'] for r in rounds)}")
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    return 0 if all(r["identical"] for r in rounds) else 1


if __name__ == "__main__":
    raise SystemExit(main())

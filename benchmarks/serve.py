"""Wall time of the project's controller driving `antsim serve` (virtual clock) against the
same campaign in process, in interleaved rounds.

    python benchmarks/serve.py [--scenario scenarios/ghigo1990.toml] [--rounds 3]

Each round runs, one after the other: the campaign in process (``run_campaign``, in this
process, after imports), the campaign over the wire (a fresh ``antsim serve`` started
before the clock starts, ``run_campaign`` with :class:`controller.wire.KatcpAntenna`), and
the two whole commands (``antsim run --no-report``, and ``antsim run --no-report --connect``
against a server already listening). Every wire campaign's recordings.ecsv is checked to be
byte-identical to the in-process one. Target: the wire at most 2x the in-process run.

Also printed, for the wire: the requests and the round trips (a write, then the replies of
everything unanswered: the client pipelines, see controller/wire.py); the processor time of
the client and of the server against the in-process run's (the two processes mostly take
turns, so the wire's wall time is about their sum); the wall time the client waited for
replies; the round trip of one trivial request (``?channels``) sent back to back, and the
cost per request of trivial requests pipelined as a scan's are (13 per write): aiokatcp's
and the client's handling of a request, which every one of the campaign's requests pays.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from antsim.scenario import load_scenario  # noqa: E402
from antsim.serve.process import ServerProcess  # noqa: E402
from antsim.serve.remote import connect  # noqa: E402
from antsim.simulate.runner import run_campaign  # noqa: E402


def _env() -> dict:
    env = os.environ.copy()
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    return env


def _command_s(args: list[str]) -> float:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "antsim", *args], check=True, env=_env(),
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t0


def _cpu_s(pid: int | None = None) -> float:
    """Processor time (user + system, s) of this process, or of process ``pid`` (Linux)."""
    if pid is None:
        usage = resource.getrusage(resource.RUSAGE_SELF)
        return usage.ru_utime + usage.ru_stime
    fields = Path(f"/proc/{pid}/stat").read_text().rpartition(")")[2].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def trivial_requests_us(port: int, n: int = 2000, batch: int = 13) -> tuple[float, float]:
    """Median wall time (us) of one trivial request (``?channels``) sent back to back, and
    the mean per request when they go ``batch`` to a write (pipelined)."""
    import simpy

    from controller.wire import KatcpAntenna

    with KatcpAntenna("127.0.0.1", port, simpy.Environment()) as antenna:
        times = []
        for _ in range(n):
            t0 = time.perf_counter()
            antenna._request("channels")
            times.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        for _ in range(n // batch):
            for _ in range(batch):
                antenna._send("channels")
            antenna._sync()
        pipelined = (time.perf_counter() - t0) / (n // batch * batch)
    return statistics.median(times) * 1e6, pipelined * 1e6


def one_round(path: str, tmp: Path, k: int) -> dict:
    scenario = load_scenario(path)
    out: dict = {}
    c0, t0 = _cpu_s(), time.perf_counter()
    result = run_campaign(scenario, tmp / f"in{k}", show_progress=False)
    out["campaign_in"] = time.perf_counter() - t0
    out["cpu_in"] = _cpu_s() - c0
    out["scans"] = result.n_scans
    with ServerProcess(path) as server:
        antenna, seed = connect(scenario, f"127.0.0.1:{server.port}")
        requests, trips, waited = antenna.requests, antenna.round_trips, antenna.waited_s
        s0, c0, t0 = _cpu_s(server.process.pid), _cpu_s(), time.perf_counter()
        run_campaign(scenario, tmp / f"wire{k}", seed=seed, show_progress=False,
                     antenna=antenna)
        out["campaign_wire"] = time.perf_counter() - t0
        out["cpu_client"] = _cpu_s() - c0
        out["cpu_server"] = _cpu_s(server.process.pid) - s0
        out["requests"] = antenna.requests - requests
        out["round_trips"] = antenna.round_trips - trips
        out["waited"] = antenna.waited_s - waited
        antenna.close()
    same = ((tmp / f"in{k}" / "recordings.ecsv").read_bytes()
            == (tmp / f"wire{k}" / "recordings.ecsv").read_bytes())
    out["identical"] = same
    out["command_in"] = _command_s(["run", path, "--out", str(tmp / f"cin{k}"), "--no-report"])
    with ServerProcess(path) as server:
        out["command_wire"] = _command_s(["run", path, "--out", str(tmp / f"cwire{k}"),
                                          "--no-report", "--connect",
                                          f"127.0.0.1:{server.port}"])
    with ServerProcess(path) as server:
        out["round_trip_us"], out["pipelined_us"] = trivial_requests_us(server.port)
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
                  f"{r['identical']}; load {os.getloadavg()[0]:.2f}", flush=True)
            print(f"  over the wire: {r['requests']} requests in {r['round_trips']} round "
                  f"trips ({r['round_trips'] / r['scans']:.1f} per scan); processor time: "
                  f"client {r['cpu_client']:.2f} s + server {r['cpu_server']:.2f} s against "
                  f"{r['cpu_in']:.2f} s in process; the client waited {r['waited']:.2f} s; "
                  f"a trivial request {r['round_trip_us']:.0f} us back to back, "
                  f"{r['pipelined_us']:.0f} us pipelined", flush=True)
    keys = ("campaign_in", "campaign_wire", "command_in", "command_wire", "round_trip_us",
            "pipelined_us", "requests", "round_trips", "scans", "waited", "cpu_in",
            "cpu_client", "cpu_server")
    med = {key: statistics.median(r[key] for r in rounds) for key in keys}
    campaign = statistics.median(r["campaign_wire"] / r["campaign_in"] for r in rounds)
    command = statistics.median(r["command_wire"] / r["command_in"] for r in rounds)
    print(f"median of {len(rounds)} interleaved rounds: campaign {med['campaign_in']:.2f} s in "
          f"process, {med['campaign_wire']:.2f} s over the wire (ratio x{campaign:.2f}, "
          f"target x2); whole command {med['command_in']:.2f} s vs {med['command_wire']:.2f} s "
          f"(x{command:.2f})")
    print(f"median processor time: in process {med['cpu_in']:.2f} s; over the wire client "
          f"{med['cpu_client']:.2f} s + server {med['cpu_server']:.2f} s = "
          f"{med['cpu_client'] + med['cpu_server']:.2f} s (x"
          f"{(med['cpu_client'] + med['cpu_server']) / med['cpu_in']:.2f}); "
          f"{med['requests']:.0f} requests x {med['pipelined_us']:.0f} us (a trivial request "
          f"pipelined: aiokatcp's and the client's handling) = "
          f"{med['requests'] * med['pipelined_us'] * 1e-6:.2f} s; {med['round_trips']:.0f} "
          f"round trips ({med['round_trips'] / med['scans']:.1f} per scan)")
    print(f"recordings byte-identical in every round: {all(r['identical'] for r in rounds)}")
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    return 0 if all(r["identical"] for r in rounds) else 1


if __name__ == "__main__":
    raise SystemExit(main())

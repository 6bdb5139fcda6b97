"""The project's controller on an antenna over KATCP (antsim.serve.remote, `antsim run
--connect`): the same recordings, to the byte, and an antenna of another epoch refused."""

from __future__ import annotations

import json

import pytest

from antsim.cli import main as cli_main
from antsim.scenario import load_scenario
from antsim.serve.process import ServerProcess
from antsim.serve.remote import connect
from antsim.simulate.runner import run_campaign


def test_controller_over_the_wire_records_the_same_bytes(tmp_path, ghigo_path, capsys):
    """The 24-hour 1990 campaign: `antsim run --connect` against `antsim serve` (virtual
    clock) writes the recordings `antsim run` writes in process, byte for byte; the
    server's truth.json is the in-process run's but for the recoverable truth (what a fit of
    the campaign's scans should recover: the server sees no fit); the server logged every
    request."""
    run_campaign(load_scenario(ghigo_path), tmp_path / "in", show_progress=False)
    with ServerProcess(ghigo_path, out=tmp_path / "server") as srv:
        code = cli_main(["run", str(ghigo_path), "--out", str(tmp_path / "wire"),
                         "--no-report", "--connect", f"127.0.0.1:{srv.port}"])
        assert code == 0
        assert srv.stop() == 0
    assert "truth.json" not in capsys.readouterr().out  # the client has no truth to write
    assert not (tmp_path / "wire" / "truth.json").exists()
    wire = (tmp_path / "wire" / "recordings.ecsv").read_bytes()
    assert wire == (tmp_path / "in" / "recordings.ecsv").read_bytes()
    in_process = json.loads((tmp_path / "in" / "truth.json").read_text())
    assert "recoverable" in in_process
    assert json.loads((tmp_path / "server" / "truth.json").read_text()) == \
        {k: v for k, v in in_process.items() if k != "recoverable"}
    log = [json.loads(line) for line in
           (tmp_path / "server" / "requests.jsonl").read_text().splitlines()]
    requests = int(next(line for line in srv.lines if " after " in line)
                   .split(" after ")[1].split()[0])
    assert len(log) == requests > 5000
    assert {e["request"] for e in log} >= {"track", "offset", "integrate", "powers", "wait"}
    assert all(e["reply"] == "ok" for e in log if e["request"] == "integrate")


@pytest.mark.parametrize(("name", "hours", "what"), [
    ("fomalont1973_x.toml", 6.0, "feed angles"),
    ("fomalont1973_s.toml", 6.0, "feed angles, one channel"),
    ("crane1981_140ft_4990.toml", 6.0, "equatorial mount, idle beyond a track's table"),
    ("wright1992_bima_ant5.toml", 3.0, "optical camera"),
    ("ghigo1990_sensors.toml", 2.0, "structure temperatures read mid-scan"),
])
def test_other_telescopes_over_the_wire(tmp_path, repo_root, write_scenario, name, hours,
                                       what):
    text = (repo_root / "scenarios" / name).read_text(encoding="utf-8")
    old = next(line for line in text.splitlines() if line.startswith("duration_h = "))
    path = write_scenario(text, [(old, f"duration_h = {hours}")], name)
    scenario = load_scenario(path)
    inproc = run_campaign(scenario, tmp_path / "in", show_progress=False)
    assert inproc.n_scans > 10, what
    with ServerProcess(path) as srv:
        antenna, seed = connect(scenario, f"127.0.0.1:{srv.port}")
        with antenna:
            run_campaign(scenario, tmp_path / "wire", seed=seed, show_progress=False,
                         antenna=antenna)
    assert (tmp_path / "wire" / "recordings.ecsv").read_bytes() == \
        (tmp_path / "in" / "recordings.ecsv").read_bytes(), what


def test_connecting_with_another_epoch_is_refused(server, short_ghigo_text, write_scenario,
                                                  tmp_path, capsys):
    """The controller's ephemeris counts time from its scenario's epoch: another epoch
    than the antenna's would point at the wrong sky."""
    path = write_scenario(short_ghigo_text, [('start_utc = "1990-02-08T17:00:00"',
                                              'start_utc = "1990-02-08T18:00:00"')])
    assert cli_main(["run", str(path), "--out", str(tmp_path / "o"), "--connect",
                     f"127.0.0.1:{server.port}"]) == 2
    err = capsys.readouterr().err
    assert "the antenna's epoch is '1990-02-08T17:00:00.000', the scenario's " \
           "'1990-02-08T18:00:00.000'" in err and err.count("\n") == 1
    assert not (tmp_path / "o" / "recordings.ecsv").exists()

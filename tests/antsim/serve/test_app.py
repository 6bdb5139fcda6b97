"""Running the KATCP device until it is stopped (antsim.serve.app): listening on loopback
and saying so, signals, bad options, and `antsim serve --out DIR` with the same protection as
`antsim run --out`. A second session into a directory truncated the first one's request log
(30,253 lines to 1), and ``--seed 99`` into a run's directory replaced its truth.json; a port
in use left both files behind."""

from __future__ import annotations

import json
import signal
import socket
from pathlib import Path

import pytest

from antsim.cli import main
from antsim.cli import main as cli_main
from antsim.serve.process import ServerProcess
from tests.antsim.serve.conftest import LineClient

REPO = Path(__file__).resolve().parents[3]
BASE = REPO / "tests" / "data" / "bad_inputs" / "scenario" / "_base.toml"


def test_a_second_session_keeps_the_firsts_log_and_truth(tmp_path, capsys):
    out = tmp_path / "served"
    with ServerProcess(BASE, out=out) as srv:
        c = LineClient(srv.port)
        for _ in range(25):
            c.request("?clock")
        c.close()
    log = (out / "requests.jsonl").read_bytes()
    truth = (out / "truth.json").read_bytes()
    assert len(log.splitlines()) == 25 and json.loads(truth)["seed"] == 3
    for extra in ([], ["--seed", "99"]):
        assert main(["serve", str(BASE), "--port", "0", "--out", str(out), *extra]) == 2
        err = capsys.readouterr().err.splitlines()
        assert len(err) == 1 and "already holds truth.json requests.jsonl" in err[0]
    assert (out / "requests.jsonl").read_bytes() == log
    assert (out / "truth.json").read_bytes() == truth


def test_a_port_in_use_leaves_the_directory_as_it_was(tmp_path, capsys):
    busy = socket.socket()
    busy.bind(("127.0.0.1", 0))
    busy.listen()
    try:
        out = tmp_path / "served"
        assert main(["serve", str(BASE), "--port", str(busy.getsockname()[1]), "--out",
                     str(out)]) == 2
    finally:
        busy.close()
    assert "address already in use" in capsys.readouterr().err
    assert not out.exists()  # the refused command made it and leaves no trace


def test_listens_on_loopback_and_says_so(server):
    assert server.host == "127.0.0.1"
    listening = next(line for line in server.lines if "listening on" in line)
    assert "loopback only" in listening and "--host 0.0.0.0" in listening


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_signals_stop_the_server_cleanly_with_its_outputs(tmp_path, short_path, sig):
    with ServerProcess(short_path, out=tmp_path) as srv:
        c = LineClient(srv.port)
        c.request("?track 0 200 45 7200 230 60")
        c.request("?integrate 15")
        assert srv.stop(sig) == 0
        c.close()
    assert f"stopped ({sig.name}) after 2 requests" in srv.lines[-1]
    truth = json.loads((tmp_path / "truth.json").read_text())
    assert truth["seed"] == 1 and "W6" in truth["terms"]
    log = [json.loads(line) for line in (tmp_path / "requests.jsonl").read_text().splitlines()]
    assert [e["request"] for e in log] == ["track", "integrate"]
    assert log[1]["reply"] == "ok" and len(log[1]["values"]) == 15


def test_bad_options_give_one_line_and_status_2(tmp_path, short_path, capsys):
    busy = socket.socket()
    busy.bind(("127.0.0.1", 0))
    busy.listen()
    try:
        closed = socket.socket()
        closed.bind(("127.0.0.1", 0))
        free = closed.getsockname()[1]
        closed.close()  # nothing listens there now
        out = str(tmp_path / "o")
        cases = [
            (["serve", str(short_path), "--port", str(busy.getsockname()[1])],
             f"--port = {busy.getsockname()[1]}: address already in use"),
            (["serve", str(short_path), "--clock", "x0"], "--clock = 'x0': use virtual"),
            (["serve", str(short_path), "--port", "70000"], "--port = 70000: must be in"),
            (["serve", str(tmp_path / "missing.toml")], "missing.toml"),
            (["run", str(short_path), "--out", out, "--connect", "nowhere"],
             "--connect = 'nowhere': expected HOST:PORT"),
            (["run", str(short_path), "--out", out, "--seed", "3", "--connect",
              f"127.0.0.1:{free}"], "--seed = True: not with --connect"),
            (["run", str(short_path), "--out", out, "--connect", f"127.0.0.1:{free}"],
             "cannot connect to the antenna"),
        ]
        for argv, expected in cases:
            assert cli_main(argv) == 2, argv
            err = capsys.readouterr().err
            assert err.count("\n") == 1 and "Traceback" not in err, err
            assert expected in err, (expected, err)
    finally:
        busy.close()


def test_serve_has_help(capsys):
    with pytest.raises(SystemExit):
        cli_main(["serve", "--help"])
    out = capsys.readouterr().out
    assert "--clock" in out and "realtime" in out and "127.0.0.1" in out

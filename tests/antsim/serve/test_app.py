"""`antsim serve --out DIR`: the same protection as `antsim run --out`. A second session
into a directory truncated the first one's request log (30,253 lines to 1), and ``--seed
99`` into a run's directory replaced its truth.json; a port in use left both files behind."""

from __future__ import annotations

import json
import socket
from pathlib import Path

from antsim.cli import main
from antsim.serve.process import ServerProcess
from tests.antsim.serve.test_serve import LineClient

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

"""`antsim serve --requests`: the request list, from the device's own handlers, reachable
from an installed wheel (which does not carry docs/katcp.md)."""

from __future__ import annotations

import re
from pathlib import Path

from antsim.cli import main
from antsim.serve.device import AntennaDevice

REPO = Path(__file__).resolve().parents[3]


def test_the_list_has_every_request_the_device_serves_with_its_meaning(capsys):
    assert main(["serve", "--requests"]) == 0
    text = capsys.readouterr().out
    for name, handler in AntennaDevice._request_handlers.items():
        assert re.search(rf"^\?{re.escape(name)}\b", text, re.M), name
        first = (handler.__doc__ or "").strip().splitlines()[0]
        assert first in text, name
    # the device's own requests say what they command or read, with arguments and reply
    assert re.search(r"^\?offset \(command\)\n    Offset from the track: \?offset DAZ DEL "
                     r"\(encoder deg\) -> clock, move\+settle s\.", text, re.M)
    assert "?clock (reading)" in text and "Conventions:" in text


def test_the_list_names_every_request_of_docs_katcp(capsys):
    """docs/katcp.md's request table and the printed list name the same requests."""
    assert main(["serve", "--requests"]) == 0
    printed = set(re.findall(r"^\?([\w-]+)", capsys.readouterr().out, re.M))
    page = (REPO / "docs" / "katcp.md").read_text(encoding="utf-8")
    table = set(re.findall(r"^\| `\?([\w-]+)` \|", page, re.M))
    assert table and table <= printed
    own = {n for n, h in AntennaDevice._request_handlers.items() if hasattr(h, "antsim_kind")}
    assert own == table


def test_without_a_scenario_or_requests_is_one_line(capsys):
    assert main(["serve"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "SCENARIO" in err[0] and "--requests" in err[0]


def test_an_installed_wheel_prints_the_list(installed, tmp_path):
    listing = installed.run("antsim serve --requests", cwd=tmp_path)
    assert listing.returncode == 0, listing.stderr
    assert "?integrate (command)" in listing.stdout
    assert "?structure-temperatures (reading)" in listing.stdout

"""Recordings' headers read as plain data: bounded, no YAML references, no key twice."""

from __future__ import annotations

from pathlib import Path

import pytest

from controller.errors import InputError
from controller.program import recordings
from controller.program.recordings import read_recordings, recorded_mount

BASE = Path(__file__).resolve().parents[2] / "data" / "bad_inputs" / "ecsv" / "_base.ecsv"


def test_a_header_beyond_the_bound_is_refused_before_it_is_parsed(tmp_path, monkeypatch):
    text = BASE.read_text(encoding="utf-8")
    monkeypatch.setattr(recordings, "MAX_HEADER_BYTES", 2000)
    with pytest.raises(InputError, match="is larger than 0 MiB: not a recordings header"):
        read_recordings(BASE, text=text)


def test_an_alias_bomb_is_refused_and_the_quick_look_at_the_mount_is_not_fooled(tmp_path):
    text = BASE.read_text(encoding="utf-8")
    bomb = "".join(["# - lol0: &a0 [x, x, x, x, x, x, x, x, x]\n"]
                   + [f"# - lol{k}: &a{k} [" + ", ".join([f"*a{k - 1}"] * 9) + "]\n"
                      for k in range(1, 10)] + ["# - mount: *a9\n"])
    path = tmp_path / "bomb.ecsv"
    path.write_text(text.replace("# meta: !!omap\n", "# meta: !!omap\n" + bomb), encoding="utf-8")
    with pytest.raises(InputError, match="is a YAML anchor or alias"):
        read_recordings(path)
    assert recorded_mount(path) is None  # the quick look says "unknown", never expands it
    assert recorded_mount(BASE) == "altaz"


def test_the_base_recordings_still_read():
    table = read_recordings(BASE)
    assert len(table) == 36 and table.meta["site"]["latitude_deg"] == 38.43

"""Recordings (controller.program.recordings): headers read as plain data (bounded, no YAML
references, no key twice, PyYAML's safe loader where astropy's would give the same), and the
fast reader giving astropy's table."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from astropy.table import Table

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


def test_the_fast_ecsv_reader_reads_what_astropys_reads():
    """antsim's own recordings go through numpy's reader, anything else through astropy's:
    the same table either way (decimal text parsed correctly rounded by both: equal to the
    bit on any machine), and a layout the fast reader does not know goes to astropy's."""
    from controller.program.recordings import _fast_table

    text = BASE.read_text(encoding="utf-8")
    fast, lines = _fast_table(text, len(text))
    slow = Table.read(text, format="ascii.ecsv")
    assert fast.colnames == slow.colnames and len(fast) == len(slow) == 36
    for name in fast.colnames:
        assert fast[name].dtype.kind == slow[name].dtype.kind, name
        np.testing.assert_array_equal(np.asarray(fast[name]), np.asarray(slow[name]), name)
        assert fast[name].unit == slow[name].unit, name
    assert dict(fast.meta) == dict(slow.meta)
    assert text.splitlines()[lines[0] - 1].startswith("0 ")  # the first scan's first row
    # a blank line (first, inside, last): not the plain layout
    names = next(line for line in text.splitlines() if not line.startswith("#"))
    for blank in (text.replace("\n0 ", "\n\n0 ", 1), text.replace(names, names + "\n", 1),
                  text + "\n"):
        assert blank.count("\n\n") == 1
        assert _fast_table(blank, len(blank)) is None


def test_the_ecsv_header_is_read_as_astropys_yaml_loader_reads_it():
    """The recordings' YAML header through PyYAML's safe loader (astropy's loader is it with
    tags added; importing astropy's imports astropy.coordinates): the same objects as
    astropy's loader for antsim's header, and a header with astropy's own tags (a unit, a
    tuple) or a malformed one goes to astropy's loader: its objects, its error."""
    import yaml
    from astropy.io.misc.yaml import load

    from controller.program.recordings import _yaml_header

    header = [line for line in BASE.read_text(encoding="utf-8").splitlines()
              if line.startswith("#")][1:]
    body = "\n".join(line[2:] if line.startswith("# ") else line[1:] for line in header)
    assert "!!omap" in body
    got = _yaml_header(header)
    assert got == load(body) and dict(got["meta"])["site"] == dict(load(body)["meta"])["site"]
    tagged = [*header, "# extra: !astropy.units.Unit {unit: arcmin}",
              "# pair: !!python/tuple [1, 2]"]
    with pytest.raises(yaml.YAMLError):  # the safe loader alone refuses these tags
        yaml.load("\n".join(line[2:] for line in tagged), Loader=yaml.SafeLoader)
    got = _yaml_header(tagged)
    assert str(got["extra"]) == "arcmin" and got["pair"] == (1, 2)
    assert got == load("\n".join(line[2:] for line in tagged))
    with pytest.raises(yaml.YAMLError):  # malformed: astropy's loader says so
        _yaml_header(["# meta: [1, 2"])

"""Recordings (controller.program.recordings): headers read as plain data (bounded, no YAML
references, no key twice, PyYAML's safe loader where astropy's would give the same), and the
fast reader giving astropy's table."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from astropy.table import Table

from antsim.simulate.runner import run_campaign
from controller.errors import InputError
from controller.program import recordings
from controller.program.recordings import (
    COLUMN_NAMES,
    read_pointing_data,
    read_recordings,
    recorded_mount,
)

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


def test_recordings_round_trip(ghigo, tmp_path):
    sc = replace(ghigo, duration_s=2 * 3600.0,
                 controller=replace(ghigo.controller, duration_s=2 * 3600.0))
    result = run_campaign(sc, tmp_path, show_progress=False)
    table = read_recordings(tmp_path / "recordings.ecsv")
    assert tuple(table.colnames) == COLUMN_NAMES
    assert len(table) == len(result.rows)
    for i, row in enumerate(result.rows):
        for name in COLUMN_NAMES:
            value = table[name][i]
            if isinstance(row[name], float):
                assert float(value) == row[name] or (math.isnan(row[name])
                                                     and math.isnan(float(value)))
            else:
                assert value == row[name]
    assert table["xel_arcmin"].unit == "arcmin"
    meta = table.meta
    assert meta["scenario"] == "ghigo1990" and meta["seed"] == sc.seed
    assert meta["model"]["name"] == "ghigo10"
    assert meta["model"]["terms_arcsec"]["W6"] == pytest.approx(720.0)
    assert meta["model"]["w_terms"] == "Ghigo 1990 (NRAO EDIR 288) section II"
    assert meta["step_arcmin"] == 7.0 and meta["beam_hpbw_arcmin"] == 11.0
    # total pointing error = measured + model in use + applied correction
    data = read_pointing_data(tmp_path / "recordings.ecsv")
    avg = [r for r in result.rows if r["polarization"] == "AVG" and r["good"]]
    expected_el = [60 * (r["el_arcmin"] + r["model_el_arcmin"] + r["applied_el_arcmin"])
                   for r in avg]
    assert np.allclose(data.el_arcsec, expected_el)


def test_resume_after_a_torn_write_is_byte_identical(ghigo, tmp_path):
    sc = replace(ghigo, duration_s=2 * 3600.0,
                 controller=replace(ghigo.controller, duration_s=2 * 3600.0))
    full = tmp_path / "full"
    run_campaign(sc, full, show_progress=False)
    reference = (full / "recordings.ecsv").read_bytes()
    names_line = reference.index(b"\nscan ") + 1
    header_end = reference.index(b"\n", names_line) + 1  # first byte of the first data row
    body_lines = reference[header_end:].count(b"\n")
    assert body_lines > 20
    rng = np.random.default_rng(7)
    # cut the file anywhere: inside the header, mid-line, exactly at a line end
    cuts = [header_end - 5, header_end + 10, reference.index(b"\n", header_end + 2000) + 1,
            *rng.integers(header_end, len(reference) - 1, size=3)]
    for cut in cuts:
        part = tmp_path / f"cut{cut}"
        part.mkdir()
        (part / "recordings.ecsv").write_bytes(reference[:cut])
        if cut < header_end:
            # a torn header is not this run's header: resuming refuses, it does not guess
            from controller.errors import InputError

            with pytest.raises(InputError):
                run_campaign(sc, part, resume=True, show_progress=False)
            continue
        # what is on disk is readable up to the last complete row
        table = read_recordings(part / "recordings.ecsv")
        assert len(table) == reference[header_end:cut].count(b"\n")
        run_campaign(sc, part, resume=True, show_progress=False)
        assert (part / "recordings.ecsv").read_bytes() == reference


def test_resume_refuses_another_runs_file(ghigo, tmp_path):
    from controller.program.recordings import ResumeMismatchError

    sc = replace(ghigo, duration_s=1 * 3600.0,
                 controller=replace(ghigo.controller, duration_s=1 * 3600.0))
    run_campaign(sc, tmp_path, seed=1, show_progress=False)
    text = (tmp_path / "recordings.ecsv").read_text()
    # same header (same seed), but a tampered data row
    lines = text.splitlines(keepends=True)
    lines[-1] = lines[-1].replace("AVG", "XR", 1)
    (tmp_path / "recordings.ecsv").write_text("".join(lines))
    with pytest.raises(ResumeMismatchError):
        run_campaign(sc, tmp_path, seed=1, resume=True, show_progress=False)

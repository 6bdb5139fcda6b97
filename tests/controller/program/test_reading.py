"""Inputs read as they say: units converted, CSV in every documented form, byte-order marks
dropped, output directories locked and never overwritten, summaries naming only what was
written, and docs/inputs.md's column tables the readers' own (the recordings' fast reader is
tested in test_recordings.py).

(Bad input of every kind, one line and exit 2, is tests/end_to_end/test_bad_inputs.py.)
"""

from __future__ import annotations

import json
import os
import pickle
import re
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from astropy.table import Table

from antsim.cli import main
from controller.errors import InputError

REPO = Path(__file__).resolve().parents[3]
DATA = REPO / "tests" / "data" / "bad_inputs"
ECSV = DATA / "ecsv" / "_base.ecsv"
CSV = DATA / "csv" / "_base.csv"
BASE = DATA / "scenario" / "_base.toml"


def fit_json(capsys, *args) -> dict:
    assert main(["fit", *map(str, args), "--json"]) == 0, capsys.readouterr().err
    return json.loads(capsys.readouterr().out)


def values(doc: dict) -> np.ndarray:
    return np.array([t["value_arcsec"] for t in doc["terms"].values()])


# ---------------------------------------------------------------------------------------------
# units
def test_recordings_in_other_units_fit_the_same(tmp_path, capsys):
    """Positions in rad, offsets in arcsec, temperatures in K: converted on reading, so the
    fit is the one of the file in the units of the column names."""
    table = Table.read(ECSV, format="ascii.ecsv")
    for name in ("az_deg", "el_deg"):
        table[name] = np.radians(table[name])
        table[name].unit = "rad"
    for name in ("xel_arcmin", "el_arcmin", "model_xel_arcmin", "applied_el_arcmin"):
        table[name] = table[name] * 60.0
        table[name].unit = "arcsec"
    table["air_temp_c"] = table["air_temp_c"] + 273.15
    table["air_temp_c"].unit = "K"
    converted = tmp_path / "converted.ecsv"
    table.write(converted, format="ascii.ecsv")
    # rad -> deg -> rad and arcsec -> arcmin round: 1e-9" is 1e4 times below the last digit
    # the fit's values carry in fit.json's print
    np.testing.assert_allclose(values(fit_json(capsys, converted)),
                               values(fit_json(capsys, ECSV)), rtol=0, atol=1e-9)
    from controller.program.recordings import read_recordings

    back = read_recordings(converted)
    np.testing.assert_allclose(back["air_temp_c"], Table.read(ECSV, format="ascii.ecsv")[
        "air_temp_c"], atol=1e-9)
    assert str(back["az_deg"].unit) == "deg"


def test_recordings_without_units_are_in_the_units_of_their_names(tmp_path, capsys):
    table = Table.read(ECSV, format="ascii.ecsv")
    for name in table.colnames:
        table[name].unit = None
    bare = tmp_path / "bare.ecsv"
    table.write(bare, format="ascii.ecsv")
    np.testing.assert_array_equal(values(fit_json(capsys, bare)), values(fit_json(capsys, ECSV)))


def test_a_missing_optional_column_is_named_in_a_note(tmp_path, capsys):
    table = Table.read(ECSV, format="ascii.ecsv")
    table.remove_column("good")
    path = tmp_path / "no_good.ecsv"
    table.write(path, format="ascii.ecsv")
    assert main(["fit", str(path)]) == 0
    err = capsys.readouterr().err.splitlines()
    assert err == [f"antsim fit: note: {path}: no column good: every row with finite offsets "
                   "is used"]


# ---------------------------------------------------------------------------------------------
# CSV
def _csv_rows():
    lines = CSV.read_text(encoding="utf-8").splitlines()
    names = next(i for i, line in enumerate(lines) if not line.startswith("#"))
    return [line.split(",") for line in lines[names + 1:]]


def test_csv_fits_as_the_recordings_it_was_made_from(capsys):
    """The base CSV holds the AVG rows of the base recordings, their total errors printed to
    0.01": the fits agree to what that rounding moves (< 0.05" on coefficients whose
    sigmas are 25-190")."""
    csv_fit = fit_json(capsys, CSV, "--model", "ghigo10")
    ecsv_fit = fit_json(capsys, ECSV)
    assert csv_fit["n_input"] == ecsv_fit["n_input"] == 12
    np.testing.assert_allclose(values(csv_fit), values(ecsv_fit), rtol=0, atol=0.05)


def test_csv_sign_units_and_offset_columns_in_every_documented_form(tmp_path, capsys):
    """TPOINT's sign, radians and arcmin through the units setting given on the command line,
    and d_az instead of d_xel, all give the fit of the base file (to float rounding)."""
    rows = _csv_rows()
    reference = values(fit_json(capsys, CSV, "--model", "ghigo10"))
    other = tmp_path / "other.csv"
    lines = ["time,az,el,d_az,d_el,source"]
    for time_, az, el, dxel, d_el, source, _ in rows:
        d_az = float(dxel) / float(np.cos(np.radians(float(el))))
        lines.append(f"{time_}Z,{float(np.radians(float(az)))!r},{el},{-d_az / 60.0!r},"
                     f"{-float(d_el) / 60.0!r},{source}")
    other.write_text("\n".join(lines) + "\n", encoding="utf-8")
    got = values(fit_json(capsys, other, "--model", "ghigo10",
                          "--csv", "sign: true-minus-indicated",
                          "--csv", "units: az=rad el=deg d_az=arcmin d_el=arcmin"))
    np.testing.assert_allclose(got, reference, rtol=0, atol=1e-9)


def test_csv_structure_temperatures_are_the_recordings_sensor_readings(tmp_path):
    """temp_<sensor> in any temperature unit becomes the recordings' one-reading column
    temp_<sensor>_c in Celsius, which the thermal terms read as the sensor's reading."""
    from controller.program.csvdata import pointing_data, read_csv

    rows = _csv_rows()
    path = tmp_path / "temps.csv"
    lines = ["# sign: indicated-minus-true", "az_deg,el_deg,d_xel_arcsec,d_el_arcsec,"
             "temp_dish_front_k,temp_dish_back_c"]
    lines += [f"{r[1]},{r[2]},{r[3]},{r[4]},{280.15 + i},{5.0 - i}" for i, r in enumerate(rows)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    data = read_csv(path)
    front, back = 7.0 + np.arange(len(rows)), 5.0 - np.arange(len(rows))
    np.testing.assert_allclose(data.columns["temp_dish_front_c"], front)
    np.testing.assert_allclose(data.columns["temp_dish_back_c"], back)
    assert "t_s" not in data.columns  # no time column: no times made up
    aux = pointing_data(data).aux
    assert set(aux) == {"dish_front", "dish_back"}
    np.testing.assert_allclose(aux["dish_front"], [front, front])  # both halves: one reading


# ---------------------------------------------------------------------------------------------
# byte-order marks
def test_a_byte_order_mark_is_dropped_from_every_text_input(tmp_path, capsys):
    """Editors on Windows write one; TPOINT data, scenarios and CSV read the same with it."""
    for source in (DATA / "tpoint" / "_base.dat", CSV):
        marked = tmp_path / ("bom_" + source.name)
        marked.write_bytes(b"\xef\xbb\xbf" + source.read_bytes())
        assert fit_json(capsys, marked) == fit_json(capsys, source)
    from antsim.scenario import load_scenario

    marked = tmp_path / "bom.toml"
    marked.write_bytes(b"\xef\xbb\xbf" + BASE.read_bytes())
    assert load_scenario(marked).name == load_scenario(BASE).name


# ---------------------------------------------------------------------------------------------
# errors survive the machinery they pass through
def test_an_input_error_survives_simpy_and_a_process_pool():
    """simpy re-raises a process's exception as type(err)(*err.args), a process pool
    pickles it: both must give back the same one line."""
    from controller.program.recordings import ResumeMismatchError

    for err in (InputError("f.toml", "a.b", 3.5, "must be small", "make it smaller"),
                ResumeMismatchError("out/recordings.ecsv", 12, "12 some row")):
        assert type(err)(*err.args).line() == err.line()
        assert pickle.loads(pickle.dumps(err)).line() == err.line()


# ---------------------------------------------------------------------------------------------
# output directories
def _run_cmd(scenario: Path, out: Path, *extra: str) -> list[str]:
    return [sys.executable, "-m", "antsim", "run", str(scenario), "--out", str(out),
            "--no-report", "--no-progress", *extra]


def test_two_runs_into_one_directory_one_is_refused(tmp_path, repo_root):
    """Started together, one run takes the directory; the other is refused with one line
    and exit 2 and writes nothing there: the files are the first run's alone."""
    env = dict(os.environ, PYTHONPATH=str(repo_root))
    out = tmp_path / "shared"
    procs = [subprocess.Popen(_run_cmd(BASE, out, "--seed", str(seed)), env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for seed in (1, 2)]
    results = [(p.wait(timeout=300), *p.communicate()) for p in procs]
    codes = sorted(r[0] for r in results)
    assert codes == [0, 2], results
    winner = next(seed for seed, r in zip((1, 2), results, strict=True) if r[0] == 0)
    loser = next(r for r in results if r[0] == 2)
    assert len(loser[2].splitlines()) == 1 and "--out" in loser[2]
    assert ("is in use by another antsim process" in loser[2]
            or "already holds recordings.ecsv" in loser[2])
    fresh = tmp_path / "fresh"
    subprocess.run(_run_cmd(BASE, fresh, "--seed", str(winner)), env=env, check=True,
                   capture_output=True)
    for name in ("recordings.ecsv", "truth.json", "fit.json", "model.dat"):
        assert (out / name).read_bytes() == (fresh / name).read_bytes(), name


@pytest.mark.skipif(sys.platform == "win32", reason="flock and SIGKILL")
def test_a_lock_dies_with_its_holder_even_under_kill_9(tmp_path, repo_root):
    """The lock is the kernel's: a holder killed with SIGKILL leaves nothing to clean up."""
    from antsim.outdir import DirectoryLock

    out = tmp_path / "held"
    out.mkdir()
    code = ("import sys, time; from antsim.outdir import DirectoryLock; "
            f"lock = DirectoryLock({str(out)!r}, command='holder').__enter__(); "
            "print('held', flush=True); time.sleep(600)")
    env = dict(os.environ, PYTHONPATH=str(repo_root))
    holder = subprocess.Popen([sys.executable, "-c", code], env=env, stdout=subprocess.PIPE,
                              text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        with pytest.raises(InputError, match=rf"in use by another antsim process \(pid "
                                             rf"{holder.pid}: holder\)"):
            DirectoryLock(out).__enter__()
    finally:
        holder.send_signal(signal.SIGKILL)
        holder.wait(timeout=30)
    with DirectoryLock(out, command="next"):
        assert (out / ".antsim.lock").read_text().split("\t")[0] == str(os.getpid())


@pytest.fixture(scope="module")
def no_fit_scenario(tmp_path_factory) -> Path:
    """The base scenario with a detection threshold no scan reaches: every scan flagged."""
    path = tmp_path_factory.mktemp("nofit") / "nofit.toml"
    path.write_text(BASE.read_text(encoding="utf-8").replace("snr_min = 4.0",
                                                             "snr_min = 1e9"), encoding="utf-8")
    return path


def test_a_run_without_a_fit_names_only_the_files_it_wrote(no_fit_scenario, tmp_path, capsys):
    out = tmp_path / "nofit"
    assert main(["run", str(no_fit_scenario), "--out", str(out), "--no-report",
                 "--no-progress"]) == 0
    summary = capsys.readouterr().out
    assert "(0 good)" in summary and "no fit A" in summary
    written = summary.splitlines()[-1].split(": ", 1)[1].split()
    assert "model.dat" not in written and "fit.json" not in written
    assert sorted(written) == sorted(p.name for p in out.iterdir() if p.name != ".antsim.lock")


def test_resume_removes_the_products_it_cannot_make_again(no_fit_scenario, tmp_path, capsys):
    """A stale model.dat must not pass as the resumed run's output: a resumed run whose
    recordings can no longer be fitted leaves no fit.json, model.dat or report behind."""
    out = tmp_path / "resumed"
    assert main(["run", str(no_fit_scenario), "--out", str(out), "--no-report",
                 "--no-progress"]) == 0
    recorded = (out / "recordings.ecsv").read_bytes()
    for name in ("model.dat", "fit.json", "report.html"):
        (out / name).write_text("an earlier run's\n", encoding="utf-8")
    (out / "figures").mkdir()
    (out / "mine.txt").write_text("the user's own file\n", encoding="utf-8")
    capsys.readouterr()
    assert main(["run", str(no_fit_scenario), "--out", str(out), "--no-report", "--resume",
                 "--no-progress"]) == 0
    capsys.readouterr()
    assert (out / "recordings.ecsv").read_bytes() == recorded
    for name in ("model.dat", "fit.json", "report.html", "figures"):
        assert not (out / name).exists(), name
    assert (out / "mine.txt").exists()


def test_a_run_failing_before_its_first_scan_leaves_no_recordings(tmp_path, monkeypatch,
                                                                  capsys):
    """Whatever stops a run before it records a scan, the same --out takes a plain re-run."""
    from antsim.simulate import runner

    def broken(*args, **kwargs):
        raise RuntimeError("the simulation broke before its first scan (test)")

    monkeypatch.setattr(runner, "simulate", broken)
    out = tmp_path / "early"
    with pytest.raises(RuntimeError, match="before its first scan"):
        main(["run", str(BASE), "--out", str(out), "--no-progress"])
    assert not (out / "recordings.ecsv").exists()


# ---------------------------------------------------------------------------------------------
# docs/inputs.md
def _doc_table(marker: str) -> list[list[str]]:
    text = (REPO / "docs" / "inputs.md").read_text(encoding="utf-8")
    block = text.split(f"<!-- {marker}:", 1)[1].split(f"<!-- end {marker} -->", 1)[0]
    rows = [line for line in block.splitlines() if line.startswith("| `")]
    return [[cell.strip() for cell in row.strip("|").split("|")] for row in rows]


def test_the_documented_ecsv_columns_are_the_readers(tmp_path):
    from controller.pointing.thermal import STRUCTURE_SENSORS
    from controller.program.recordings import (
        COLUMNS,
        EXTRA_COLUMNS,
        OPTIONAL,
        REQUIRED,
        SENSOR_COLUMNS,
    )

    text = (REPO / "docs" / "inputs.md").read_text(encoding="utf-8")
    sensors = text.split("<!-- sensors -->", 1)[1].split("<!-- end sensors -->", 1)[0]
    assert re.findall(r"`([a-z_]+)`", sensors) == list(STRUCTURE_SENSORS)
    documented = {}
    for name, unit, rng, required in _doc_table("ecsv-columns"):
        names = re.findall(r"`([a-z_0-9<>]+)`", name)
        if "..." in name:  # p_az_m4 ... p_el_p4: the ten raw powers
            names = [c.name for c in COLUMNS if c.name.startswith("p_")]
        names = [n.replace("<sensor>", s) for n in names
                 for s in (STRUCTURE_SENSORS if "<sensor>" in n else ("",))]
        for n in names:
            documented[n] = (unit, rng, required)
    columns = {c.name: c for c in (*COLUMNS, *EXTRA_COLUMNS.values(), *SENSOR_COLUMNS.values())}
    assert set(documented) == set(columns)
    for name, col in columns.items():
        unit, rng, required = documented[name]
        assert unit == (col.unit or "-"), name
        parts = []
        if col.lo is not None:
            parts.append(f"{col.lo:g}..{col.hi:g}")
        if col.finite:
            parts.append("finite")
        assert rng == (", ".join(parts) or "-"), name
        if name in REQUIRED:
            assert required == "yes", name
        if name in OPTIONAL:
            assert OPTIONAL[name] in required, name
    assert documented["t_s"][2] == "by diagnose"


def test_the_documented_csv_columns_are_the_readers():
    from controller.program.csvdata import CSV_COLUMNS

    text = (REPO / "docs" / "inputs.md").read_text(encoding="utf-8")
    table = text.split("## Your own measurements")[1].split("**The offsets**")[0]
    documented = re.findall(r"^\| `([a-z_<>]+)` \|", table, re.M)
    assert [n for n in documented if n != "temp_<sensor>"] == list(CSV_COLUMNS)
    required = [n for n, c in CSV_COLUMNS.items() if c.required]
    for name in required:
        assert re.search(rf"^\| `{name}` \|.*\| yes \|$", text, re.M), name


def test_the_documented_case_count_is_the_suites():
    import tomllib

    cases = tomllib.loads((DATA / "expectations.toml").read_text(encoding="utf-8"))["case"]
    text = (REPO / "docs" / "inputs.md").read_text(encoding="utf-8")
    claimed = int(re.search(r"runs more than (\d+) such inputs", text).group(1))
    assert len(cases) > claimed >= len(cases) - 50


def test_a_full_disk_mid_run_is_one_line_and_keeps_the_scans_written(tmp_path, monkeypatch,
                                                                      capsys):
    """The file system refusing a write (ENOSPC on the 4th scan) is one line and exit 2; the
    three scans written before it read back."""
    import errno

    from controller.program import recordings

    real_write = os.write
    calls = {"n": 0}

    def write(fd, data):
        if data.startswith(b"# %ECSV"):
            return real_write(fd, data)
        calls["n"] += 1
        if calls["n"] == 4:
            raise OSError(errno.ENOSPC, "No space left on device", "recordings.ecsv")
        return real_write(fd, data)

    monkeypatch.setattr(recordings.os, "write", write)
    out = tmp_path / "full"
    assert main(["run", str(BASE), "--out", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err == [f"antsim run: error: {out / 'recordings.ecsv'}: rows = 3: cannot be written: "
                   "No space left on device; the scans written before them are kept"]
    monkeypatch.undo()
    table = recordings.read_recordings(out / "recordings.ecsv")
    assert len(set(table["scan"])) == 3


def test_a_truncated_diagnose_cache_file_is_a_miss(tmp_path):
    """A cached baseline simulation cut short (a full disk, a killed writer) is simulated
    again, not a BadZipFile traceback: the same products, and the file whole again."""
    from antsim.diagnose.baseline import SimulatedBaseline
    from antsim.scenario import load_scenario

    scenario = load_scenario(BASE)
    first = SimulatedBaseline(scenario, ("W1", "W6"), n_sims=2, cache_dir=tmp_path, jobs=1)
    (cached, *_) = sorted(tmp_path.glob("baseline-*.npz"))
    whole = cached.read_bytes()
    cached.write_bytes(whole[: len(whole) // 2])
    from controller.errors import Note

    with pytest.warns(Note, match="BadZipFile"):  # said in one note, then simulated again
        again = SimulatedBaseline(scenario, ("W1", "W6"), n_sims=2, cache_dir=tmp_path,
                                  jobs=1)
    for a, b in zip(first.products, again.products, strict=True):
        np.testing.assert_array_equal(a.res, b.res)  # one code path, same seed: same bytes
    assert cached.read_bytes() == whole


def test_diagnose_reads_csv_as_the_recordings_it_was_made_from(capsys):
    """antsim diagnose on the base CSV (the AVG rows of the base recordings, printed to
    0.01") reports the residuals of the recordings to what that rounding moves (< 0.01" on
    rms of 7-22")."""
    summaries = []
    for path in (CSV, ECSV):
        assert main(["diagnose", str(path), "--model", "ghigo10", "--json", "--no-progress",
                     "--no-cache"]) == 0
        summaries.append(json.loads(capsys.readouterr().out)["summary"])
    csv_sum, ecsv_sum = summaries
    assert csv_sum["n_used"] == ecsv_sum["n_used"] == 12
    for key in ("sky_rms_before_arcsec", "cv_sky_rms_before_arcsec"):
        assert csv_sum[key] == pytest.approx(ecsv_sum[key], abs=0.01)
    np.testing.assert_allclose(csv_sum["axis_rms_before_arcsec"],
                               ecsv_sum["axis_rms_before_arcsec"], rtol=0, atol=0.01)

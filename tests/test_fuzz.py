"""Generated input for the readers: TPOINT data and models, ECSV recordings, CSV measurements,
scenario and plan TOML. Whatever the input, a reader returns or raises InputError, the one
line the command line prints; and through the command line the answer is exit 0 or one line
with exit 2, never a traceback.

Inputs are the valid base files of tests/data/bad_inputs with random edits (a token replaced
by a number of any size, NaN, infinity, text or nothing; lines deleted, repeated or cut;
bytes changed), plus free text for the line-oriented formats. The examples are drawn from a
fixed seed (``derandomize``), the same on every machine and every run, few enough for the
suite's time (``FUZZ_EXAMPLES`` per reader, 30); ``ANTSIM_FUZZ_EXAMPLES=2000`` searches
longer with fresh randomness each run.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from antsim.cli import main
from controller.errors import InputError

DATA = Path(__file__).resolve().parent / "data" / "bad_inputs"
HEAVY = "ANTSIM_FUZZ_EXAMPLES" in os.environ
FUZZ_EXAMPLES = int(os.environ.get("ANTSIM_FUZZ_EXAMPLES", "30"))
FUZZ = settings(max_examples=FUZZ_EXAMPLES, deadline=None, derandomize=not HEAVY,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture,
                                       HealthCheck.data_too_large])

#: what a token may become: numbers of every size and sign, the special floats, text
REPLACEMENTS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(min_value=-10**30, max_value=10**30).map(str),
    st.sampled_from(["nan", "inf", "-inf", "1e999", "-1e-999", "", " ", "''", '"', "#", ",",
                     ";", ":", "!", "=", "[", "]", "{", "}", "END", "True", "null", "\t",
                     "é", "\u00a0", "0x10", "1_0", "--"]),
    st.text(max_size=12),
)


@st.composite
def edited(draw, text: str) -> str:
    """``text`` with 1-4 random edits of its tokens and lines."""
    lines = text.split("\n")
    for _ in range(draw(st.integers(1, 4))):
        i = draw(st.integers(0, len(lines) - 1))
        kind = draw(st.sampled_from(["token", "token", "token", "delete", "repeat", "cut",
                                     "swap"]))
        if kind == "token":
            tokens = lines[i].split(" ")
            j = draw(st.integers(0, len(tokens) - 1))
            tokens[j] = draw(REPLACEMENTS)
            lines[i] = " ".join(tokens)
        elif kind == "delete" and len(lines) > 1:
            del lines[i]
        elif kind == "repeat":
            lines.insert(i, lines[i])
        elif kind == "cut":
            lines[i] = lines[i][: draw(st.integers(0, len(lines[i])))]
        elif kind == "swap":
            j = draw(st.integers(0, len(lines) - 1))
            lines[i], lines[j] = lines[j], lines[i]
    return "\n".join(lines)


def _comma_tokens(text: str) -> str:
    """CSV and TOML edits split on spaces; make the CSV's fields space-separated tokens too,
    then back."""
    return text.replace(",", " ,")


def _write(tmp_path: Path, name: str, data: str | bytes) -> Path:
    path = tmp_path / name
    if isinstance(data, str):
        path.write_text(data, encoding="utf-8", errors="surrogatepass")
    else:
        path.write_bytes(data)
    return path


def _one_line_or_success(capsys, argv: list[str]) -> None:
    status = main(argv)
    err = capsys.readouterr().err
    assert status in (0, 2), err
    if status == 2:
        lines = [line for line in err.splitlines() if "note:" not in line]
        assert len(lines) == 1 and "error: " in lines[0], err


def _fuzz_file(tmp_path_factory, name: str, data):
    return _write(tmp_path_factory.mktemp("fuzz"), name, data)


# ---------------------------------------------------------------------------------------------
# TPOINT data and models
TPOINT = (DATA / "tpoint" / "_base.dat").read_text(encoding="utf-8")
MOD = (DATA / "model" / "_base.mod").read_text(encoding="utf-8")


@FUZZ
@given(text=st.one_of(edited(TPOINT), st.text(max_size=400)))
def test_tpoint_data_reader(text):
    from controller.pointing.tpoint import parse_tpoint

    with contextlib.suppress(InputError):
        data = parse_tpoint(text, source="fuzz.dat")
        data.pointing_data()


@FUZZ
@given(text=st.one_of(edited(MOD), st.text(max_size=300)))
@pytest.mark.filterwarnings("ignore::UserWarning")  # W terms renamed: a note, not a failure
def test_tpoint_model_reader(text):
    from controller.pointing.tpoint import parse_mod

    with contextlib.suppress(InputError):
        parse_mod(text, source="fuzz.mod")


@FUZZ
@given(text=edited(TPOINT))
def test_tpoint_data_through_antsim_fit(text, tmp_path_factory, capsys):
    path = _fuzz_file(tmp_path_factory, "fuzz.dat", text)
    _one_line_or_success(capsys, ["fit", str(path), "--json"])


# ---------------------------------------------------------------------------------------------
# ECSV recordings
ECSV = (DATA / "ecsv" / "_base.ecsv").read_text(encoding="utf-8")


@FUZZ
@given(text=edited(ECSV))
def test_ecsv_reader(text, tmp_path_factory):
    from controller.program.recordings import read_recordings, table_pointing_data

    path = _fuzz_file(tmp_path_factory, "fuzz.ecsv", text)
    with contextlib.suppress(InputError):
        table_pointing_data(read_recordings(path), str(path))


@FUZZ
@given(text=edited(ECSV))
def test_ecsv_through_antsim_fit(text, tmp_path_factory, capsys):
    path = _fuzz_file(tmp_path_factory, "fuzz.ecsv", text)
    _one_line_or_success(capsys, ["fit", str(path), "--json"])


@FUZZ
@given(data=st.binary(max_size=600))
def test_bytes_through_antsim_fit(data, tmp_path_factory, capsys):
    path = _fuzz_file(tmp_path_factory, "fuzz.ecsv", b"# %ECSV 1.0\n" + data)
    _one_line_or_success(capsys, ["fit", str(path)])


# ---------------------------------------------------------------------------------------------
# CSV measurements
CSV = _comma_tokens((DATA / "csv" / "_base.csv").read_text(encoding="utf-8"))


@FUZZ
@given(text=st.one_of(edited(CSV).map(lambda t: t.replace(" ,", ",")), st.text(max_size=300)))
def test_csv_reader(text, tmp_path_factory):
    from controller.program.csvdata import pointing_data, read_csv

    path = _fuzz_file(tmp_path_factory, "fuzz.csv", text)
    with contextlib.suppress(InputError):
        pointing_data(read_csv(path))


@FUZZ
@given(text=edited(CSV).map(lambda t: t.replace(" ,", ",")))
def test_csv_through_antsim_fit(text, tmp_path_factory, capsys):
    path = _fuzz_file(tmp_path_factory, "fuzz.csv", text)
    _one_line_or_success(capsys, ["fit", str(path), "--json"])


# ---------------------------------------------------------------------------------------------
# TOML: scenarios and plans
SCENARIO = (DATA / "scenario" / "_base.toml").read_text(encoding="utf-8")
PLAN = (DATA / "plan" / "_base.toml").read_text(encoding="utf-8")


@FUZZ
@given(text=edited(SCENARIO))
def test_scenario_reader(text, tmp_path_factory):
    from antsim.scenario import load_scenario

    path = _fuzz_file(tmp_path_factory, "fuzz.toml", text)
    with contextlib.suppress(InputError):
        load_scenario(path)


@FUZZ
@given(text=edited(PLAN))
def test_plan_reader(text, tmp_path_factory):
    from antsim.plan.planfile import load_plan

    folder = tmp_path_factory.mktemp("fuzzplan")
    (folder / "plan").mkdir()
    (folder / "scenario").mkdir()
    (folder / "scenario" / "_base.toml").write_text(SCENARIO, encoding="utf-8")
    path = _write(folder / "plan", "fuzz.toml", text)
    with contextlib.suppress(InputError):
        load_plan(path)


@pytest.mark.parametrize("reader", ["tpoint", "ecsv", "csv", "scenario"])
def test_the_fuzzers_reach_both_outcomes(reader, tmp_path):
    """A fuzzer whose inputs all fail (or all pass) tests one path only: over a fixed sample
    of the same edits, each reader must both accept and refuse some inputs."""
    from hypothesis import find

    from antsim.scenario import load_scenario
    from controller.pointing.tpoint import parse_tpoint
    from controller.program.csvdata import read_csv
    from controller.program.recordings import read_recordings

    base = {"tpoint": TPOINT, "ecsv": ECSV, "csv": CSV, "scenario": SCENARIO}[reader]
    suffix = {"tpoint": ".dat", "ecsv": ".ecsv", "csv": ".csv", "scenario": ".toml"}[reader]

    def read(text: str) -> bool:
        path = tmp_path / ("case" + suffix)
        path.write_text(text.replace(" ,", ","), encoding="utf-8", errors="surrogatepass")
        try:
            if reader == "tpoint":
                parse_tpoint(text)
            elif reader == "ecsv":
                read_recordings(path)
            elif reader == "csv":
                read_csv(path)
            else:
                load_scenario(path)
        except InputError:
            return False
        return True

    quiet = settings(max_examples=200, derandomize=True, deadline=None, database=None,
                     suppress_health_check=list(HealthCheck))
    assert not read(find(edited(base), lambda t: not read(t), settings=quiet))
    assert read(find(edited(base), read, settings=quiet))

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

DATA = Path(__file__).resolve().parents[1] / "data" / "bad_inputs"
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


# ---------------------------------------------------------------------------------------------
# files: ECSV recordings, CSV measurements, scenarios (and TPOINT data again, from a file)
ECSV = (DATA / "ecsv" / "_base.ecsv").read_text(encoding="utf-8")
CSV = _comma_tokens((DATA / "csv" / "_base.csv").read_text(encoding="utf-8"))
SCENARIO = (DATA / "scenario" / "_base.toml").read_text(encoding="utf-8")
PLAN = (DATA / "plan" / "_base.toml").read_text(encoding="utf-8")


def _read_tpoint(path: Path) -> None:
    from controller.pointing.tpoint import read_tpoint

    read_tpoint(path).pointing_data()


def _read_ecsv(path: Path) -> None:
    from controller.program.recordings import read_recordings, table_pointing_data

    table_pointing_data(read_recordings(path), str(path))


def _read_csv(path: Path) -> None:
    from controller.program.csvdata import pointing_data, read_csv

    pointing_data(read_csv(path))


def _read_scenario(path: Path) -> None:
    from antsim.scenario import load_scenario

    load_scenario(path)


#: kind -> (file suffix, base text, reader)
FILES = {"tpoint": (".dat", TPOINT, _read_tpoint), "ecsv": (".ecsv", ECSV, _read_ecsv),
         "csv": (".csv", CSV, _read_csv), "scenario": (".toml", SCENARIO, _read_scenario)}


def _edited_file(kind: str, data, tmp_path_factory) -> Path:
    suffix, base, _ = FILES[kind]
    text = data.draw(edited(base)).replace(" ,", ",")  # CSV fields were space-split tokens
    return _fuzz_file(tmp_path_factory, "fuzz" + suffix, text)


@pytest.mark.parametrize("kind", ["ecsv", "csv", "scenario"])
@FUZZ
@given(data=st.data())
def test_file_readers(kind, data, tmp_path_factory):
    path = _edited_file(kind, data, tmp_path_factory)
    with contextlib.suppress(InputError):
        FILES[kind][2](path)


@pytest.mark.parametrize("kind", ["tpoint", "ecsv", "csv"])
@FUZZ
@given(data=st.data())
def test_edited_files_through_antsim_fit(kind, data, tmp_path_factory, capsys):
    """The whole command: read, fit, print; exit 0 or one line and 2."""
    _one_line_or_success(capsys, ["fit", str(_edited_file(kind, data, tmp_path_factory)),
                                  "--json"])


@FUZZ
@given(text=st.text(max_size=300))
def test_free_text_as_csv(text, tmp_path_factory):
    with contextlib.suppress(InputError):
        _read_csv(_fuzz_file(tmp_path_factory, "fuzz.csv", text))


@FUZZ
@given(data=st.binary(max_size=600))
def test_bytes_through_antsim_fit(data, tmp_path_factory, capsys):
    path = _fuzz_file(tmp_path_factory, "fuzz.ecsv", b"# %ECSV 1.0\n" + data)
    _one_line_or_success(capsys, ["fit", str(path)])


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


@pytest.mark.parametrize("kind", list(FILES))
def test_the_fuzzers_reach_both_outcomes(kind, tmp_path):
    """A fuzzer whose inputs all fail (or all pass) tests one path only: over a fixed sample
    of the same edits, each reader must both accept and refuse some inputs."""
    from hypothesis import find

    suffix, base, reader = FILES[kind]

    def read(text: str) -> bool:
        path = tmp_path / ("case" + suffix)
        path.write_text(text.replace(" ,", ","), encoding="utf-8", errors="surrogatepass")
        try:
            reader(path)
        except InputError:
            return False
        return True

    quiet = settings(max_examples=200, derandomize=True, deadline=None, database=None,
                     suppress_health_check=list(HealthCheck))
    assert not read(find(edited(base), lambda t: not read(t), settings=quiet))
    assert read(find(edited(base), read, settings=quiet))

"""The one place that decides what kind of file a user gave."""

from __future__ import annotations

from pathlib import Path

import pytest

from controller.errors import InputError
from controller.filekind import file_kind

DATA = Path(__file__).resolve().parents[1] / "data" / "bad_inputs"


@pytest.mark.parametrize(("name", "kind"), [
    ("ecsv/_base.ecsv", "ecsv"), ("csv/_base.csv", "csv"), ("tpoint/_base.dat", "tpoint"),
    ("model/_base.mod", "mod"), ("model/_base.json", "json"),
])
def test_each_kind_of_file_is_known_by_its_text(name, kind):
    path = DATA / name
    assert file_kind(path, path.read_text(encoding="utf-8")) == kind
    # the name does not matter but for ".csv": the text decides
    assert file_kind("renamed.txt", path.read_text(encoding="utf-8")) == kind


def test_a_csv_without_the_name_is_known_by_its_heading():
    assert file_kind("mine.txt", "# sign: true-minus-indicated\naz,el,d_xel,d_el\n1,2,3,4\n") \
        == "csv"


@pytest.mark.parametrize(("text", "says"), [
    ("", "is too short to be TPOINT data"),
    ("hello\n", "is too short to be TPOINT data"),
    ("hello\n  12 world\n", "is neither TPOINT pointing data"),
])
def test_anything_else_is_one_line(text, says):
    with pytest.raises(InputError, match=says):
        file_kind("f", text)

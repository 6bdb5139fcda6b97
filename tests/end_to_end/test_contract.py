"""docs/contract.md is what the commands write: every key and column it lists is written, and
every one written is listed (at the levels the page lists: a document's top level, each
entry of ``terms``, ``effects``, ``findings``, and the objects it details)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from astropy.table import Table

from antsim.cli import main as cli

REPO = Path(__file__).resolve().parents[2]
CONTRACT = (REPO / "docs" / "contract.md").read_text(encoding="utf-8")


def documented(heading: str, table: int = 0, optional: bool = False) -> set[str]:
    """The keys in the first column of the ``table``-th table under ``## heading`` (with
    ``optional``, only those written only sometimes: their meaning starts with "only")."""
    section = CONTRACT[CONTRACT.index(f"## {heading}") + 3:]
    section = section[:section.index("\n## ")] if "\n## " in section else section
    rows: list[list[str]] = []
    previous = False
    for line in section.splitlines():
        if line.startswith("|"):
            if not previous:
                rows.append([])
            rows[-1].append(line)
        previous = line.startswith("|")
    keys: set[str] = set()
    for line in rows[table][2:]:
        first, meaning = line.split(" | ")[:2]
        if optional and not meaning.startswith("only "):
            continue
        keys.update(re.findall(r"`([^`]+)`", first.lstrip("| ")))
    return keys


def conforms(doc: dict, heading: str) -> bool:
    """``doc`` has every key listed under ``heading`` but the optional ones, and no other."""
    keys = documented(heading)
    written = flatten(doc, keys)
    missing = keys - documented(heading, optional=True) - written
    assert not missing and written <= keys, (missing, written - keys)
    return True


def flatten(doc: dict, documented_keys: set[str]) -> set[str]:
    """The keys of ``doc`` at the levels ``documented_keys`` reach: its top level, and the
    children of every documented object (``terms.<name>``: each entry of a map by name;
    ``findings[]``: each entry of a list)."""
    keys = set(doc)
    parents = {k.rsplit(".", 1)[0] for k in documented_keys if "." in k}
    for parent in parents:
        for value in _values(doc, parent):
            assert isinstance(value, dict), parent
            keys.update(f"{parent}.{child}" for child in value)
    return keys


def _values(doc, path: str) -> list:
    """Every value at ``path`` (``a.<name>.b``, ``a[].b``) in ``doc``."""
    values = [doc]
    for part in path.split("."):
        out = []
        for v in values:
            if part == "<name>":
                out.extend(v.values())
            elif part.endswith("[]"):
                out.extend(v[part[:-2]])
            else:
                out.append(v[part])
        values = out
    return values


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory, short_ghigo_text) -> Path:
    """A 3-hour 1990 campaign, as `antsim run` writes it."""
    tmp = tmp_path_factory.mktemp("contract")
    scenario = tmp / "short.toml"
    scenario.write_text(short_ghigo_text, encoding="utf-8")
    assert cli(["run", str(scenario), "--out", str(tmp / "run"), "--no-report",
                "--no-progress"]) == 0
    return tmp / "run"


def test_the_run_writes_the_files_of_the_contract(run_dir):
    files = documented("Files of `antsim run --out DIR`")
    for name in files - {"report.html", "figures/"}:  # --no-report
        assert (run_dir / name).is_file(), name
    written = {p.name for p in run_dir.iterdir() if not p.name.startswith(".")}
    assert written <= files, written - files


def test_truth_json_is_the_contracts(run_dir):
    doc = json.loads((run_dir / "truth.json").read_text())
    assert doc["effects"], "the 1990 scenario injects effects: their keys are checked"
    assert conforms(doc, "The truth document")
    assert all(isinstance(t["value_arcsec"], float) for t in doc["terms"].values())


def test_fit_json_and_fit_dash_json_are_the_contracts(run_dir, capsys):
    doc = json.loads((run_dir / "fit.json").read_text())
    assert conforms(doc, "The fit document")
    variants = json.loads((run_dir / "fit_variants.json").read_text())
    assert set(variants) >= set("ABCDEF")
    assert variants["A"] == doc
    for variant in variants.values():
        assert variant is None or conforms(variant, "The fit document")
    assert cli(["fit", str(run_dir / "recordings.ecsv"), "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert conforms(printed, "The fit document")


def test_diagnose_json_is_the_contracts(tmp_path, capsys):
    """On the MMT's run (examples/), where diagnose finds something: the findings' keys too."""
    assert cli(["diagnose", str(REPO / "examples" / "mmt_20210821_k_and_e.dat"), "--json",
                "--out", str(tmp_path / "d")]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["findings"], "the MMT file has findings: their keys are checked"
    assert conforms(doc, "The diagnosis document") and "outputs" in doc
    assert json.loads((tmp_path / "d" / "diagnose.json").read_text()).keys() == doc.keys()


def test_the_recordings_are_the_contracts(run_dir):
    table = Table.read(run_dir / "recordings.ecsv")
    assert set(table.colnames) == documented("The recordings (`recordings.ecsv`)")
    assert set(table.meta) == documented("The recordings (`recordings.ecsv`)", table=1)
    assert set(table["polarization"]) == {"XR", "XL", "AVG"}

"""The cache of diagnose's baseline simulations is checked against what wrote it.

Each cached file holds the key of the inputs that made it and a digest of its content; both
are recomputed when it is read. A file that is damaged but loadable (its times moved, so
that the simulations no longer follow the recorded schedule), made from other inputs, or
holding anything but data is simulated again, with one note, and never changes diagnose's
answer.
"""

from __future__ import annotations

import json
import os
import pickle
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

from antsim.cli import main
from controller.errors import Note

REPO = Path(__file__).resolve().parents[3]
BASE = REPO / "tests" / "data" / "bad_inputs" / "scenario" / "_base.toml"
#: the recordings of BASE (seed 3): diagnose finds a tilt/collimation effect at 2.8 sigma
RECORDINGS = REPO / "tests" / "data" / "bad_inputs" / "ecsv" / "_base.ecsv"
TERMS = ("W1", "W6")


class Payload:
    """Unpickling this writes a marker file: proof that code ran."""

    def __init__(self, marker: str):
        self.marker = marker

    def __reduce__(self):
        return (os.system, (f"touch {self.marker}",))


@pytest.fixture(scope="module")
def clean(tmp_path_factory):
    """Two simulations of BASE cached once: the directory, its files and their products."""
    from antsim.diagnose.baseline import SimulatedBaseline
    from antsim.scenario import load_scenario

    cache = tmp_path_factory.mktemp("baseline")
    base = SimulatedBaseline(load_scenario(BASE), TERMS, n_sims=2, cache_dir=cache, jobs=1)
    files = sorted(cache.glob("baseline-*.npz"))
    assert len(files) == 2
    return cache, {f.name: f.read_bytes() for f in files}, base.products


def _copy(clean, tmp_path) -> Path:
    cache = tmp_path / "cache"
    shutil.copytree(clean[0], cache)
    return cache


def _arrays(path: Path) -> dict[str, np.ndarray]:
    with np.load(path, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def _save(path: Path, arrays: dict) -> None:
    with path.open("wb") as fh:
        np.savez(fh, **arrays)


def _load_again(cache: Path):
    from antsim.diagnose.baseline import SimulatedBaseline
    from antsim.scenario import load_scenario

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        base = SimulatedBaseline(load_scenario(BASE), TERMS, n_sims=2, cache_dir=cache, jobs=1)
    return base, [str(w.message) for w in caught if issubclass(w.category, Note)]


def _same(a, b) -> None:
    for x, y in zip(a, b, strict=True):
        for name in ("t_s", "res", "pol", "width", "az_rad", "el_rad"):
            np.testing.assert_array_equal(getattr(x, name), getattr(y, name), name)
        assert list(x.source) == list(y.source)


def test_the_clean_cache_is_read_without_a_note(clean, tmp_path):
    base, notes = _load_again(_copy(clean, tmp_path))
    assert notes == []
    _same(base.products, clean[2])


@pytest.mark.parametrize("edit", ["times moved", "a residual changed", "sources renamed"])
def test_a_damaged_but_loadable_file_is_simulated_again(clean, tmp_path, edit):
    cache = _copy(clean, tmp_path)
    path = sorted(cache.glob("baseline-*.npz"))[0]
    arrays = _arrays(path)
    if edit == "times moved":  # what made diagnose say "1 of 12 scans matched"
        arrays["t_s"] = arrays["t_s"] + 1000.0
    elif edit == "a residual changed":
        arrays["res"] = arrays["res"].copy()
        arrays["res"][0, 0] += 30.0
    else:
        arrays["source"] = np.array(["Somewhere"] * arrays["source"].size)
    _save(path, arrays)
    base, notes = _load_again(cache)
    _same(base.products, clean[2])
    assert len(notes) == 1, notes
    assert str(path) in notes[0] and "digest does not match its content" in notes[0]
    assert notes[0].endswith("simulated again")
    assert path.read_bytes() == clean[1][path.name]  # rewritten as antsim writes it


def test_a_file_made_from_other_inputs_is_not_used(clean, tmp_path):
    """A valid file under another key's name (copied, renamed): its own key says so."""
    cache = _copy(clean, tmp_path)
    first, second = sorted(cache.glob("baseline-*.npz"))
    second.write_bytes(first.read_bytes())
    base, notes = _load_again(cache)
    _same(base.products, clean[2])
    assert len(notes) == 1 and "made from other inputs" in notes[0]


def test_a_pickled_object_in_the_cache_is_never_executed(clean, tmp_path):
    cache = _copy(clean, tmp_path)
    marker = tmp_path / "ran"
    first, second = sorted(cache.glob("baseline-*.npz"))
    arrays = _arrays(first)
    arrays["res"] = np.array([Payload(str(marker))], dtype=object)
    _save(first, arrays)
    second.write_bytes(pickle.dumps(Payload(str(marker))))  # a bare pickle
    base, notes = _load_again(cache)
    assert not marker.exists()
    _same(base.products, clean[2])
    assert len(notes) == 1 and "and 1 more" in notes[0]


def test_an_old_file_without_a_digest_is_not_looked_at(clean, tmp_path):
    """Files of the earlier layout (no key, no digest) have other names: never read."""
    cache = _copy(clean, tmp_path)
    for path in cache.glob("baseline-*.npz"):
        arrays = _arrays(path)
        del arrays["key"], arrays["digest"]
        _save(path, arrays)
    base, notes = _load_again(cache)
    _same(base.products, clean[2])
    assert len(notes) == 1 and "no key" in notes[0]


def test_a_file_that_unpacks_beyond_the_bound_is_not_read(clean, tmp_path, monkeypatch):
    """A compressed archive may unpack to gigabytes (a zip bomb): its declared size is
    checked before any array is read (the bound lowered here to the files' own size)."""
    from antsim.diagnose import baseline

    cache = _copy(clean, tmp_path)
    monkeypatch.setattr(baseline, "MAX_CACHE_BYTES", 1000)
    base, notes = _load_again(cache)
    _same(base.products, clean[2])
    assert len(notes) == 1 and "it unpacks to" in notes[0] and "and 1 more" in notes[0]


def test_the_cache_is_written_without_following_a_link(clean, tmp_path):
    cache = _copy(clean, tmp_path)
    victim = tmp_path / "victim"
    victim.write_text("keep me")
    path = sorted(cache.glob("baseline-*.npz"))[0]
    path.unlink()
    path.symlink_to(victim)
    base, notes = _load_again(cache)
    _same(base.products, clean[2])
    assert victim.read_text() == "keep me" and not path.is_symlink()
    assert path.read_bytes() == clean[1][path.name]
    assert len(notes) == 1


def test_a_damaged_cache_does_not_change_diagnoses_answer(tmp_path, capsys):
    """The case once reported: the same recordings and scenario, the cache damaged in place,
    give the same finding (a tilt/collimation effect at 2.8 sigma), with one note line."""
    args = ["diagnose", str(RECORDINGS), "--scenario", str(BASE), "--sims", "2",
            "--jobs", "1", "--json", "--no-progress", "--cache", str(tmp_path)]
    assert main(args) == 0
    clean_doc = json.loads(capsys.readouterr().out)
    assert clean_doc["findings"], "the base recordings have a finding"
    for path in tmp_path.glob("baseline-*.npz"):
        arrays = _arrays(path)
        arrays["t_s"] = arrays["t_s"] + 1000.0
        _save(path, arrays)
    assert main(args) == 0
    captured = capsys.readouterr()
    doc = json.loads(captured.out)
    assert doc["findings"] == clean_doc["findings"]
    lines = captured.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("antsim diagnose: note: the cached "
                                                   "baseline simulation "), lines

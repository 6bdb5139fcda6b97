"""The Earth-orientation cache (controller.astro.offline): the table it holds is astropy's,
read back the same and rebuilt when damaged; it holds data only and is checked against what
wrote it: a crafted pickle, an archive with an object array, a damaged or edited file, or one
written for other versions is never executed or trusted; the table is rebuilt with a note."""

from __future__ import annotations

import os
import pickle
import subprocess
import sys

import numpy as np
import pytest

#: run in a child process: the cache is read once per process
SCRIPT = """
import warnings
import numpy as np
from astropy.time import Time
from astropy.utils import iers
import controller.astro.offline as offline
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    offline.use_cached_eop_table()
t = Time(np.linspace(47000.0, 61000.0, 7), format="mjd")
print(repr(iers.earth_orientation_table.get().ut1_utc(t).value.tolist()))
for w in caught:
    print("NOTE", type(w.message).__name__, w.message)
"""


class Payload:
    """Unpickling this writes a marker file: proof that code ran."""

    def __init__(self, marker: str):
        self.marker = marker

    def __reduce__(self):
        return (os.system, (f"touch {self.marker}",))


def _run(cache_dir) -> tuple[str, list[str]]:
    env = {**os.environ, "ANTSIM_CACHE": str(cache_dir)}
    done = subprocess.run([sys.executable, "-c", SCRIPT], env=env, capture_output=True,
                          text=True, check=True, timeout=120)
    lines = done.stdout.strip().splitlines()
    return lines[0], [line for line in lines[1:] if line.startswith("NOTE")]


@pytest.fixture(scope="module")
def first(tmp_path_factory):
    """A cache written once, and the numbers astropy gave."""
    cache = tmp_path_factory.mktemp("eop")
    numbers, notes = _run(cache)
    assert notes == []
    (path,) = cache.glob("iers-auto-*.npz")
    return cache, path, numbers


def _again(first, tmp_path, write) -> tuple[str, list[str], bytes]:
    _, path_src, _ = first
    cache = tmp_path / "cache"
    cache.mkdir()
    path = cache / path_src.name
    write(path, path_src.read_bytes())
    got, notes = _run(cache)
    return got, notes, path.read_bytes()


def test_a_crafted_pickle_in_place_of_the_cache_is_never_executed(first, tmp_path):
    marker = tmp_path / "ran"
    payload = pickle.dumps(Payload(str(marker)))
    got, notes, rewritten = _again(first, tmp_path, lambda p, good: p.write_bytes(payload))
    assert not marker.exists()
    assert got == first[2]
    assert len(notes) == 1 and "was not written by antsim" in notes[0] and "rebuilt" in notes[0]
    assert rewritten == first[1].read_bytes()  # rebuilt: the file antsim writes


def test_an_archive_with_a_pickled_object_array_is_never_executed(first, tmp_path):
    marker = tmp_path / "ran"

    def write(path, good):
        with np.load(first[1], allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
        arrays["v0"] = np.array([Payload(str(marker))], dtype=object)
        with path.open("wb") as fh:
            np.savez(fh, **arrays)

    got, notes, _ = _again(first, tmp_path, write)
    assert not marker.exists() and got == first[2] and len(notes) == 1


def test_an_edited_value_is_caught_by_the_digest(first, tmp_path):
    """A loadable archive with one UT1-UTC value changed: the table is rebuilt, so the
    numbers are astropy's, not the edited ones."""
    from astropy.utils import iers  # noqa: F401 (the column names are astropy's)

    def write(path, good):
        with np.load(first[1], allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
        import json

        names = json.loads(str(arrays["manifest"][()]))["names"]
        i = names.index("UT1_UTC")
        arrays[f"v{i}"] = arrays[f"v{i}"] + 0.5  # half a second of UT1: 7.5" of hour angle
        with path.open("wb") as fh:
            np.savez(fh, **arrays)

    got, notes, _ = _again(first, tmp_path, write)
    assert got == first[2]
    assert len(notes) == 1 and "digest does not match its content" in notes[0]


@pytest.mark.parametrize("damage", ["empty", "half", "not a zip"])
def test_a_damaged_file_is_rebuilt(first, tmp_path, damage):
    def write(path, good):
        path.write_bytes({"empty": b"", "half": good[: len(good) // 2],
                          "not a zip": b"PK\x03\x04 nonsense"}[damage])

    got, notes, rewritten = _again(first, tmp_path, write)
    assert got == first[2] and len(notes) == 1 and rewritten == first[1].read_bytes()


def test_a_file_for_other_versions_is_not_used(first, tmp_path):
    """The digest is right, but the manifest names other versions (a file renamed)."""
    import json

    from controller.astro import offline

    def write(path, good):
        with np.load(first[1], allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
        manifest = json.loads(str(arrays.pop("manifest")[()]))
        manifest["versions"]["astropy"] = "0.0"
        text = json.dumps(manifest, sort_keys=True)
        arrays.pop("digest")
        digest = offline._digest(text, [arrays[k] for k in sorted(arrays)])
        with path.open("wb") as fh:
            np.savez(fh, manifest=np.array(text), digest=np.array(digest), **arrays)

    got, notes, _ = _again(first, tmp_path, write)
    assert got == first[2] and len(notes) == 1 and "written for" in notes[0]


def test_an_archive_that_unpacks_to_gigabytes_is_not_read(first, tmp_path):
    """A zip bomb in place of the cache: a member declaring 100 MB of zeros (compressed to
    100 kB) is refused from the archive's directory, before any array is read."""
    import zipfile

    def write(path, good):
        with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z, \
                z.open("v0.npy", "w", force_zip64=True) as member:
            chunk = bytes(1 << 20)  # the content does not matter: its size does
            for _ in range(100):
                member.write(chunk)

    got, notes, _ = _again(first, tmp_path, write)
    assert got == first[2] and len(notes) == 1 and "it holds 104857600 bytes" in notes[0]


def test_the_cache_is_written_without_following_a_link(first, tmp_path):
    """A symbolic link where the temporary file goes, or where the cache goes: the target
    is never written (the file is made new, then renamed over the link)."""
    victim = tmp_path / "victim"
    victim.write_text("keep me")
    cache = tmp_path / "cache"
    cache.mkdir()
    (cache / first[1].name).symlink_to(victim)
    got, notes = _run(cache)
    assert got == first[2] and victim.read_text() == "keep me"
    assert not (cache / first[1].name).is_symlink()
    assert len(notes) == 1  # the link's target was not a cache file


def test_a_cache_that_cannot_be_written_only_costs_time(first, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    got, notes = _run(blocker / "cache")  # a path through a file: mkdir fails
    assert got == first[2] and notes == []


TABLE_SCRIPT = """
import numpy as np
from astropy.time import Time
from astropy.utils import iers
import controller.astro.offline as offline
offline.use_cached_eop_table()
t = Time(np.linspace(47000.0, 61000.0, 7), format="mjd")
print(type(iers.earth_orientation_table.get()).__name__,
      repr(iers.earth_orientation_table.get().ut1_utc(t).value.tolist()))
"""


def _table(cache_dir) -> str:
    env = {**os.environ, "ANTSIM_CACHE": str(cache_dir)}
    done = subprocess.run([sys.executable, "-c", TABLE_SCRIPT], env=env, capture_output=True,
                          text=True, check=True)
    return done.stdout.strip()


def _astropy_own() -> str:
    script = TABLE_SCRIPT.replace("offline.use_cached_eop_table()", "")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          check=True)
    return done.stdout.strip()


def test_cached_table_is_astropys_and_survives_damage(tmp_path):
    own = _astropy_own()
    assert own.startswith("IERS_Auto")
    assert _table(tmp_path) == own  # first use: astropy's loading, then written to the cache
    (cache,) = tmp_path.glob("iers-auto-*.npz")
    assert cache.stat().st_size > 100_000
    assert _table(tmp_path) == own  # read back from the cache: the same numbers
    cache.write_bytes(b"not a cache file")
    assert _table(tmp_path) == own  # damaged: rebuilt
    assert cache.stat().st_size > 100_000

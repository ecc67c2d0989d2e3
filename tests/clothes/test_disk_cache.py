"""The garment cache on disk: a build read back in another process is the same garment, bit
for bit, with no build; a damaged or unwritable cache costs a rebuild, never an error."""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys

import numpy as np
import pytest

from avatar.clothes import disk_cache, library

# A fresh process: enable the cache, load a built-in and a variant, and fail if anything is
# built (every builtin.build / builtin.look call raises).
_CHILD = """
import pickle, sys
from avatar.clothes import builtin, disk_cache, library
disk_cache.enable(sys.argv[1])
if sys.argv[2] == "no-build":
    def refuse(*a, **k):
        raise SystemExit("built although cached")
    builtin.build = builtin.look = refuse
out = [library.load_garment("sweatpants"),
       library.load_garment("sweatpants", options={"colour": "navy"})]
sys.stdout.buffer.write(pickle.dumps(out))
"""


def _child(root, mode: str):
    import pickle

    done = subprocess.run([sys.executable, "-c", _CHILD, str(root), mode], capture_output=True,
                          check=False)  # fmt: skip
    assert done.returncode == 0, done.stderr.decode()[-2000:]
    return pickle.loads(done.stdout)


def _same(a, b, path="garment"):
    """Assert two records are equal field by field, arrays bit for bit."""
    if dataclasses.is_dataclass(a):
        assert type(a) is type(b), path
        for f in dataclasses.fields(a):
            _same(getattr(a, f.name), getattr(b, f.name), f"{path}.{f.name}")
    elif isinstance(a, np.ndarray):
        assert a.dtype == b.dtype and a.shape == b.shape, path
        assert np.array_equal(a, b, equal_nan=a.dtype.kind == "f"), path
    elif isinstance(a, dict):
        assert a.keys() == b.keys(), path
        for k in a:
            _same(a[k], b[k], f"{path}[{k!r}]")
    elif isinstance(a, (list, tuple)):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _same(x, y, f"{path}[{i}]")
    else:
        assert a == b, path


def test_a_second_process_reads_the_first_ones_builds_bit_for_bit(tmp_path):
    built = _child(tmp_path, "build")
    assert len(list(tmp_path.rglob("*.pickle"))) == 2  # the garment and its variant's look
    read = _child(tmp_path, "no-build")
    for a, b in zip(built, read, strict=True):
        _same(a, b)
    assert read[1].material is not None and read[0].material is not None
    assert not np.array_equal(read[0].material.base_color_texture,
                              read[1].material.base_color_texture)  # fmt: skip
    # the variant shares the default's geometry arrays, as an in-memory build does
    assert read[1].mesh is read[0].mesh


def test_a_damaged_file_is_rebuilt_and_rewritten(tmp_path, caplog):
    folder = disk_cache.enable(tmp_path)
    try:
        key = ("test", "damaged")
        assert disk_cache.fetch(key, lambda: [1, 2]) == [1, 2]
        (path,) = folder.glob("*.pickle")
        path.write_bytes(path.read_bytes()[:5])  # cut short
        assert disk_cache.fetch(key, lambda: [3]) == [3]
        assert "unreadable" in caplog.text
        assert disk_cache.fetch(key, lambda: pytest.fail("rebuilt twice")) == [3]
    finally:
        disk_cache.disable()


def test_an_unwritable_cache_still_returns_the_build(tmp_path, caplog):
    folder = disk_cache.enable(tmp_path)
    try:
        folder.rmdir()
        folder.write_text("")  # the folder is gone and a file holds its name: writes fail
        assert disk_cache.fetch(("test", "ro"), lambda: "built") == "built"
        assert "could not write" in caplog.text
        assert [p.name for p in tmp_path.iterdir()] == [folder.name]  # nothing half-written
    finally:
        disk_cache.disable()


def test_old_code_versions_and_killed_writes_are_pruned(tmp_path):
    current = tmp_path / disk_cache.code_fingerprint()
    current.mkdir()
    (current / ".a.pickle.1.tmp").write_bytes(b"half")  # a writer killed long ago
    os.utime(current / ".a.pickle.1.tmp", (1000, 1000))
    (current / ".b.pickle.2.tmp").write_bytes(b"half")  # one writing now
    for i in range(5):
        old = tmp_path / f"old{i}"
        old.mkdir()
        os.utime(old, (1000 + i, 1000 + i))
    folder = disk_cache.enable(tmp_path)
    disk_cache.disable()
    kept = sorted(p.name for p in tmp_path.iterdir())
    assert kept == sorted([folder.name, "old4", "old3"][: disk_cache.KEEP_OLD + 1])
    assert [p.name for p in folder.iterdir()] == [".b.pickle.2.tmp"]


def test_off_unless_enabled():
    """Only a caller that asks (the dataset worker) writes builds to disk."""
    assert disk_cache.enabled() is None
    assert library.load_garment("sweatpants") is library.load_garment("sweatpants")

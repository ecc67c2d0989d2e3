"""The extension in other Blender Pythons: a fresh process per environment runs
extension_smoke.py (install the zip, create, live changes checked against the library,
wear, error reports, Apply with slotted or legacy actions, unregister).

- this venv's bpy with pygltflib made unimportable (the zip does not bundle it; tqdm, which
  the garment bake imports, it does: ``bundled_requirements``);
- pip bpy 4.2 LTS (no slotted actions), in the venv named by ``AVATAR_BPY42_PYTHON``
  (default /tmp/bpy42/bin/python: ``python3.11 -m venv /tmp/bpy42 && /tmp/bpy42/bin/pip
  install bpy==4.2.0 numpy scipy pillow pykdtree pygltflib tqdm``);
- pip bpy 5.1+ on Python 3.13 where ``AVATAR_BPY5X_PYTHON`` names one.
Each is skipped cleanly when its interpreter is absent.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from test_extension import FIXTURES, ROOT, load_build_script

SMOKE = Path(__file__).with_name("extension_smoke.py")
WALK = FIXTURES / "bvh" / "cmu_motionbuilder" / "02_01_walk.bvh"
BPY42 = os.environ.get("AVATAR_BPY42_PYTHON", "/tmp/bpy42/bin/python")
BPY5X = os.environ.get("AVATAR_BPY5X_PYTHON", "")


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


def _smoke(python: str, zip_and_env, *extra: str) -> str:
    zip_path, env = zip_and_env
    bvh = ["--bvh", str(WALK)] if WALK.is_file() else []
    run = subprocess.run([python, str(SMOKE), str(zip_path), *bvh, *extra], env=env,
                         capture_output=True, text=True, timeout=900)  # fmt: skip
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    assert "unregister ok" in run.stdout
    print(run.stdout)  # the versions and errors measured, in pytest's -s output
    return run.stdout


@pytest.mark.timeout(900)
def test_the_zip_needs_no_pygltflib(zip_and_env):
    out = _smoke(sys.executable, zip_and_env, "--block", "pygltflib")
    assert "motion ok: slotted actions True" in out or not WALK.is_file()


def test_the_zip_bundles_tqdm_and_the_binary_wheels():
    wanted = load_build_script().bundled_requirements(lambda package: "1.0")
    bundled = {req.split("==")[0] for requirements, _ in wanted for req in requirements}
    assert {"scipy", "pillow", "tqdm", "pykdtree"} <= bundled


@pytest.mark.timeout(900)
@pytest.mark.skipif(not Path(BPY42).is_file(), reason=f"no bpy 4.2 venv at {BPY42}")
def test_blender_4_2(zip_and_env):
    out = _smoke(BPY42, zip_and_env)
    assert "blender 4.2" in out
    assert "motion ok: slotted actions False" in out or not WALK.is_file()


@pytest.mark.timeout(900)
@pytest.mark.skipif(not BPY5X or not Path(BPY5X).is_file(), reason="AVATAR_BPY5X_PYTHON unset")
def test_blender_5x_on_python_3_13(zip_and_env):
    _smoke(BPY5X, zip_and_env)

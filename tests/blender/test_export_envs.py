"""Export presets, studio and camera export under pip bpy 4.2 LTS (a fresh process running
export_smoke.py), in the venv named by ``AVATAR_BPY42_PYTHON`` (default /tmp/bpy42/bin/python,
see test_extension_envs.py); skipped cleanly where it is absent."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest
from test_extension import ROOT

BPY42 = os.environ.get("AVATAR_BPY42_PYTHON", "/tmp/bpy42/bin/python")


@pytest.mark.timeout(900)
@pytest.mark.skipif(not Path(BPY42).is_file(), reason=f"no bpy 4.2 venv at {BPY42}")
def test_export_presets_studio_and_camera_on_blender_4_2():
    from avatar.body import assets
    from avatar.errors import AssetError

    try:
        data = assets.find_data_dir()
    except AssetError as exc:
        pytest.skip(f"MakeHuman assets not installed: {exc}")
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"), AVATAR_ASSETS=str(data))
    env.pop("BLENDER_USER_RESOURCES", None)
    run = subprocess.run([BPY42, str(Path(__file__).with_name("export_smoke.py"))], env=env,
                         capture_output=True, text=True, timeout=900)  # fmt: skip
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    assert "blender 4.2" in run.stdout and "camera ok" in run.stdout
    assert "studio EEVEE ok: BLENDER_EEVEE_NEXT" in run.stdout

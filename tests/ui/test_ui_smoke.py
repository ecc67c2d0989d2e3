"""Runs run_ui_smoke.sh: the add-on in a real Blender window, Create clicked with xdotool.

Skipped unless Debian's blender, Xvfb and xdotool are installed and the MakeHuman assets
can be found (``apt-get install -y blender xvfb xdotool python3-numpy``).
"""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
TOOLS = ("blender", "Xvfb", "xdotool")


def _assets_available() -> bool:
    try:
        from avatar.body import assets

        assets.find_data_dir()
    except Exception:  # noqa: BLE001 - any failure means: nothing to create a human from
        return False
    return True


@pytest.mark.skipif(not all(shutil.which(t) for t in TOOLS), reason="needs blender, Xvfb, xdotool")
@pytest.mark.skipif(not _assets_available(), reason="needs the MakeHuman assets")
@pytest.mark.timeout(300)
def test_create_button_makes_a_character(tmp_path):
    run = subprocess.run([str(HERE / "run_ui_smoke.sh"), str(tmp_path)],
                         capture_output=True, text=True, timeout=280)  # fmt: skip
    state = json.loads((tmp_path / "state.json").read_text())
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    assert state["panel"]
    ((name, recipe),) = state["characters"].items()
    assert recipe["rig"] == "default" and recipe["params"]["gender"] == 0.5
    assert state["meshes"]["body"] == 13380
    assert (tmp_path / "after-create.png").stat().st_size > 50_000

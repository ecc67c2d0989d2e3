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
@pytest.mark.timeout(1500)
def test_create_drag_undo_wear_and_apply_in_a_real_window(tmp_path):
    # xdotool's synthetic clicks can be lost when the machine is loaded (X event timing, not
    # the add-on): a session that failed is run again in a fresh Blender, up to three times,
    # and every one of its checks must hold in the same session.
    failures = []
    for attempt in range(3):
        out = tmp_path / f"session{attempt}"
        try:
            run = subprocess.run([str(HERE / "run_ui_smoke.sh"), str(out)],
                                 capture_output=True, text=True, timeout=480)  # fmt: skip
        except subprocess.TimeoutExpired as exc:
            run = subprocess.CompletedProcess(exc.cmd, 124, str(exc.stdout), str(exc.stderr))
        try:
            assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
            _check_session(out)
            return
        except (AssertionError, FileNotFoundError, ValueError) as exc:
            failures.append(f"session {attempt}: {exc}")
    pytest.fail("\n".join(failures))


def _check_session(folder):
    def state(step):
        data = json.loads((folder / f"state-{step}.json").read_text())
        ((name, recipe),) = data["characters"].items()
        return data, recipe

    created, recipe = state("settled")
    assert created["panel"] and recipe["rig"] == "default"
    assert created["meshes"]["body"] == 13380
    assert {"hair-short", "eyebrows", "eyelashes"} <= set(created["shown"])  # by default
    # A drag on the Weight slider changed the body shown, with no button pressed.
    dragged, recipe = state("after-drag")
    assert recipe["params"]["weight"] > 0.6
    assert dragged["shown"]["body"] != created["shown"]["body"]
    # Edit > Undo in the window brings the previous body back.
    undone, recipe = state("after-undo")
    assert recipe["params"].get("weight", 0.5) == 0.5
    assert undone["shown"]["body"] == created["shown"]["body"]
    # Two clicks in the Dress panel's grid: both garments worn, as objects.
    worn, recipe = state("after-wear")
    assert {"tshirt", "trousers"} <= set(recipe["clothes"]) and {"tshirt", "trousers"} <= set(
        worn["shown"]
    )
    # Apply (Motion) on the dressed character: 30 frames played, the report kept.
    moved, recipe = state("after-motion")
    assert list(moved["actions"].values()) == [[1, 30]]
    assert "bones mapped" in next(iter(moved["reports"].values()))
    for shot in ("after-create", "after-drag", "after-wear", "after-motion"):
        assert (folder / f"{shot}.png").stat().st_size > 50_000

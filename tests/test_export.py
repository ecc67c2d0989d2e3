"""A real human written to every format: valid glTF (Khronos validator), lossless read-back."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import avatar
from avatar.io import gltf

ROOT = Path(__file__).resolve().parents[1]
VALIDATOR = ROOT / ".cache/node/node_modules/gltf-validator"


@pytest.fixture(scope="module")
def walker(model):
    human = avatar.Human({"gender": 0.8, "pca/belly": 1.0}, rig="game_engine", model=model)
    return human, avatar.walk(human.skeleton, seconds=0.5, fps=24)


def test_glb_round_trip(tmp_path, walker):
    human, animation = walker
    path = avatar.save(human, tmp_path / "h.glb", animation, expressions=True)
    back = gltf.read(path)
    names = [p.name for p in back.parts]
    assert names[:2] == ["body", "eyes"]
    body = back.parts[0]
    np.testing.assert_allclose(body.mesh.vertices, human.mesh.vertices, atol=1e-5)
    assert len(body.morphs) == 52 and "jawOpen" in body.morphs
    assert back.skeleton is not None and back.skeleton.names == human.skeleton.names
    np.testing.assert_allclose(back.skeleton.rest, human.skeleton.rest, atol=1e-5)
    assert next(iter(back.animations.values())).frames == animation.frames


@pytest.mark.skipif(not VALIDATOR.is_dir() or shutil.which("node") is None,
                    reason="Khronos gltf-validator not installed (scripts/setup.sh)")  # fmt: skip
def test_glb_passes_the_khronos_validator(tmp_path, walker):
    human, animation = walker
    path = avatar.save(human, tmp_path / "h.glb", animation)
    done = subprocess.run(["node", str(ROOT / "tests/io/validate_gltf.cjs"), str(VALIDATOR),
                           str(path)], capture_output=True, text=True, check=True)  # fmt: skip
    report = json.loads(done.stdout)
    assert report["issues"]["numErrors"] == 0, report["issues"]["messages"][:5]


@pytest.mark.parametrize("suffix", [".obj", ".mhm", ".gltf"])
def test_other_formats_write(tmp_path, walker, suffix):
    human, animation = walker
    path = avatar.save(human, tmp_path / f"h{suffix}", animation)
    assert path.stat().st_size > 500

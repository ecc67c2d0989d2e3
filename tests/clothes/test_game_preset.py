"""``avatar create --preset game``: a GLB within a game engine's budget (at most 4 joints per
vertex, maps at most 1024 px, LODs) that reads back, next to the full-quality default."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pygltflib
import pytest

from avatar.cli import main
from avatar.cli.presets import PRESETS, export_options
from avatar.errors import ParameterError
from avatar.io import gltf, images

ROOT = Path(__file__).resolve().parents[2]
VALIDATOR = ROOT / ".cache/node/node_modules/gltf-validator"
WEAR = ("tshirt", "jeans", "hair-short", "beard-short", "eyebrows", "stubble")


def test_preset_options():
    assert export_options("game") == {"max_influences": 4, "texture_size": 1024, "lods": 2}
    assert export_options(None) == PRESETS["full"]
    assert export_options("game", lods=0, texture_size=None)["lods"] == 0  # given wins
    with pytest.raises(ParameterError, match="did you mean game"):
        export_options("gaem")


def _glb_images(raw: pygltflib.GLTF2, path: Path) -> list[np.ndarray]:
    blob = raw.binary_blob()
    out = []
    for image in raw.images:
        view = raw.bufferViews[image.bufferView]
        data = blob[view.byteOffset or 0 : (view.byteOffset or 0) + view.byteLength]
        out.append(images.decode(bytes(data), path))
    return out


@pytest.fixture(scope="module")
def game_glb(tmp_path_factory, model):
    out = tmp_path_factory.mktemp("game") / "game.glb"
    args = ["create", "--set", "gender=1", "--rig", "game_engine", "--preset", "game", "-o",
            str(out)]  # fmt: skip
    for name in WEAR:
        args += ["--wear", name]
    assert main(args) == 0
    return out


def test_game_glb_fits_the_budget_and_reads_back(game_glb):
    raw = pygltflib.GLTF2().load(str(game_glb))
    for mesh in raw.meshes:
        for p in mesh.primitives:
            assert getattr(p.attributes, "JOINTS_1", None) is None  # one set: <= 4 joints
    back = gltf.read(game_glb)
    parts = {p.name: p for p in back.parts}
    for part in back.parts:
        if part.skin is not None:
            assert (np.asarray(part.skin[1]) > 0).sum(axis=1).max() <= 4
            np.testing.assert_allclose(np.asarray(part.skin[1]).sum(axis=1), 1, atol=1e-3)
    sides = [max(i.shape[:2]) for i in _glb_images(raw, game_glb)]
    assert sides and max(sides) <= 1024
    for name in ("body", *WEAR[:3]):
        assert f"{name}_LOD1" in parts and f"{name}_LOD2" in parts
    assert {"beard-short", "hair-short"} <= set(parts)
    hair = parts["hair-short"].material
    assert hair.alpha_mode == "MASK" and hair.base_color_texture is not None
    # Hair in the file: cut-out (MASK) or blended (BLEND) with a colour texture, both sides.
    materials = {m.name: m for m in raw.materials}
    for name, mode in (("hair-short", "MASK"), ("beard-short", "MASK"), ("eyebrows", "BLEND"),
                       ("stubble", "BLEND")):  # fmt: skip
        m = materials[name]
        assert m.alphaMode == mode and m.pbrMetallicRoughness.baseColorTexture is not None
    assert materials["hair-short"].doubleSided


def test_full_preset_keeps_eight_influences_and_no_lods(tmp_path, model):
    out = tmp_path / "full.glb"
    assert main(["create", "--wear", "tshirt", "--preset", "full", "-o", str(out)]) == 0
    names = [p.name for p in gltf.read(out).parts]
    assert not any("_LOD" in n for n in names)
    raw = pygltflib.GLTF2().load(str(out))
    body = next(m for m in raw.meshes if m.name == "body")
    assert body.primitives[0].attributes.JOINTS_1 is not None  # the default rig: up to 8


def test_explicit_option_overrides_the_preset(tmp_path, model):
    out = tmp_path / "g0.glb"
    assert main(["create", "--preset", "game", "--lods", "0", "-o", str(out)]) == 0
    names = [p.name for p in gltf.read(out).parts]
    assert not any("_LOD" in n for n in names)


def test_unknown_preset_is_a_usage_error(tmp_path, capsys):
    with pytest.raises(SystemExit):
        main(["create", "--preset", "mobile", "-o", str(tmp_path / "x.glb")])
    assert "invalid choice" in capsys.readouterr().err


@pytest.mark.skipif(not VALIDATOR.is_dir() or shutil.which("node") is None,
                    reason="Khronos gltf-validator not installed (scripts/setup.sh)")  # fmt: skip
def test_game_glb_passes_the_khronos_validator(game_glb):
    done = subprocess.run(["node", str(ROOT / "tests/io/validate_gltf.cjs"), str(VALIDATOR),
                           str(game_glb)], capture_output=True, text=True, check=True)  # fmt: skip
    issues = json.loads(done.stdout)["issues"]
    assert issues["numErrors"] == 0, issues["messages"][:5]

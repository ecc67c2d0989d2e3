"""A real human written to every format: valid glTF (Khronos validator), lossless read-back."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pygltflib
import pytest

import avatar
from avatar.errors import ParameterError
from avatar.io import gltf, images, obj
from avatar.io import texture_size as sizing

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
    assert names[:4] == ["body", "eyes", "teeth", "tongue"]
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


# ---------------------------------------------------------------------------- OBJ, options


def test_obj_writes_every_part_with_its_mtl_and_textures(tmp_path, model):
    human = avatar.Human({"gender": 0.2}, model=model).dressed("tshirt")
    path = avatar.save(human, tmp_path / "h.obj")
    mesh = obj.read(path)
    parts = sizing.sized(human.parts())
    assert (
        list(mesh.face_groups)
        == [p.name for p in parts]
        == ["body", "eyes", "teeth", "tongue", "tshirt"]
    )
    start = 0
    for part in parts:  # vertices in part order, each part's faces under its object
        count = len(part.mesh.vertices)
        np.testing.assert_allclose(mesh.vertices[start : start + count], part.mesh.vertices,
                                   atol=1e-6)  # fmt: skip
        assert len(mesh.face_groups[part.name]) == len(part.mesh.faces)
        start += count
    library = obj.read_mtl(path.with_suffix(".mtl"))
    assert len(library) == 5
    for part in parts:
        entry = library[part.material.name]
        if part.material.base_color_texture is None:  # teeth, tongue: a colour
            assert "map_Kd" not in entry and part.name in ("teeth", "tongue")
            continue
        texture = images.read(tmp_path / entry["map_Kd"])
        np.testing.assert_array_equal(texture, part.material.base_color_texture)
    assert "map_Pr" in library["skin"] and "map_Bump" in library["tshirt"]
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temporary left


def test_obj_of_an_animation_is_its_first_frame_with_garments_out(tmp_path, model):
    from avatar.geometry import collision

    human = avatar.Human({"weight": 0.8}, model=model).dressed("tshirt")
    walk = human.walk(seconds=0.2, fps=10)
    mesh = obj.read(avatar.save(human, tmp_path / "w.obj", walk))
    body = human.posed(walk, slice(0, 1))[0][:13380]
    np.testing.assert_allclose(mesh.vertices[:13380], body, atol=1e-5)
    shirt = mesh.vertices[np.unique(mesh.faces[mesh.face_groups["tshirt"]])]
    faces = model.base.faces[model.base.face_groups["body"]]
    assert collision.penetration(body, faces, shirt)[0] == 0


@pytest.mark.skipif(not VALIDATOR.is_dir() or shutil.which("node") is None,
                    reason="Khronos gltf-validator not installed (scripts/setup.sh)")  # fmt: skip
def test_game_engine_options_write_a_valid_glb(tmp_path, model):
    human = avatar.Human({"gender": 0.6}, rig="game_engine", model=model).dressed("tshirt")
    walk = human.walk(seconds=0.2, fps=15)
    path = avatar.save(human, tmp_path / "g.glb", walk, max_influences=4, texture_size=256,
                       lods=2, expressions=True)  # fmt: skip
    done = subprocess.run(["node", str(ROOT / "tests/io/validate_gltf.cjs"), str(VALIDATOR),
                           str(path)], capture_output=True, text=True, check=True)  # fmt: skip
    issues = json.loads(done.stdout)["issues"]
    assert issues["numErrors"] == 0 and issues["numWarnings"] == 0, issues["messages"][:5]
    raw = pygltflib.GLTF2().load(str(path))
    assert all(getattr(p.attributes, "JOINTS_1", None) is None for m in raw.meshes
               for p in m.primitives)  # fmt: skip
    back = gltf.read(path)
    names = [p.name for p in back.parts]
    assert names == ["body", "eyes", "teeth", "tongue", "tshirt", "body_LOD1", "body_LOD2",
                     "tshirt_LOD1", "tshirt_LOD2"]  # fmt: skip
    by_name = {p.name: p for p in back.parts}
    for name in ("body", "tshirt"):
        counts = [len(by_name[n].mesh.faces) for n in (name, f"{name}_LOD1", f"{name}_LOD2")]
        assert 0.35 < counts[1] / counts[0] < 0.65 and 0.35 < counts[2] / counts[1] < 0.65
        assert by_name[f"{name}_LOD1"].skin is not None
    assert len(by_name["body_LOD1"].morphs) == 52  # expressions kept on the levels
    keyed = back.morph_weights["animation"]
    assert "tshirt_LOD1" in keyed and keyed["tshirt_LOD1"].shape == keyed["tshirt"].shape
    for part in back.parts:
        for image in part.material.textures().values():
            assert max(image.shape[:2]) <= 256


def test_textures_are_sized_to_their_part_by_default(fixtures, model):
    from avatar.clothes import library

    folder = fixtures / "makehuman"
    eyebrow = library.load_garment(folder / "eyebrows/eyebrow001/eyebrow001.mhclo")
    human = avatar.Human(model=model).dressed(eyebrow.source)
    parts = {p.name: p for p in sizing.sized(human.parts())}
    small = parts[eyebrow.name].material.textures()
    assert small and all(max(i.shape[:2]) <= sizing.MIN_SIZE for i in small.values())
    assert parts["body"].material.base_color_texture.shape[0] == 1024  # the body keeps its maps
    image = np.zeros((300, 100, 3), np.uint8)
    assert sizing.fit(image, 1024) is image and sizing.fit(image, 150).shape == (150, 50, 3)


@pytest.mark.parametrize("options,message", [({"max_influences": 6}, "4 or 8"),
                                             ({"texture_size": 3}, "texture size"),
                                             ({"lods": 9}, "0 to 6")])  # fmt: skip
def test_bad_export_options_are_clear_errors(tmp_path, model, options, message):
    human = avatar.Human(model=model)
    with pytest.raises(ParameterError, match=message):
        avatar.save(human, tmp_path / "x.glb", **options)
    assert not list(tmp_path.iterdir())


def test_makehuman_garments_hide_the_body_they_cover_by_default(fixtures, model):
    suit = str(fixtures / "makehuman/clothes/female_casualsuit01/female_casualsuit01.mhclo")
    human = avatar.Human(model=model).dressed(suit, "socks")
    full = len(human.part("body").faces)
    assert human.hidden_by() == ["female_casualsuit01"]  # MakeHuman's, not the built-in
    body = human.parts()[0].mesh
    assert len(body.faces) < 0.8 * full  # jeans and T-shirt hide most of the skin
    assert len(human.parts(hide_covered=False)[0].mesh.faces) == full  # --keep-body
    assert human.hidden_by(True) == ["socks", "female_casualsuit01"] or set(
        human.hidden_by(True)) == {"socks", "female_casualsuit01"}  # fmt: skip
    assert len(human.parts(hide_covered=True)[0].mesh.faces) < len(body.faces)
    kept = avatar.Human(model=model, recipe=avatar.human.Recipe(hide_covered=False))
    assert kept.dressed(suit).hidden_by() == []  # the recipe's choice (a .mhm's False)

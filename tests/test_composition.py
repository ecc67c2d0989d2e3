"""The composition root: one Human per character, names checked where they enter, records
handed down (``avatar.body.shaped.Body``), files in and out through one registry."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

import avatar
from avatar.errors import AvatarError, ParameterError

# Counts what one `avatar create --wear tshirt` builds, in a fresh process (empty caches).
COUNT = r"""
import json, sys
import avatar.body.assets as assets
import avatar.clothes.builtin as builtin
import avatar.human as human
import avatar.rig.placement as placement
from avatar.cli import main

counts = {"humans": 0, "asset_loads": 0, "rig_placements": [], "garments_built": 0}
def counting(module, name, key):
    original = getattr(module, name)
    def wrapper(*args, **kwargs):
        if key == "rig_placements":
            counts[key].append(args[1])  # the vertices the rig is placed on
        else:
            counts[key] += 1
        return original(*args, **kwargs)
    setattr(module, name, wrapper)
counting(assets, "load", "asset_loads")
counting(builtin, "build", "garments_built")
counting(placement.RigDefinition, "skeleton", "rig_placements")
init = human.Human.__init__
def counted_init(self, *a, **k):
    counts["humans"] += 1
    init(self, *a, **k)
human.Human.__init__ = counted_init
made = []
original_from_recipe = human.Human.from_recipe.__func__
def recording(cls, *a, **k):
    made.append(original_from_recipe(cls, *a, **k))
    return made[-1]
human.Human.from_recipe = classmethod(recording)
assert main(["create", "--set", "pca/belly=1.5", "--wear", "tshirt", "-o", sys.argv[1]]) == 0
from avatar.body.shaped import default_vertices
placed = counts.pop("rig_placements")
mine = made[0].vertices
counts["rig_placements_on_the_human"] = sum(v is mine for v in placed)
counts["rig_placements_on_the_library_body"] = sum(
    v is default_vertices(made[0].model) for v in placed)
counts["rig_placements"] = len(placed)
print(json.dumps(counts))
"""


def test_create_builds_one_human_places_its_rig_once_and_loads_assets_once(tmp_path, model):
    """One `avatar create --wear tshirt`: one Human, its rig placed once, the assets loaded
    once, the garment built once. The built-in garments are cut from the library's default
    body, whose rig is placed once per process (the garment's landmarks)."""
    out = subprocess.run([sys.executable, "-c", COUNT, str(tmp_path / "h.glb")], check=True,
                         capture_output=True, text=True).stdout  # fmt: skip
    counts = json.loads(out.strip().splitlines()[-1])
    assert counts["humans"] == 1, counts
    assert counts["asset_loads"] == 1, counts
    assert counts["garments_built"] == 1, counts
    assert counts["rig_placements_on_the_human"] == 1, counts
    assert counts["rig_placements_on_the_library_body"] == 1, counts
    assert counts["rig_placements"] == 2, counts


def test_unknown_garment_is_refused_when_worn_with_close_matches(model):
    human = avatar.Human(model=model)
    with pytest.raises(ParameterError, match="tshirt"):
        human.dressed("tshrt")
    with pytest.raises(ParameterError, match="tshirt"):
        avatar.Human.from_recipe({"clothes": ["tshrt"]}, model)
    with pytest.raises(AvatarError, match="missing.mhclo"):
        human.dressed("missing.mhclo")


def test_unknown_rig_and_parameter_name_close_matches(model):
    with pytest.raises(ParameterError, match="game_engine"):
        avatar.Human(rig="game_engin", model=model)
    with pytest.raises(ParameterError, match="gender"):
        avatar.Human({"gendr": 1.0}, model=model)


def test_body_record_is_what_the_human_realises(model):
    human = avatar.Human({"weight": 0.8}, rig="game_engine", model=model)
    body = human.body
    assert body is human.body  # realised once
    assert body.vertices is human.vertices and body.skeleton is human.skeleton
    assert body.weights is human.weights and body.model is model and body.rig == "game_engine"
    np.testing.assert_array_equal(body.skin_index, human.part_vertices("body"))
    assert body.skin_vertices.shape == (13380, 3)
    with pytest.raises(AttributeError):
        body.rig = "default"  # frozen


def test_walk_and_retarget_take_a_skeleton_and_an_optional_body(model):
    human = avatar.Human(model=model)
    plain = avatar.walk(human.skeleton, seconds=0.2, fps=10)
    hung = human.walk(seconds=0.2, fps=10)  # arms hung clear of this body's torso
    assert plain.frames == hung.frames == 2
    assert not np.allclose(plain.rotations, hung.rotations)
    with pytest.raises(AttributeError):
        avatar.walk(human, seconds=0.2)  # a Human is not a Skeleton: no run-time branching


@pytest.mark.parametrize("suffix", [".glb", ".gltf", ".obj", ".mhm", ".bvh"])
def test_load_reads_back_what_save_wrote(tmp_path, model, suffix):
    human = avatar.Human({"gender": 0.9, "weight": 0.7}, rig="game_engine", model=model)
    path = avatar.save(human, tmp_path / f"h{suffix}", human.pose("t-pose"))
    loaded = avatar.load(path)
    if suffix == ".mhm":
        assert loaded.params == pytest.approx(model.defaults() | human.params)
        assert loaded.recipe.rig == "game_engine"
    elif suffix == ".obj":  # every part: the body's 13,380 vertices first, then the eyes
        assert list(loaded.face_groups)[:2] == ["body", "eyes"]
        assert np.unique(loaded.faces[loaded.face_groups["body"]]).max() == 13379
    elif suffix == ".bvh":
        skeleton, animation = loaded
        assert sorted(skeleton.names) == sorted(human.skeleton.names) and animation.frames == 1
    else:
        assert loaded.skeleton.names == human.skeleton.names
        assert [p.name for p in loaded.parts] == ["body", "eyes", "teeth", "tongue"]


def test_load_refuses_unknown_suffixes_and_missing_files(tmp_path):
    with pytest.raises(AvatarError, match="unknown input format"):
        avatar.load(tmp_path / "x.xyz")
    with pytest.raises(AvatarError, match="no such file"):
        avatar.load(tmp_path / "missing.glb")


def test_the_extension_path_needs_no_pygltflib_nor_tqdm(model):
    """Debian's Blender (the UI test, legacy add-on installs) has numpy, SciPy and Pillow
    only: making, dressing and staging a character must not import pygltflib or tqdm."""
    code = (
        "import sys; sys.modules['pygltflib'] = None; sys.modules['tqdm'] = None\n"
        "import avatar, avatar.export\n"
        "human = avatar.Human().dressed('tshirt')\n"
        "parts = human.parts()\n"
        "print(len(parts))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True,
                         text=True).stdout  # fmt: skip
    assert out.strip() == "5"  # body, eyes, teeth, tongue, tshirt


def test_create_takes_asset_folders_and_game_engine_options(fixtures, tmp_path, model):
    """`create --folder DIR --wear NAME`: a MakeHuman asset found by name in the folder,
    its covered skin hidden (MakeHuman's default) unless --keep-body; the .mhm names it as
    MakeHuman does and re-creates the same character; the GLB options reach the file."""
    from avatar import cli
    from avatar.io import gltf, mhm

    folder = str(fixtures / "makehuman")
    out = tmp_path / "suit.mhm"
    assert cli.main(["create", "--folder", folder, "--wear", "female_casualsuit01",
                     "--wear", "short02", "-o", str(out)]) == 0  # fmt: skip
    lines = mhm.dumps(mhm.read(out)).splitlines()
    assert "clothes female_casualsuit01 a8b0e841-144b-4f03-8b9e-ea8fdce8c863" in lines
    assert "hair short02 c104cd4a-1edc-43f9-8b94-f63345a44638" in lines
    glb = tmp_path / "suit.glb"
    assert cli.main(["create", str(out), "--folder", folder, "--max-influences", "4",
                     "--texture-size", "128", "--lods", "1", "-o", str(glb)]) == 0  # fmt: skip
    parts = {p.name: p for p in gltf.read(glb).parts}
    assert {"female_casualsuit01", "short02", "body_LOD1", "short02_LOD1"} <= set(parts)
    assert len(parts["body"].mesh.vertices) < 13380  # covered skin left out
    assert max(parts["short02"].material.base_color_texture.shape[:2]) <= 128
    kept = tmp_path / "kept.glb"
    assert cli.main(["create", str(out), "--folder", folder, "--keep-body",
                     "-o", str(kept)]) == 0  # fmt: skip
    assert len(gltf.read(kept).parts[0].mesh.vertices) == 13380

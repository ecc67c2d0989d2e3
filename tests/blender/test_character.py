"""The extension's engine (``avatar.blender.character`` and ``live``) on real characters:
recipes stored, bodies changed in place, garments added and removed, failures that change
nothing, motion applied through a swap. Skipped without the MakeHuman assets."""

from __future__ import annotations

import json
import os
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from bridge_fixtures import box_mesh

from avatar.body.shaped import PART_GROUPS

ROOT = Path(__file__).resolve().parents[2]
FIXTURES = Path(os.environ.get("AVATAR_FIXTURES", ROOT.parent / "shared" / "fixtures"))
WALK = FIXTURES / "bvh" / "cmu_motionbuilder" / "02_01_walk.bvh"



def _body(built):
    from avatar.blender import live, mesh

    return mesh.read_vertices(live.part_objects(built.root)["body"])


def test_create_stores_the_recipe_and_update_changes_it_in_place(empty_scene, assets):
    from avatar.blender import character, live
    from avatar.human import Human

    built = character.create({"params": {"height": 0.2}}, name="Eve", location=(1, 0, 0))
    assert built.root.name == "Eve" and tuple(built.root.location) == (1, 0, 0)
    assert json.loads(built.root["avatar_recipe"])["params"] == {"height": 0.2}
    body = live.part_objects(built.root)["body"]
    again = character.update(built.parts[0], {"params": {"height": 0.8}})
    assert again.root == built.root and live.part_objects(again.root)["body"] == body
    np.testing.assert_allclose(_body(again), Human({"height": 0.8}).mesh.vertices, atol=1e-5)


def test_unrigged_characters_have_the_body_as_root(empty_scene, assets):
    from avatar.blender import character, live

    built = character.create({"params": {}, "clothes": ["eyebrows"]}, rigged=False)
    assert built.armature is None and built.root.type == "MESH"
    assert set(live.part_objects(built.root)) == {*PART_GROUPS, "eyebrows"}
    live.set_params(built.root, {"weight": 0.9})
    assert json.loads(built.root["avatar_recipe"])["params"]["weight"] == 0.9


def test_failed_update_keeps_the_old_character(empty_scene, assets):
    from avatar.blender import character
    from avatar.errors import AvatarError

    built = character.create({"params": {"height": 0.5}, "clothes": ["eyebrows"]})
    before, recipe = _body(built).copy(), built.root["avatar_recipe"]
    bad_recipes = (
        {"params": {"height": float("nan")}},
        {"params": {"heigth": 0.3}},
        {"params": {}, "clothes": ["no-such-garment"]},
        {"params": {}, "rig": "nope"},
    )
    for bad in bad_recipes:
        with pytest.raises(AvatarError):
            character.update(built.root, bad)
        np.testing.assert_array_equal(_body(built), before)
        assert built.root["avatar_recipe"] == recipe


def test_template_meshes_carry_the_skin_weights(empty_scene, assets):
    from avatar.blender import character
    from avatar.human import Human

    first = character.create({"params": {}})
    second = character.create({"params": {"weight": 1.0}})
    human = Human()
    for built in (first, second):
        body = built.parts[0]
        names = [g.name for g in body.vertex_groups]
        assert names == list(human.skeleton.names)
        weights = np.zeros((len(body.data.vertices), len(names)))
        for v in body.data.vertices:
            for g in v.groups:
                weights[v.index, g.group] = g.weight
        skin = human.body.skin_weights
        want = np.zeros_like(weights)
        np.put_along_axis(want, skin.indices, skin.weights, axis=1)
        np.testing.assert_allclose(weights, want, atol=1e-6)
        assert body.data.materials[0] is not None


@pytest.mark.skipif(not WALK.is_file(), reason="needs the CMU BVH fixtures")
def test_motion_is_applied_and_survives_update(empty_scene, assets):
    from avatar.blender import character, live

    built = character.create({"params": {}, "clothes": ["eyebrows"]}, name="Walker")
    spec = {"path": str(WALK), "frames": [1, 7], "fps": None, "in_place": False}
    moved, summary = character.apply_motion(built.parts[0], spec)
    assert moved.root.name == "Walker" and "6 frames" in summary
    assert moved.root.animation_data.action is not None
    again = character.update(moved.root, {"params": {"height": 0.9}, "clothes": ["eyebrows"]})
    assert json.loads(again.root["avatar_motion"]) == spec  # the motion is re-applied
    assert again.root.animation_data.action is not None
    assert set(live.part_objects(again.root)) == {*PART_GROUPS, "eyebrows"}


def test_a_failed_motion_never_deletes_the_character(empty_scene, assets, tmp_path):
    import bpy

    from avatar.blender import character
    from avatar.errors import AvatarError

    built = character.create({"params": {}}, name="Keeper")
    names = sorted(o.name for o in bpy.data.objects)
    for path in (tmp_path / "missing.bvh", ""):
        with pytest.raises(AvatarError):
            character.apply_motion(built.root, {"path": str(path), "frames": None})
    bad = tmp_path / "bad.bvh"
    bad.write_text("HIERARCHY\nROOT Hips\n{\n")
    with pytest.raises(AvatarError):
        character.apply_motion(built.root, {"path": str(bad), "frames": None})
    assert sorted(o.name for o in bpy.data.objects) == names


def test_not_a_character(empty_scene):
    from avatar.blender import character
    from avatar.blender.mesh import new_mesh_object
    from avatar.errors import AvatarError

    obj = new_mesh_object("cube", box_mesh((0, 0, 0), (1, 1, 1)))
    assert character.recipe_of(obj) is None
    with pytest.raises(AvatarError):
        character.update(obj, {"params": {}})
    with pytest.raises(AvatarError):
        character.apply_motion(obj, SimpleNamespace())


def test_trees_are_built_before_the_call_returns_inside_blender():
    """A k-d tree thread still running when the next operator ran crashed Blender (a
    segfault in CI, in mode_set during character.create): with bpy loaded, a tree asked for
    "later" is built at once, so no Python thread runs while Blender works."""
    import bpy  # noqa: F401  (the condition the tree builder looks at)

    from avatar.geometry.nearest import PointTree

    future = PointTree.later(np.random.default_rng(0).random((500, 3)))
    assert future.done() and len(future.result()) == 500

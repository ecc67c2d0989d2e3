"""Characters remember their recipe; update rebuilds in place; errors leave the scene alone."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest
from bridge_fixtures import box_mesh, skeleton


class FakeHuman:
    """Stands in for avatar.human.Human: height scales a box on a fixed skeleton."""

    def __init__(self, recipe):
        from avatar.errors import ParameterError

        self.spec = recipe
        self.recipe = SimpleNamespace(clothes=())  # wears nothing: no garment bake
        height = recipe["params"].get("height", 0.5)
        if not 0 <= height <= 1:
            raise ParameterError("height out of range")
        self.mesh = box_mesh((0, 0, 0), (0.4, 0.3, 1.0 + height))
        self.skeleton = skeleton(np.random.default_rng(1))
        self.weights = (np.zeros((8, 1), np.int32), np.ones((8, 1)))
        self.body = None  # the shaped-body record retargeting settles on

    def to_recipe(self):
        return self.spec

    def parts(self):
        from avatar.part import MeshPart

        return [MeshPart("body", self.mesh, None, self.weights)]


@pytest.fixture
def fake_library(monkeypatch):
    from avatar.blender import character

    monkeypatch.setattr(character, "realise", FakeHuman)
    return character


def height_of(built):
    from avatar.blender.scene import world_bounds

    lo, hi = world_bounds(built.parts)
    return hi[2] - lo[2]


def test_create_stores_the_recipe_and_update_rebuilds(empty_scene, fake_library):
    import bpy

    character = fake_library
    built = character.create({"params": {"height": 0.2}}, name="Eve", location=(1, 0, 0))
    assert character.recipe_of(built.parts[0]) == {"params": {"height": 0.2}}
    assert height_of(built) == pytest.approx(1.2)
    again = character.update(built.parts[0], {"params": {"height": 0.8}})
    assert again.root.name == "Eve" and tuple(again.root.location) == (1, 0, 0)
    assert height_of(again) == pytest.approx(1.8)
    assert len([o for o in bpy.data.objects if o.type == "ARMATURE"]) == 1
    assert len(bpy.data.meshes) == 1  # the old body's mesh went with it


def test_failed_update_keeps_the_old_character(empty_scene, fake_library):
    from avatar.errors import AvatarError

    character = fake_library
    built = character.create({"params": {"height": 0.5}})
    with pytest.raises(AvatarError, match="out of range"):
        character.update(built.root, {"params": {"height": 7.0}})
    assert json.loads(built.root["avatar_recipe"]) == {"params": {"height": 0.5}}


def test_motion_is_applied_and_survives_update(empty_scene, fake_library, monkeypatch):
    from bridge_fixtures import random_animation

    import avatar.motion

    character = fake_library
    calls = []

    def retarget(source, clip, target, body, frames, fps, in_place):
        calls.append((clip, frames, fps, in_place))
        # the Motion panel retargets onto the Human's body (its skin settles the feet)
        return random_animation(target, np.random.default_rng(2), frames=6), None

    monkeypatch.setattr(avatar.motion, "load_bvh", lambda path: (None, path))
    monkeypatch.setattr(avatar.motion, "retarget", retarget)
    built = character.create({"params": {}})
    built_name = built.root.name
    spec = {"path": "walk.bvh", "frames": [1, 7], "fps": 30, "in_place": False}
    moved, summary = character.apply_motion(built.parts[0], spec)
    assert "6 frames" in summary and moved.root.name == built_name
    assert moved.root.animation_data.action is not None
    again = character.update(moved.root, {"params": {"height": 0.9}})
    assert again.root.animation_data.action is not None
    assert json.loads(again.root["avatar_motion"]) == spec
    assert calls[-1] == ("walk.bvh", slice(1, 7), 30, False)


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

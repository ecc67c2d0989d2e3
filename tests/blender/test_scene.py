"""Staging: characters built from records, recipes stored, camera framing everything."""

from __future__ import annotations

import json

import numpy as np
from bridge_fixtures import box_mesh, figure, skeleton


def test_character_from_records(empty_scene, rng):
    from avatar.blender import scene
    from avatar.part import MeshPart

    skel = skeleton(rng)
    body = MeshPart("body", box_mesh((0, 0, 0), (1, 1, 1)), None,
                    (np.zeros((8, 1), np.int32), np.ones((8, 1))))  # fmt: skip
    character = scene.Character("Ann", [body], skel, recipe={"macros": {"age": 0.5}})
    built = scene.build_character(character)
    assert built.armature is built.root and built.root.name == "Ann"
    assert json.loads(built.root["avatar_recipe"]) == {"macros": {"age": 0.5}}
    body = built.parts[0]
    assert body.parent is built.armature
    assert body.modifiers["Armature"].object is built.armature
    assert [g.name for g in body.vertex_groups] == list(skel.names)


def test_parts_with_normals_and_morphs(empty_scene, rng):
    from avatar.blender import scene
    from avatar.part import MeshPart

    box = box_mesh((0, 0, 0), (1, 1, 1))
    normals = np.tile(np.array([[0.0, 0.0, 1.0]], np.float32), (8, 1))
    part = MeshPart("lid", box, morphs={"open": np.ones((8, 3), np.float32) * 0.1},
                    normals=normals)  # fmt: skip
    built = scene.build_character(scene.Character("box", [part]))
    obj = built.root
    assert obj is built.parts[0] and built.armature is None
    assert obj.data.shape_keys.key_blocks.keys() == ["Basis", "open"]
    corner = np.array([n.vector[:] for n in obj.data.corner_normals])
    # Blender stores custom normals compressed (about 1e-4 rad resolution).
    np.testing.assert_allclose(corner, np.tile([0, 0, 1], (len(corner), 1)), atol=2e-4)


def test_camera_sees_every_character(empty_scene, rng):
    import bpy
    from bpy_extras.object_utils import world_to_camera_view
    from mathutils import Vector

    from avatar.blender import render

    built = render.stage_characters([figure(rng, f"f{i}") for i in range(4)], (400, 200))
    cam, sc = bpy.context.scene.camera, bpy.context.scene
    for obj in (o for b in built for o in b.parts):
        for corner in obj.bound_box:
            x, y, depth = world_to_camera_view(sc, cam, obj.matrix_world @ Vector(corner))
            assert 0 <= x <= 1 and 0 <= y <= 1 and depth > 0


def test_failed_build_adds_nothing(empty_scene, rng):
    import bpy
    import pytest

    from avatar.blender import scene
    from avatar.part import MeshPart

    good = MeshPart("ok", box_mesh((0, 0, 0), (1, 1, 1)))
    bad = MeshPart(
        "bad", box_mesh((0, 0, 0), (1, 1, 1)), skin=(np.full((8, 1), 99), np.ones((8, 1)))
    )
    with pytest.raises(IndexError):
        scene.build_character(scene.Character("broken", [good, bad], skeleton(rng)))
    assert len(bpy.data.objects) == 0 and "broken" not in bpy.data.collections

"""Blender exports carry the baked garment corrections: shape keys stepped by a Key action.

Blender plays what the file will: the Armature modifier skins every vertex group, frame t's
shape key is on at scene frame 1 + t, and the garments land on ``Outfit.frame(exact=True)``
with no vertex inside the body.
"""

from __future__ import annotations

import numpy as np
import pytest

GARMENTS = ("tshirt", "jeans")


@pytest.fixture(scope="module")
def dressed(heavy_walker):
    return heavy_walker(0.3)


def _exact_frames(human, walk, frames):
    """(t, skinned body (V, 3), exact garments [(M, 3)] in layer order) for ``frames``."""
    from avatar.rig import kinematics, skinning

    world = kinematics.forward(human.skeleton, walk.rotations, walk.translations)
    matrices = kinematics.skinning_matrices(human.skeleton, world)
    for t in frames:
        body = skinning.linear_blend(human.vertices, human.weights, matrices[t])
        yield t, body, human.outfit.frame(body, matrices[t], exact=True)


def _objects():
    import bpy

    return {o.name: o for o in bpy.data.objects if o.type == "MESH"}


def _frame_keys(obj) -> list[str]:
    keys = obj.data.shape_keys
    return [k.name for k in keys.key_blocks if k.name.startswith("frame_")] if keys else []


def test_blend_export_plays_the_exact_frames_with_no_garment_inside(empty_scene, dressed, tmp_path):
    import bpy

    import avatar
    from avatar.blender import mesh
    from avatar.geometry import collision

    human, walk = dressed
    avatar.save(human, tmp_path / "walk.blend", walk)  # the scene it wrote stays open
    objects = _objects()
    triangles = collision.skin_surface(human.model.base.faces).triangles
    names = [g.name for g in human.outfit]
    for t, skinned, exact in _exact_frames(human, walk, (0, walk.frames // 2, walk.frames - 1)):
        bpy.context.scene.frame_set(1 + t)  # the action starts at frame 1
        body = mesh.read_vertices(objects["body"], evaluated=True)
        np.testing.assert_allclose(body, skinned[:13380], atol=1e-4)
        for name, want in zip(names, exact, strict=True):
            got = mesh.read_vertices(objects[name], evaluated=True)
            np.testing.assert_allclose(got, want, atol=1e-4, err_msg=f"{name} frame {t}")
            assert not np.any(collision.winding_number(got, body, triangles) > 0), (name, t)
    assert (tmp_path / "walk.blend").stat().st_size > 1000


def test_frame_keys_are_stepped_by_the_key_action(empty_scene, dressed, tmp_path):
    import bpy

    import avatar

    human, walk = dressed
    avatar.save(human, tmp_path / "walk.usdc", walk)
    for name in GARMENTS:
        obj = _objects()[name]
        frames = [int(k.split("_")[1]) for k in _frame_keys(obj)]
        assert frames and set(frames) <= set(range(walk.frames))
        curves = obj.data.shape_keys.animation_data.action.layers[0].strips[0].channelbags[0]
        assert all(p.interpolation == "CONSTANT" for c in curves.fcurves for p in c.keyframe_points)
        for t in (0, frames[len(frames) // 2], walk.frames - 1):
            bpy.context.scene.frame_set(1 + t)
            on = [k.name for k in obj.data.shape_keys.key_blocks[1:] if k.value != 0]
            assert on == ([f"frame_{t:04d}"] if t in frames else []), (name, t)


def test_fbx_carries_the_stepped_keys(empty_scene, dressed, tmp_path):
    """FBX round trip: the keys and their animation come back (the importer starts one frame
    later, the armature's action too)."""
    import bpy

    import avatar
    from avatar.blender import scene

    human, walk = dressed
    path = avatar.save(human, tmp_path / "walk.fbx", walk)
    scene.clear_scene()
    bpy.ops.import_scene.fbx(filepath=str(path))
    armature = next(o for o in bpy.data.objects if o.type == "ARMATURE")
    start = round(armature.animation_data.action.frame_range[0])
    obj = _objects()["tshirt"]
    frames = [int(k.split("_")[1]) for k in _frame_keys(obj)]
    assert frames and obj.data.shape_keys.animation_data.action is not None
    for t in frames[:: max(1, len(frames) // 3)]:
        bpy.context.scene.frame_set(start + t)
        on = [k.name for k in obj.data.shape_keys.key_blocks[1:] if k.value > 0.5]
        assert on == [f"frame_{t:04d}"]


def test_plain_export_has_no_frame_keys(empty_scene, dressed, tmp_path):
    import avatar

    human, walk = dressed
    avatar.save(human, tmp_path / "plain.blend", walk, resolve_garments=False)
    objects = _objects()
    assert set(GARMENTS) <= set(objects)
    assert not any(_frame_keys(o) for o in objects.values())


def test_morph_weights_become_constant_steps(empty_scene):
    """Any (T, K) weights: the keyed values at every frame are the weights."""
    import bpy
    from bridge_fixtures import box_mesh

    from avatar.blender import mesh, morph_action

    obj = mesh.new_mesh_object("box", box_mesh((0, 0, 0), (1, 1, 1)))
    names = ["a", "b", "c"]
    mesh.set_shape_keys(obj, {n: np.full((8, 3), 0.1, np.float32) for n in names})
    weights = np.zeros((6, 3), np.float32)
    weights[2, 0], weights[[0, 1, 4], 1] = 1.0, [0.5, 0.5, 1.0]  # "c" never moves
    morph_action.apply_morph_weights(obj, names, weights, frame_start=3)
    channelbag = obj.data.shape_keys.animation_data.action.layers[0].strips[0].channelbags[0]
    assert len(channelbag.fcurves) == 2
    for t in range(6):
        bpy.context.scene.frame_set(3 + t)
        got = [obj.data.shape_keys.key_blocks[n].value for n in names]
        np.testing.assert_allclose(got, weights[t])


def test_morph_weights_are_checked(empty_scene):
    from bridge_fixtures import box_mesh

    from avatar.blender import mesh, morph_action
    from avatar.errors import AvatarError

    obj = mesh.new_mesh_object("box", box_mesh((0, 0, 0), (1, 1, 1)))
    with pytest.raises(AvatarError, match="no shape key"):
        morph_action.apply_morph_weights(obj, ["a"], np.ones((2, 1)))
    with pytest.raises(AvatarError, match="must be"):
        morph_action.apply_morph_weights(obj, ["a"], np.ones((2, 2)))

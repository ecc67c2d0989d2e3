"""Blender exports carry the baked garment corrections: a few shape keys a garment driven by
a Key action (their per-frame values).

Blender plays what the file will: the Armature modifier skins every vertex group, the keys
take frame t's values at scene frame 1 + t, and the garments land on
``Outfit.frame(exact=True)`` within the bake's bound, no vertex 1 mm inside the body.
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
    """The correction shape keys of a garment."""
    from avatar.clothes.bake import BASIS_PREFIX

    keys = obj.data.shape_keys
    return [k.name for k in keys.key_blocks if k.name.startswith(BASIS_PREFIX)] if keys else []


def test_blend_export_plays_the_exact_frames_with_no_garment_inside(empty_scene, dressed, tmp_path):
    import bpy

    import avatar
    from avatar.blender import mesh
    from avatar.clothes.bake import ERROR_BOUND
    from avatar.geometry import collision

    human, walk = dressed
    avatar.save(human, tmp_path / "walk.blend", walk)  # the scene it wrote stays open
    objects = _objects()
    faces = human.model.base.faces[human.model.base.face_groups["body"]]
    names = [g.name for g in human.outfit]
    for t, skinned, exact in _exact_frames(human, walk, (0, walk.frames // 2, walk.frames - 1)):
        bpy.context.scene.frame_set(1 + t)  # the action starts at frame 1
        body = mesh.read_vertices(objects["body"], evaluated=True)
        np.testing.assert_allclose(body, skinned[:13380], atol=1e-4)
        for name, want in zip(names, exact, strict=True):
            got = mesh.read_vertices(objects[name], evaluated=True)
            error = np.linalg.norm(got - want, axis=1).max()
            assert error <= ERROR_BOUND + 1e-4, (name, t, error)
            assert collision.penetration(body, faces, got)[1].max() <= 1e-3, (name, t)
    assert (tmp_path / "walk.blend").stat().st_size > 1000


def test_correction_keys_are_driven_by_the_key_action(empty_scene, dressed, tmp_path):
    import bpy

    import avatar
    from avatar.clothes.correction_basis import MAX_BASIS

    human, walk = dressed
    avatar.save(human, tmp_path / "walk.usdc", walk)
    for name in GARMENTS:
        obj = _objects()[name]
        keys = _frame_keys(obj)
        assert 0 < len(keys) <= MAX_BASIS + 1
        curves = obj.data.shape_keys.animation_data.action.layers[0].strips[0].channelbags[0]
        assert all(p.interpolation == "CONSTANT" for c in curves.fcurves for p in c.keyframe_points)
        values = []
        for t in range(walk.frames):
            bpy.context.scene.frame_set(1 + t)
            values.append([obj.data.shape_keys.key_blocks[k].value for k in keys])
        assert np.any(np.asarray(values) != 0), name  # the keys move over the clip


def test_fbx_carries_the_keys_and_their_action(empty_scene, dressed, tmp_path):
    """FBX round trip: the keys and their animation come back (the importer starts one frame
    later, the armature's action too)."""
    import bpy

    import avatar
    from avatar.blender import scene

    human, walk = dressed
    path = avatar.save(human, tmp_path / "walk.fbx", walk)
    scene.clear_scene()
    bpy.ops.import_scene.fbx(filepath=str(path))
    obj = _objects()["tshirt"]
    keys = _frame_keys(obj)
    assert keys and obj.data.shape_keys.animation_data.action is not None


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

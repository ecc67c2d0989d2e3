"""Avatar's GLB opens correctly in Blender: mesh, armature, rolls, shape keys, action, poses."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from avatar.io import gltf

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "io"))
from gltf_fixtures import scene  # noqa: E402


def test_blender_imports_avatar_glb(tmp_path, empty_scene):
    import bpy

    parts, sk, anim = scene()
    path = tmp_path / "limb.glb"
    gltf.write(path, parts, sk, {"bend": anim})
    # Blender's importer converts seconds to frames at the scene's rate: match the clip's.
    bpy.context.scene.render.fps, bpy.context.scene.render.fps_base = round(anim.fps), 1.0
    bpy.ops.import_scene.gltf(filepath=str(path))

    limb = bpy.data.objects["limb"]
    seams = len(gltf.split_vertices(parts[0].mesh)[0])
    assert len(limb.data.vertices) == seams == 48  # 16 corners, each on 3 UV islands
    assert [k.name for k in limb.data.shape_keys.key_blocks] == ["Basis", "bulge", "poke",
                                                                 "nothing"]  # fmt: skip
    assert limb.data.materials[0].name == "skin"
    assert [g.name for g in limb.vertex_groups] == list(sk.names)

    armature = next(o for o in bpy.data.objects if o.type == "ARMATURE")
    assert armature.name == "Rig" and len(armature.data.bones) == 3
    rest = np.array([np.array(armature.data.bones[n].matrix_local) for n in sk.names])
    np.testing.assert_allclose(rest, sk.rest, atol=1e-5)  # heads, directions and rolls

    action = bpy.data.actions["bend"]
    assert tuple(action.frame_range) == (0.0, anim.frames - 1)
    for frame in (0, 5, anim.frames - 1):
        bpy.context.scene.frame_set(frame)
        for j, name in enumerate(sk.names):
            q = np.array(armature.pose.bones[name].rotation_quaternion)
            np.testing.assert_allclose(np.abs(q @ anim.rotations[frame, j]), 1.0, atol=1e-5)
        location = np.array(armature.pose.bones["root"].location)
        np.testing.assert_allclose(location, anim.translations[frame, 0], atol=1e-5)


def test_blender_imports_a_real_walking_human(tmp_path, empty_scene, model):
    import bpy

    import avatar

    human = avatar.Human({"gender": 0.2, "age": 0.3}, model=model)
    walk = avatar.walk(human.skeleton, seconds=0.5, fps=24)
    path = avatar.save(human, tmp_path / "walker.glb", walk, expressions=True)
    bpy.context.scene.render.fps, bpy.context.scene.render.fps_base = 24, 1.0
    bpy.ops.import_scene.gltf(filepath=str(path))

    body = bpy.data.objects["body"]
    assert len(body.data.vertices) == len(gltf.split_vertices(human.parts()[0].mesh)[0])
    assert (
        len(body.data.shape_keys.key_blocks) == 53 and "jawOpen" in body.data.shape_keys.key_blocks
    )
    image = body.data.materials[0].node_tree.nodes["Image Texture"].image
    assert tuple(image.size) == (1024, 1024)  # the procedural skin came along
    armature = next(o for o in bpy.data.objects if o.type == "ARMATURE")
    sk = human.skeleton
    assert len(armature.data.bones) == len(sk.names)
    rest = np.array([np.array(armature.data.bones[n].matrix_local) for n in sk.names])
    np.testing.assert_allclose(rest, sk.rest, atol=1e-4)
    (action,) = bpy.data.actions
    assert tuple(action.frame_range) == (0.0, walk.frames - 1)  # 24 fps file, 24 fps scene
    bpy.context.scene.frame_set(6)
    pose = np.array([np.array(armature.pose.bones[n].rotation_quaternion) for n in sk.names])
    np.testing.assert_allclose(np.abs(np.sum(pose * walk.rotations[6], axis=1)), 1.0, atol=1e-5)

"""Skeleton -> armature -> action: Blender evaluates exactly what Avatar's kinematics computes."""

from __future__ import annotations

import numpy as np
import pytest
from bridge_fixtures import grid_mesh, random_animation, skeleton

from avatar.rig.kinematics import forward

bpy = pytest.importorskip("bpy")


def test_armature_rest_matrices_equal_skeleton(empty_scene, rng):
    from avatar.blender import armature

    skel = skeleton(rng)
    obj = armature.new_armature_object("rig", skel)
    rest = armature.rest_matrices(obj, skel.names)
    np.testing.assert_allclose(rest, skel.rest, atol=1e-5)
    tails = np.array([obj.data.bones[n].tail_local for n in skel.names])
    np.testing.assert_allclose(tails, skel.tails, atol=1e-5)
    parents = [obj.data.bones[n].parent for n in skel.names]
    assert [skel.names.index(p.name) if p else -1 for p in parents] == list(skel.parents)


def test_action_matches_forward_kinematics(empty_scene, rng):
    from avatar.blender import action, armature

    skel = skeleton(rng)
    anim = random_animation(skel, rng, frames=5)
    obj = armature.new_armature_object("rig", skel)
    action.apply_animation(obj, anim)
    expected = forward(skel, anim.rotations, anim.translations)
    scene = bpy.context.scene
    assert (scene.frame_start, scene.frame_end, scene.render.fps) == (1, 5, 30)
    for t in range(anim.frames):
        scene.frame_set(1 + t)
        np.testing.assert_allclose(armature.pose_matrices(obj, skel.names), expected[t], atol=1e-4)


def test_skinned_mesh_follows_the_root(empty_scene, rng):
    from avatar.blender import action, armature, mesh

    skel = skeleton(rng)
    anim = random_animation(skel, rng, frames=2)
    grid = grid_mesh(3)
    count = len(grid.vertices)
    body = mesh.new_mesh_object("body", grid)
    mesh.set_vertex_groups(body, skel.names, np.zeros((count, 1), int), np.ones((count, 1)))
    rig = armature.new_armature_object("rig", skel)
    armature.bind(body, rig)
    action.apply_animation(rig, anim)
    bpy.context.scene.frame_set(2)
    world = forward(skel, anim.rotations, anim.translations)[1, 0] @ np.linalg.inv(skel.rest[0])
    expected = grid.vertices @ world[:3, :3].T + world[:3, 3]
    np.testing.assert_allclose(mesh.read_vertices(body, evaluated=True), expected, atol=1e-4)

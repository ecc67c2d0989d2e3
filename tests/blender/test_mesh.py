"""numpy Mesh -> Blender mesh: positions, faces, UVs, groups and shape keys survive."""

from __future__ import annotations

import numpy as np
from bridge_fixtures import grid_mesh


def test_mesh_round_trip(empty_scene):
    from avatar.blender import mesh as bridge

    mesh = grid_mesh(5)
    obj = bridge.new_mesh_object("grid", mesh)
    back = bridge.read_mesh(obj)
    np.testing.assert_array_equal(back.vertices, mesh.vertices)
    np.testing.assert_array_equal(back.faces, mesh.faces)
    np.testing.assert_allclose(back.uvs[back.face_uvs], mesh.uvs[mesh.face_uvs], atol=1e-7)
    assert all(p.use_smooth for p in obj.data.polygons)


def test_triangles_round_trip(empty_scene):
    from avatar.blender import mesh as bridge
    from avatar.mesh import Mesh

    quads = grid_mesh(3)
    tris = Mesh(quads.vertices, quads.triangles())
    back = bridge.read_mesh(bridge.new_mesh_object("tris", tris))
    np.testing.assert_array_equal(back.faces, tris.faces)


def test_vertex_groups_hold_the_weights(empty_scene, rng):
    from avatar.blender import mesh as bridge

    mesh = grid_mesh(4)
    count = len(mesh.vertices)
    indices = rng.integers(0, 3, size=(count, 2))
    indices[:, 1] = (indices[:, 0] + 1) % 3
    weights = rng.random((count, 2))
    weights /= weights.sum(axis=1, keepdims=True)
    obj = bridge.new_mesh_object("skinned", mesh)
    bridge.set_vertex_groups(obj, ["a", "b", "c"], indices, weights)
    dense = np.zeros((count, 3))
    for v in obj.data.vertices:
        for g in v.groups:
            dense[v.index, g.group] = g.weight
    expected = np.zeros((count, 3))
    np.put_along_axis(expected, indices, weights, axis=1)
    np.testing.assert_allclose(dense, expected, atol=1e-6)


def test_shape_keys_are_offsets(empty_scene, rng):
    from avatar.blender import mesh as bridge

    mesh = grid_mesh(2)
    delta = rng.normal(size=mesh.vertices.shape).astype(np.float32) * 0.01
    obj = bridge.new_mesh_object("keyed", mesh)
    bridge.set_shape_keys(obj, {"smile": delta})
    obj.data.shape_keys.key_blocks["smile"].value = 1.0
    posed = bridge.read_vertices(obj, evaluated=True)
    np.testing.assert_allclose(posed, mesh.vertices + delta, atol=1e-6)

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


def test_evaluated_mesh_in_world_space_splits_ngons(empty_scene):
    import bpy
    from mathutils import Matrix

    from avatar.blender import mesh as bridge

    # a triangle, a quad and a pentagon sharing vertices, as a user models them
    verts = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (2, 0, 0), (2, 1, 0), (3, 0.5, 0)]
    data = bpy.data.meshes.new("mixed")
    data.from_pydata(verts, [], [(0, 1, 3), (1, 4, 5, 2), (4, 6, 5, 2, 1)])
    data.uv_layers.new(name="UVMap")
    obj = bpy.data.objects.new("mixed", data)
    bpy.context.scene.collection.objects.link(obj)
    obj.location = (0.5, 0, 0)
    shift = obj.modifiers.new("shift", "DISPLACE")  # along the normal, +Z
    shift.strength, shift.mid_level = 0.25, 0.0

    to_frame = Matrix.Translation((0, 0, -1))
    mesh = bridge.read_evaluated_mesh(obj, to_frame)
    np.testing.assert_allclose(mesh.vertices, np.add(verts, [0.5, 0, -0.75]), atol=1e-6)
    assert mesh.faces.shape == (1 + 1 + 3, 4)
    assert mesh.faces[0].tolist() == [0, 1, 3, 3]  # a triangle beside quads repeats a corner
    assert mesh.face_uvs.shape == mesh.faces.shape and mesh.face_uvs.max() < len(mesh.uvs)
    pentagon = {tuple(sorted(set(f))) for f in mesh.faces[2:].tolist()}
    assert set().union(*pentagon) == {1, 2, 4, 5, 6}


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



def test_shell_normals_reach_blender_unless_a_face_repeats_a_vertex(empty_scene):
    """A garment part's own normals (``library.garment_normals``) become the object's
    custom normals; on a mesh whose faces repeat a vertex (triangles padded to quads, the
    hoodie's drawstrings) Blender segfaulted setting them, so such a part keeps Blender's."""
    import bpy

    from avatar.blender import mesh as bridge
    from avatar.blender import scene
    from avatar.mesh import Mesh
    from avatar.part import MeshPart

    grid = grid_mesh(3)
    up = np.tile(np.float32([0.0, 0.6, 0.8]), (len(grid.vertices), 1))
    collection = bpy.context.scene.collection
    built = scene._build_part(MeshPart("flat", grid, None, normals=up), None, None, collection)
    corner = np.empty(len(built.data.loops) * 3, np.float32)
    built.data.loops.foreach_get("normal", corner)
    np.testing.assert_allclose(corner.reshape(-1, 3), np.tile(up[0], (len(built.data.loops), 1)),
                               atol=1e-3)  # fmt: skip
    padded = grid.faces.copy()
    padded[0, 3] = padded[0, 2]
    assert bridge.repeats_corners(padded) and not bridge.repeats_corners(grid.faces)
    part = MeshPart("padded", Mesh(grid.vertices, padded, grid.uvs, grid.face_uvs), None,
                    normals=up)  # fmt: skip
    assert scene._build_part(part, None, None, collection).name == "padded"

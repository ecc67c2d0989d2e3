"""numpy Mesh -> Blender mesh object, and back.

Everything goes through ``foreach_set``/``foreach_get`` (one C call per attribute), so a
19k-vertex body builds in milliseconds. Avatar's frame is Blender's: no axis conversion.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import bpy
import numpy as np

from avatar.mesh import Mesh


def mesh_data(name: str, mesh: Mesh) -> bpy.types.Mesh:
    """A new ``bpy.types.Mesh`` with ``mesh``'s vertices, faces and per-corner UVs.

    mesh.vertices (V, 3) metres; mesh.faces (F, N) with N = 3 or 4; mesh.face_uvs (F, N)
    indices into mesh.uvs (U, 2). Faces are shaded smooth (skin and cloth are smooth surfaces).
    """
    faces = np.asarray(mesh.faces, dtype=np.int32)
    n_faces, corners = faces.shape
    data = bpy.data.meshes.new(name)
    data.vertices.add(len(mesh.vertices))
    data.vertices.foreach_set("co", np.asarray(mesh.vertices, np.float32).ravel())
    data.loops.add(faces.size)
    data.loops.foreach_set("vertex_index", faces.ravel())
    data.polygons.add(n_faces)
    data.polygons.foreach_set("loop_start", np.arange(n_faces, dtype=np.int32) * corners)
    data.polygons.foreach_set("loop_total", np.full(n_faces, corners, dtype=np.int32))
    data.update(calc_edges=True)
    if mesh.uvs is not None and mesh.face_uvs is not None:
        _set_uvs(data, mesh.uvs[np.asarray(mesh.face_uvs).ravel()])
    _shade_smooth(data)
    return data


def _shade_smooth(data: bpy.types.Mesh) -> None:
    if hasattr(data, "shade_smooth"):  # Blender 4.1+
        data.shade_smooth()
    else:
        data.polygons.foreach_set("use_smooth", np.ones(len(data.polygons), dtype=bool))


def _set_uvs(data: bpy.types.Mesh, corner_uvs: np.ndarray) -> None:
    """corner_uvs: (F*N, 2) one UV per face corner, in loop order."""
    layer = data.uv_layers.new(name="UVMap")
    layer.data.foreach_set("uv", np.asarray(corner_uvs, np.float32).ravel())


def new_mesh_object(
    name: str, mesh: Mesh, collection: bpy.types.Collection | None = None
) -> bpy.types.Object:
    """A new object holding ``mesh_data(name, mesh)``, linked to ``collection`` or the scene."""
    obj = bpy.data.objects.new(name, mesh_data(name, mesh))
    (collection or bpy.context.scene.collection).objects.link(obj)
    return obj


def set_vertex_groups(
    obj: bpy.types.Object,
    names: Sequence[str],
    indices: np.ndarray,
    weights: np.ndarray,
) -> None:
    """Create one vertex group per name and fill it from sparse skin weights.

    names: J group (bone) names. indices: (V, K) int joint indices per vertex.
    weights: (V, K) float weights; zero weights are skipped.
    """
    indices = np.asarray(indices)
    weights = np.asarray(weights, dtype=np.float64)
    groups = [obj.vertex_groups.new(name=n) for n in names]
    vert, slot = np.nonzero(weights > 0)
    joint, value = indices[vert, slot], weights[vert, slot]
    # vg.add takes one weight per call; sorting by (joint, weight) batches equal weights.
    order = np.lexsort((value, joint))
    vert, joint, value = vert[order], joint[order], value[order]
    breaks = np.flatnonzero((np.diff(joint) != 0) | (np.diff(value) != 0)) + 1
    for run in np.split(np.arange(len(vert)), breaks):
        if len(run):
            groups[joint[run[0]]].add(vert[run].tolist(), float(value[run[0]]), "REPLACE")


def set_shape_keys(obj: bpy.types.Object, offsets: Mapping[str, np.ndarray]) -> None:
    """Add a Basis key and one shape key per entry.

    offsets: name -> (V, 3) displacement from the rest vertices (metres), as morph targets
    and MakeHuman targets are stored. Keys start at value 0.
    """
    if not offsets:
        return
    if obj.data.shape_keys is None:
        obj.shape_key_add(name="Basis", from_mix=False)
    rest = read_vertices(obj)
    for name, delta in offsets.items():
        key = obj.shape_key_add(name=name, from_mix=False)
        key.data.foreach_set("co", (rest + np.asarray(delta, np.float32)).ravel())
        key.value = 0.0


def set_normals(obj: bpy.types.Object, normals: np.ndarray) -> None:
    """Custom per-vertex normals (V, 3) (e.g. the body's, so seams between parts match)."""
    if bpy.app.version < (4, 1):  # older Blenders ignore custom normals without auto smooth
        obj.data.use_auto_smooth = True
    obj.data.normals_split_custom_set_from_vertices(np.asarray(normals, np.float32))


def repeats_corners(faces: np.ndarray) -> bool:
    """Whether any face (F, N) names a vertex twice (a triangle padded to a quad): Blender
    crashed (segfault) setting custom normals on such a mesh (the hoodie's drawstrings)."""
    f = np.asarray(faces)
    return bool(np.any(f == np.roll(f, -1, axis=1)))


def read_vertices(obj: bpy.types.Object, evaluated: bool = False) -> np.ndarray:
    """(V, 3) float32 vertex positions in object space; ``evaluated`` applies modifiers/keys."""
    if evaluated:
        depsgraph = bpy.context.evaluated_depsgraph_get()
        ev = obj.evaluated_get(depsgraph)
        data = ev.to_mesh()
        try:
            return _vertices(data)
        finally:
            ev.to_mesh_clear()
    return _vertices(obj.data)


def _vertices(data: bpy.types.Mesh) -> np.ndarray:
    out = np.empty(len(data.vertices) * 3, dtype=np.float32)
    data.vertices.foreach_get("co", out)
    return out.reshape(-1, 3)


def read_mesh(obj: bpy.types.Object) -> Mesh:
    """The object's mesh as a Mesh record (vertices, faces, per-corner UVs).

    All faces must have the same corner count (the record holds one (F, N) array).
    """
    data = obj.data
    totals = np.empty(len(data.polygons), dtype=np.int32)
    data.polygons.foreach_get("loop_total", totals)
    corners = int(totals[0]) if len(totals) else 3
    loops = np.empty(len(data.loops), dtype=np.int32)
    data.loops.foreach_get("vertex_index", loops)
    uvs = face_uvs = None
    if data.uv_layers.active is not None:
        uvs = np.empty(len(data.loops) * 2, dtype=np.float32)
        data.uv_layers.active.data.foreach_get("uv", uvs)
        uvs = uvs.reshape(-1, 2)
        face_uvs = np.arange(len(uvs), dtype=np.int32).reshape(-1, corners)
    return Mesh(_vertices(data), loops.reshape(-1, corners), uvs, face_uvs)


def read_evaluated_mesh(obj: bpy.types.Object, to_frame=None) -> Mesh:
    """The object as it shows (modifiers, shape keys applied) as a Mesh record in world space,
    or in the frame the 4x4 ``to_frame`` maps world space to (e.g. a character's).

    Blender meshes mix triangles, quads and n-gons, the record holds one (F, N) array: n-gons
    become their triangles, and next to quads a triangle repeats its last corner (as
    ``avatar.io.obj`` reads such meshes). UVs are the active layer's, equal values merged.
    """
    evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    data = evaluated.to_mesh()
    try:
        corners = _face_corners(data)
        loop_vertex = np.empty(len(data.loops), dtype=np.int32)
        data.loops.foreach_get("vertex_index", loop_vertex)
        vertices = _vertices(data).astype(np.float64)
        loop_uvs = None
        if data.uv_layers.active is not None:
            loop_uvs = np.empty(len(data.loops) * 2, dtype=np.float32)
            data.uv_layers.active.data.foreach_get("uv", loop_uvs)
    finally:
        evaluated.to_mesh_clear()
    matrix = obj.matrix_world if to_frame is None else to_frame @ obj.matrix_world
    m = np.array(matrix, dtype=np.float64)
    vertices = vertices @ m[:3, :3].T + m[:3, 3]
    uvs = face_uvs = None
    if loop_uvs is not None:
        uvs, inverse = np.unique(loop_uvs.reshape(-1, 2), axis=0, return_inverse=True)
        face_uvs = inverse.reshape(-1).astype(np.int32)[corners]
    return Mesh(vertices.astype(np.float32), loop_vertex[corners], uvs, face_uvs)


def _face_corners(data: bpy.types.Mesh) -> np.ndarray:
    """(F, N) loop indices of the faces, N = 4 if there are quads else 3 (see above)."""
    start = np.empty(len(data.polygons), dtype=np.int32)
    total = np.empty(len(data.polygons), dtype=np.int32)
    data.polygons.foreach_get("loop_start", start)
    data.polygons.foreach_get("loop_total", total)
    n = 4 if (total == 4).any() else 3
    small = total <= 4
    faces = start[small, None] + np.minimum(np.arange(n), total[small, None] - 1)
    if small.all():
        return faces.astype(np.int32)
    data.calc_loop_triangles()
    tris = np.empty(len(data.loop_triangles) * 3, dtype=np.int32)
    data.loop_triangles.foreach_get("loops", tris)
    owner = np.empty(len(data.loop_triangles), dtype=np.int32)
    data.loop_triangles.foreach_get("polygon_index", owner)
    tris = tris.reshape(-1, 3)[~small[owner]]
    return np.concatenate([faces, tris[:, [0, 1, 2, 2][:n]]]).astype(np.int32)

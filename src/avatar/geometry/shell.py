"""Solidify a single-layer garment into a shell with hems (thickness you can see in a render).

Vertex layout of a shell over an N-vertex surface: 0..N-1 the inner (bound) surface,
N..2N-1 the outer surface; faces: outer (original winding), inner (reversed), and one quad
per boundary edge closing the hem. The outer surface is placed per fit or frame by
``extrude`` (along the body normal, so it is outward whatever the garment's winding).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from avatar.mesh import Mesh, face_normals


@dataclass(frozen=True)
class Shell:
    """The topology of a solidified surface (see module docstring)."""

    mesh: Mesh
    count: int  # N, vertices of the bound surface


def boundary_edges(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Directed boundary edges (E, 2) of polygon faces (F, 3|4) and the (E, 2) (face, corner)
    they start at, following the faces' winding."""
    f = faces
    n = f.shape[1]
    a = f.reshape(-1)
    b = np.roll(f, -1, axis=1).reshape(-1)
    face = np.repeat(np.arange(len(f)), n)
    corner = np.tile(np.arange(n), len(f))
    real = a != b  # padded triangles repeat their last index
    a, b, face, corner = a[real], b[real], face[real], corner[real]
    key = np.minimum(a, b).astype(np.int64) * (1 << 32) + np.maximum(a, b)
    _, inverse, counts = np.unique(key, return_inverse=True, return_counts=True)
    edge = counts[inverse] == 1
    return np.stack([a[edge], b[edge]], 1), np.stack([face[edge], corner[edge]], 1)


def solidify(mesh: Mesh) -> Shell:
    """The shell topology of a surface mesh (quads or triangles, UVs optional)."""
    n = len(mesh.vertices)
    faces = mesh.faces
    edges, where = boundary_edges(faces)
    hem = np.stack([edges[:, 0], edges[:, 1], edges[:, 1] + n, edges[:, 0] + n], 1)
    if faces.shape[1] == 3:  # one face width for all: pad triangles (last index repeated)
        faces = np.concatenate([faces, faces[:, -1:]], 1)
        flip = np.array([0, 2, 1, 1])
    else:
        flip = np.array([2, 1, 0, 3])  # the reversed cycle, padding (if any) kept last
    inner = faces[:, flip]
    all_faces = np.concatenate([faces + n, inner, hem]).astype(np.int32)
    uvs = face_uvs = None
    if mesh.uvs is not None and mesh.face_uvs is not None:
        fuv = (
            mesh.face_uvs
            if mesh.face_uvs.shape[1] == 4
            else np.concatenate([mesh.face_uvs, mesh.face_uvs[:, -1:]], 1)
        )
        ncorner = mesh.faces.shape[1]
        ua = mesh.face_uvs[where[:, 0], where[:, 1]]
        ub = mesh.face_uvs[where[:, 0], (where[:, 1] + 1) % ncorner]
        # The hem strip reuses the edge's UVs, shifted a little so the band is not degenerate.
        shifted = mesh.uvs[ua] + np.float32(0.01)
        extra = np.arange(len(mesh.uvs), len(mesh.uvs) + len(ua))
        uvs = np.concatenate([mesh.uvs, shifted]).astype(np.float32)
        hem_uv = np.stack([ua, ub, extra, extra], 1)
        face_uvs = np.concatenate([fuv, fuv[:, flip], hem_uv]).astype(np.int32)
    groups = {"outer": np.arange(n, 2 * n, dtype=np.int32), "inner": np.arange(n, dtype=np.int32)}
    shell_mesh = Mesh(
        vertices=np.concatenate([mesh.vertices, mesh.vertices]),
        faces=all_faces,
        uvs=uvs,
        face_uvs=face_uvs,
        groups=groups,
    )
    return Shell(shell_mesh, n)


def layer_normals(shell: Shell, vertices: np.ndarray) -> np.ndarray:
    """(2N, 3) float32 unit vertex normals of a shell posed at ``vertices`` (2N, 3), each
    layer's from its own faces alone: the hem quads, at right angles to the cloth, left
    out. Averaged in (Blender weighs a vertex's faces by their corner angles), they turned
    the normals along every open edge up to 45 degrees out of the cloth, and smooth shading
    spread that over the whole row of faces under the edge: a dress's skirt top, 1.5 mm
    proud of its bodice, read from behind as a step across the back (a light edge over a
    dark band)."""
    faces = shell.mesh.faces
    layer = faces[np.all(faces >= shell.count, axis=1) | np.all(faces < shell.count, axis=1)]
    v = np.asarray(vertices, np.float64)
    normal = face_normals(v, layer)  # area-weighted, as ``mesh.vertex_normals``
    summed = np.stack([sum(np.bincount(layer[:, k], normal[:, axis], len(v))
                           for k in range(layer.shape[1])) for axis in range(3)], 1)  # fmt: skip
    size = np.linalg.norm(summed, axis=1, keepdims=True)
    return (summed / np.maximum(size, 1e-12)).astype(np.float32)


def extrude(inner: np.ndarray, normals: np.ndarray, thickness: float) -> np.ndarray:
    """(..., 2N, 3) shell vertices: inner (..., N, 3) then inner + thickness * normals."""
    outer = inner + np.float32(thickness) * normals
    return np.concatenate([inner, outer], axis=-2).astype(np.float32)


def corner_gather(faces: np.ndarray, count: int):
    """(count, F) sparse float32: 1 where a face meets a vertex (a padded triangle's
    repeated corner once), to sum faces' values at vertices (``summed_normals``)."""
    from scipy.sparse import csr_matrix

    pairs = np.unique(np.stack([faces.ravel(), np.repeat(np.arange(len(faces)), faces.shape[1])],
                               1), axis=0)  # fmt: skip
    return csr_matrix((np.ones(len(pairs), np.float32), (pairs[:, 0], pairs[:, 1])),
                      shape=(count, len(faces)))  # fmt: skip


def summed_normals(points: np.ndarray, faces: np.ndarray, gather) -> np.ndarray:
    """(N, 3) float64 each vertex's faces' normals (quads or padded triangles ``faces``,
    the cross product of their diagonals) summed, unnormalised; gather: ``corner_gather``."""
    c = np.asarray(points, np.float64)[faces]
    return np.asarray(gather @ np.cross(c[:, 2] - c[:, 0], c[:, -1] - c[:, 1]))

"""The mesh record shared by every module: arrays in, arrays out."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np


@dataclass(frozen=True)
class Mesh:
    """A polygon mesh in Avatar's frame (Blender's: metres, Z-up, facing -Y).

    vertices: (V, 3) float32 positions.
    faces: (F, N) int32 vertex indices; N = 3 or 4 (quads; a triangle repeats its last index
        is *not* used: mixed meshes are split into ``faces`` quads and triangles by the caller).
    uvs: (U, 2) float32 texture coordinates, or None.
    face_uvs: (F, N) int32 indices into ``uvs``, or None.
    groups: name -> (k,) int32 vertex indices (e.g. MakeHuman's ``body``, ``joint-*``).
    face_groups: name -> (k,) int32 face indices.
    """

    vertices: np.ndarray
    faces: np.ndarray
    uvs: np.ndarray | None = None
    face_uvs: np.ndarray | None = None
    groups: dict[str, np.ndarray] = field(default_factory=dict)
    face_groups: dict[str, np.ndarray] = field(default_factory=dict)

    def with_vertices(self, vertices: np.ndarray) -> Mesh:
        """The same topology with new vertex positions (V, 3)."""
        return replace(self, vertices=np.asarray(vertices, dtype=np.float32))

    def triangles(self) -> np.ndarray:
        """(T, 3) int32 triangles; quads split along their 0-2 diagonal."""
        f = self.faces
        if f.shape[1] == 3:
            return f
        return np.concatenate([f[:, [0, 1, 2]], f[:, [0, 2, 3]]]).astype(np.int32)

    def subset(self, face_index: np.ndarray) -> Mesh:
        """A mesh of the given faces only, with unused vertices and UVs dropped."""
        faces = self.faces[face_index]
        used, inverse = np.unique(faces, return_inverse=True)
        new = replace(
            self,
            vertices=self.vertices[used],
            faces=inverse.reshape(faces.shape).astype(np.int32),
            groups={},
            face_groups={},
        )
        if self.face_uvs is not None and self.uvs is not None:
            fuv = self.face_uvs[face_index]
            used_uv, inv_uv = np.unique(fuv, return_inverse=True)
            new = replace(
                new, uvs=self.uvs[used_uv], face_uvs=inv_uv.reshape(fuv.shape).astype(np.int32)
            )
        return new


def face_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(..., F, 3) unnormalised face normals (twice the area for triangles).

    For quads, the cross product of the diagonals (robust for non-planar quads).
    """
    v = vertices[..., faces, :]
    if faces.shape[1] == 4:
        n = np.cross(v[..., 2, :] - v[..., 0, :], v[..., 3, :] - v[..., 1, :])
    else:
        n = np.cross(v[..., 1, :] - v[..., 0, :], v[..., 2, :] - v[..., 0, :])
    return n


def face_edges(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(K, 2) every edge of faces (F, N), each as its sorted vertex pair (an edge two faces
    share appears twice), and (K,) the face each belongs to. The zero-length edge of a
    padded triangle (a quad repeating its last corner) is dropped."""
    edges = np.sort(np.stack([faces, np.roll(faces, -1, axis=1)], -1).reshape(-1, 2), axis=1)
    owner = np.repeat(np.arange(len(faces)), faces.shape[1])
    real = edges[:, 0] != edges[:, 1]
    return edges[real], owner[real]


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(V, 3) float32 unit vertex normals, area-weighted over adjacent faces."""
    fn = face_normals(vertices, faces)
    out = np.zeros(vertices.shape, dtype=np.float64)
    for k in range(faces.shape[1]):
        np.add.at(out, faces[:, k], fn)
    length = np.linalg.norm(out, axis=-1, keepdims=True)
    return (out / np.maximum(length, 1e-12)).astype(np.float32)

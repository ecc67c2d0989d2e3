"""Skin weights and skinning: linear blend (LBS) and dual quaternion (DQS).

Written as numbered steps in the manner of smplx's ``lbs.py``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import csr_matrix

from avatar.rig import quaternion


@dataclass(frozen=True)
class SkinWeights:
    """Per-vertex bone influences, padded to K with weight 0.

    indices: (V, K) int32 bone indices; weights: (V, K) float32, each row summing to 1.
    """

    indices: np.ndarray
    weights: np.ndarray

    @classmethod
    def from_lists(
        cls,
        vertex_count: int,
        bone_of_entry: np.ndarray,
        vertex: np.ndarray,
        weight: np.ndarray,
        fallback_bone: int = 0,
    ) -> SkinWeights:
        """Build from flat (bone, vertex, weight) triples; unweighted vertices follow
        ``fallback_bone``; rows are normalised to sum 1."""
        keep = weight > 0
        bone_of_entry, vertex, weight = bone_of_entry[keep], vertex[keep], weight[keep]
        order = np.lexsort((-weight, vertex))
        bone_of_entry, vertex, weight = bone_of_entry[order], vertex[order], weight[order]
        counts = np.bincount(vertex, minlength=vertex_count)
        k = max(int(counts.max(initial=1)), 1)
        slot = np.arange(len(vertex)) - np.repeat(np.cumsum(counts) - counts, counts)
        idx = np.zeros((vertex_count, k), dtype=np.int32)
        w = np.zeros((vertex_count, k), dtype=np.float64)
        idx[vertex, slot] = bone_of_entry
        w[vertex, slot] = weight
        empty = counts == 0
        idx[empty, 0], w[empty, 0] = fallback_bone, 1.0
        w /= w.sum(axis=1, keepdims=True)
        return cls(idx, w.astype(np.float32))

    def limit(self, k: int) -> SkinWeights:
        """Keep the ``k`` largest influences per vertex, renormalised (for game engines)."""
        if self.weights.shape[1] <= k:
            return self
        cache = self.__dict__.setdefault("_limited", {})  # a garment's weights serve every body
        if k not in cache:
            order = np.argsort(-self.weights, axis=1)[:, :k]
            w = np.take_along_axis(self.weights, order, 1).astype(np.float64)
            w /= np.maximum(w.sum(axis=1, keepdims=True), 1e-12)
            indices = np.take_along_axis(self.indices, order, 1)
            cache[k] = SkinWeights(indices, w.astype(np.float32))
        return cache[k]

    def subset(self, vertex_index: np.ndarray) -> SkinWeights:
        """Weights of the given vertices only."""
        return SkinWeights(self.indices[vertex_index], self.weights[vertex_index])

    def matrix(self, bones: int) -> csr_matrix:
        """(V, J) sparse float32 weight matrix, built once per bone count (skinning's hot path)."""
        cache = self.__dict__.setdefault("_matrices", {})  # frozen: cache beside the fields
        if bones not in cache:
            v, k = self.indices.shape
            rows = np.repeat(np.arange(v), k)
            m = csr_matrix((self.weights.ravel(), (rows, self.indices.ravel())), (v, bones))
            m.sum_duplicates()
            m.eliminate_zeros()
            cache[bones] = m.astype(np.float32)
        return cache[bones]

    def dense(self, bones: int) -> np.ndarray:
        """(V, J) dense weight matrix."""
        out = np.zeros((len(self.indices), bones), dtype=np.float32)
        np.add.at(out, (np.arange(len(self.indices))[:, None], self.indices), self.weights)
        return out


def linear_blend(vertices: np.ndarray, weights: SkinWeights, matrices: np.ndarray) -> np.ndarray:
    """Linear blend skinning.

    vertices: (V, 3) rest positions; matrices: (..., J, 4, 4) skinning matrices
    (world @ inverse rest). Returns (..., V, 3) float32 posed positions.
    """
    matrices = np.asarray(matrices)
    batch, bones = matrices.shape[:-3], matrices.shape[-3]
    # 1. Blend the 3x4 matrices per vertex, sum_k w_k M_{b_k}, as one sparse product
    #    (V, J) @ (J, frames * 12): most padded influences are zero, and numpy's einsum
    #    over tiny matrices is ~15x slower.
    m = np.moveaxis(matrices[..., :3, :].reshape(*batch, bones, 12), -2, 0)
    blended = weights.matrix(bones) @ m.reshape(bones, -1).astype(np.float32)
    b = np.moveaxis(blended.reshape(len(blended), -1, 12), 1, 0)  # (frames, V, 12)
    # 2. Apply to homogeneous rest positions, component by component.
    v = np.asarray(vertices, dtype=np.float32)
    x, y, z = v[:, 0], v[:, 1], v[:, 2]
    out = np.empty(b.shape[:2] + (3,), np.float32)
    for i in range(3):
        r = b[..., 4 * i : 4 * i + 4]
        out[..., i] = r[..., 0] * x + r[..., 1] * y + r[..., 2] * z + r[..., 3]
    return out.reshape(*batch, len(v), 3)


def dual_quaternions(matrices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rigid (..., J, 4, 4) -> real (..., J, 4) and dual (..., J, 4) quaternion parts."""
    real = quaternion.from_matrix(matrices[..., :3, :3])
    t = np.concatenate([np.zeros(matrices.shape[:-2] + (1,)), matrices[..., :3, 3]], axis=-1)
    dual = 0.5 * quaternion.multiply(t, real)
    return real, dual


def dual_quaternion(vertices: np.ndarray, weights: SkinWeights, matrices: np.ndarray) -> np.ndarray:
    """Dual quaternion skinning (Kavan et al. 2007); same arguments as ``linear_blend``.

    Avoids LBS's candy-wrapper collapse under twists. Matrices must be rigid.
    """
    real, dual = dual_quaternions(matrices)
    # 1. Gather each vertex's bone quaternions, flipped into the hemisphere of the first.
    r = real[..., weights.indices, :]  # (..., V, K, 4)
    d = dual[..., weights.indices, :]
    sign = np.where(np.sum(r * r[..., :1, :], axis=-1, keepdims=True) < 0, -1.0, 1.0)
    w = weights.weights[..., None] * sign
    # 2. Blend and normalise.
    br = np.sum(w * r, axis=-2)
    bd = np.sum(w * d, axis=-2)
    norm = np.linalg.norm(br, axis=-1, keepdims=True)
    br, bd = br / norm, bd / norm
    # 3. Rotate then translate: t = 2 * dual * conj(real).
    rot = quaternion.to_matrix(br)
    trans = 2.0 * quaternion.multiply(bd, quaternion.conjugate(br))[..., 1:]
    out = np.einsum("...vij,vj->...vi", rot, vertices) + trans
    return out.astype(np.float32)

"""Garment skin weights: the garment's own ``.mhw`` file, or the body's through the binding.

MakeHuman 1.1 (``proxy.Proxy.getVertexWeights``): garment vertex i gets, for each bone, the
sum over its three references of (binding weight x body weight), products below 1e-4 dropped
(this also drops negative barycentric weights), then each vertex is normalised; a vertex left
with nothing follows the root bone.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from avatar.clothes.binding import Binding
from avatar.io.mhw import BoneWeights
from avatar.rig.skinning import SkinWeights

MIN_WEIGHT = 1e-4  # MakeHuman's threshold


def transfer(binding: Binding, body: SkinWeights, max_influences: int = 8) -> SkinWeights:
    """Skin weights of N garment vertices from the body's (V, K) weights.

    Returns SkinWeights with (N, <=max_influences) entries over the body's bones.
    """
    # 1. Every (reference, body influence) pair of each garment vertex: (N, 3 * K).
    bone = body.indices[binding.indices].reshape(len(binding), -1)
    w = (binding.weights[:, :, None] * body.weights[binding.indices]).reshape(len(binding), -1)
    w = np.where(w > MIN_WEIGHT, w, 0.0)
    # 2. Merge duplicate bones: sort by bone, sum runs.
    return _merge(bone, w, max_influences)


def _merge(bone: np.ndarray, w: np.ndarray, k: int) -> SkinWeights:
    """(N, M) bone ids and weights with repeats -> SkinWeights with the k largest sums."""
    order = np.argsort(bone, axis=1, kind="stable")
    bone = np.take_along_axis(bone, order, 1)
    w = np.take_along_axis(w, order, 1)
    start = np.ones_like(bone, dtype=bool)
    start[:, 1:] = bone[:, 1:] != bone[:, :-1]
    run = np.cumsum(start, axis=1) - 1  # run id per column
    summed = np.zeros(w.shape)
    np.add.at(summed, (np.arange(len(w))[:, None], run), w)
    run_bone = np.zeros(bone.shape, np.int32)
    rows = np.nonzero(start)[0]
    run_bone[rows, run[start]] = bone[start]
    top = np.argsort(-summed, axis=1)[:, :k]
    out_w = np.take_along_axis(summed, top, 1)
    out_b = np.take_along_axis(run_bone, top, 1)
    total = out_w.sum(axis=1, keepdims=True)
    empty = total[:, 0] <= 0
    out_w[empty, 0], out_b[empty, 0], total[empty] = 1.0, 0, 1.0  # root bone, as MakeHuman
    return SkinWeights(out_b.astype(np.int32), (out_w / total).astype(np.float32))


def from_file(
    weights: BoneWeights, bone_names: Sequence[str], vertex_count: int, max_influences: int = 8
) -> SkinWeights:
    """A garment's own ``.mhw`` weights over a skeleton's bones (by name, normalised).

    Bones the skeleton lacks are dropped; a vertex left without weight follows bone 0.
    """
    index = {name: i for i, name in enumerate(bone_names)}
    ids = np.array([index.get(b, -1) for b in weights.bones], dtype=np.int64)
    bone = ids[weights.bone] if len(weights.bone) else np.zeros(0, np.int64)
    keep = (bone >= 0) & (weights.vertex < vertex_count) & (weights.weight > 0)
    dense = np.zeros((vertex_count, max(len(bone_names), 1)), np.float64)
    np.add.at(dense, (weights.vertex[keep], bone[keep]), weights.weight[keep])
    top = np.argsort(-dense, axis=1)[:, :max_influences]
    w = np.take_along_axis(dense, top, 1)
    return _merge(top.astype(np.int32), w, max_influences)

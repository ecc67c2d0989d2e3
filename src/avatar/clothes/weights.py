"""Garment skin weights: the garment's own ``.mhw`` file, or the body's through the binding.

MakeHuman 1.1 (``proxy.Proxy.getVertexWeights``): garment vertex i gets, for each bone, the
sum over its three references of (binding weight x body weight), products below 1e-4 dropped
(this also drops negative barycentric weights), then each vertex is normalised; a vertex left
with nothing follows the root bone.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.sparse import csr_matrix
from scipy.spatial import cKDTree

from avatar.clothes.binding import Binding
from avatar.io.mhw import BoneWeights
from avatar.mesh import Mesh, face_edges
from avatar.rig.skinning import SkinWeights

MIN_WEIGHT = 1e-4  # MakeHuman's threshold
# A skirt's weights (``swing``): diffusion steps over its cloth (its rows lie 3-4 cm apart).
# 30 steps spread a bone's switch over ~15 cm, but the hem still followed one leg at the
# sides and both at the back, and turned 33 degrees where the two met mid-stride; 240 carry
# the hips' and thighs' weights down to the hem (the calf's pushes are shared smoothly,
# ``clothes.hems``): the dress's hem turned at most 31 degrees in the walk (26 at rest; 120
# steps 34, 360 31 but 29 on the skirt, more at the knee). Built once per rig: ~40 ms. And
# the influences each vertex keeps: with 4 or 6, a fading bone took the legs' share with it
# where four leg bones weigh alike (the back's midline followed the spine alone, 0.24 more
# spine weight than its neighbour 4 cm away).
SWING_ITERATIONS = 240
SWING_INFLUENCES = 8


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


def swing(
    weights: SkinWeights, mesh: Mesh, below: float, iterations: int = SWING_ITERATIONS,
    influences: int = SWING_INFLUENCES,
) -> SkinWeights:  # fmt: skip
    """A skirt's weights smoothed over its cloth below height ``below`` (m, on the authored
    mesh), so they ramp from the hips to the hem instead of switching bones between two
    rows of vertices.

    Transferred from the body, a skirt's weights switched from thigh to shin within two
    rows above the knee and from one leg to both at a corner of the sides' blend; mid-stride
    its hem folded there (a 42 degree notch over the knee). The weights are diffused over
    the mesh's edges (``iterations`` steps: ~15 cm), the vertices above ``below`` held, then
    each vertex keeps its ``influences`` largest with the next largest subtracted from them,
    so a bone fades out where it leaves the top ``influences`` instead of dropping (the
    frames' cut to 4 left a 5% shin weight on one hem vertex and not the next; frames skin
    these rows with all ``influences``: ``fitting._frame_weights``).

    weights: (N, K) over the body's bones; mesh: the garment's N authored vertices.
    Returns SkinWeights (N, <= max(K, influences)); vertices above ``below`` as given.
    """
    n = len(mesh.vertices)
    bones = int(weights.indices.max(initial=0)) + 1
    dense = np.zeros((n, bones))
    rows = np.repeat(np.arange(n), weights.indices.shape[1])
    np.add.at(dense, (rows, weights.indices.ravel()), weights.weights.ravel())
    free = mesh.vertices[:, 2] < below
    step = _neighbour_mean(mesh, free)
    for _ in range(iterations):
        dense[free] = 0.5 * dense[free] + 0.5 * (step @ dense)
    top = np.argsort(-dense, axis=1)
    kept = np.take_along_axis(dense, top[:, :influences], 1)
    if bones > influences:
        kept = kept - np.take_along_axis(dense, top[:, influences:influences + 1], 1)
    ramped = _merge(top[:, :influences].astype(np.int32), np.maximum(kept, 0.0), influences)
    width = max(weights.indices.shape[1], influences)
    idx = np.zeros((n, width), np.int32)
    w = np.zeros((n, width), np.float32)
    idx[:, : weights.indices.shape[1]], w[:, : weights.indices.shape[1]] = (
        weights.indices, weights.weights)  # fmt: skip
    idx[free], w[free] = 0, 0.0
    idx[free, :influences], w[free, :influences] = ramped.indices[free], ramped.weights[free]
    return SkinWeights(idx, w)


def shared_across(weights: SkinWeights, mesh: Mesh, share: np.ndarray) -> SkinWeights:
    """Weights of cloth spanning the body's midline blended with their mirror twins': each
    vertex keeps 1 - share/2 of its own and takes share/2 of its twin's (the vertex
    nearest its mirror image in x), so where share is 1 both halves move as one piece (the
    mean of the left and right legs' motion: the pelvis's, mid-stride).

    weights: (N, K); mesh: the garment's N authored vertices (symmetric about x = 0);
    share: (N,) in [0, 1]. Returns (N, K) SkinWeights; vertices with share 0 as given.
    """
    pick = np.flatnonzero(share > 0)
    if len(pick) == 0:
        return weights
    v = mesh.vertices.astype(np.float64)
    _, twin = cKDTree(v).query(v[pick] * np.array([-1.0, 1.0, 1.0]))
    half = share[pick, None] / 2
    bone = np.concatenate([weights.indices[pick], weights.indices[twin]], axis=1)
    w = np.concatenate([weights.weights[pick] * (1 - half), weights.weights[twin] * half], axis=1)
    blended = _merge(bone, w, weights.indices.shape[1])
    idx, wt = weights.indices.copy(), weights.weights.copy()
    idx[pick], wt[pick] = blended.indices, blended.weights
    return SkinWeights(idx, wt)


def _neighbour_mean(mesh: Mesh, rows: np.ndarray) -> csr_matrix:
    """(R, N) sparse: for each vertex of ``rows`` (N,) bool, the mean over its mesh
    neighbours (an isolated vertex keeps its own value)."""
    edges = np.unique(face_edges(mesh.faces)[0], axis=0)
    n = len(mesh.vertices)
    a = np.concatenate([edges[:, 0], edges[:, 1], np.arange(n)])
    b = np.concatenate([edges[:, 1], edges[:, 0], np.arange(n)])
    lonely = np.bincount(edges.ravel(), minlength=n) == 0
    value = np.concatenate([np.ones(2 * len(edges)), lonely.astype(np.float64)])
    adjacency = csr_matrix((value, (a, b)), shape=(n, n))[rows]
    degree = np.asarray(adjacency.sum(axis=1)).ravel()
    return csr_matrix(adjacency.multiply(1.0 / degree[:, None]))

"""glTF 2.0 skin weights (spec section 3.7.3.3): JOINTS_n/WEIGHTS_n columns of 4.

numpy only (no pygltflib), so code that must skin exactly as a glTF viewer will, such as
``avatar.clothes.bake``, can use it where pygltflib is not installed (a Blender's Python).
"""

from __future__ import annotations

import numpy as np

MAX_INFLUENCES = 8  # JOINTS_0 and JOINTS_1: what Babylon, Blender and Unity read
INFLUENCE_LIMITS = (4, 8)  # 4: JOINTS_0 only, what three.js and many engines skin with


def pack_weights(
    indices: np.ndarray, weights: np.ndarray, joint_count: int, limit: int = MAX_INFLUENCES
) -> tuple[np.ndarray, np.ndarray]:
    """Per-vertex influences -> glTF JOINTS/WEIGHTS columns (4 or 8 of them).

    indices, weights: (N, K) joint indices and weights, any K. Duplicate joints are merged,
    negative weights dropped, the ``limit`` (4 or 8) largest kept and renormalised to sum 1;
    a vertex with no weight at all goes to joint 0 (the root). Unused slots get joint 0 and
    weight 0, as the spec requires.
    Returns joints (N, 4|8) uint8 (uint16 over 256 joints) and weights (N, 4|8) float32.
    """
    if limit not in INFLUENCE_LIMITS:
        raise ValueError(f"at most 4 or 8 influences per vertex, not {limit}")
    idx = np.asarray(indices, dtype=np.int64).copy()
    w = np.clip(np.asarray(weights, dtype=np.float64), 0.0, None).copy()
    if np.any((idx < 0) | (idx >= joint_count)) and np.any(w[(idx < 0) | (idx >= joint_count)]):
        raise ValueError(f"skin joint index out of range 0..{joint_count - 1}")
    w[(idx < 0) | (idx >= joint_count)] = 0.0
    _merge_duplicates(idx, w)
    order = np.argsort(-w, axis=1, kind="stable")[:, :limit]
    idx, w = np.take_along_axis(idx, order, 1), np.take_along_axis(w, order, 1)
    empty = w.sum(axis=1) <= 0
    w[empty, 0], idx[empty, 0] = 1.0, 0
    width = 4 if np.count_nonzero(w, axis=1).max(initial=0) <= 4 else 8
    idx, w = _pad(idx, width), _pad(w, width)
    w32 = (w / w.sum(axis=1, keepdims=True)).astype(np.float32)
    # Put the float32 rounding residue on the largest weight: sums are 1 to about 1 ulp.
    w32[:, 0] = np.float32(1.0) - w32[:, 1:].sum(axis=1, dtype=np.float32)
    idx[w32 == 0] = 0
    return idx.astype(np.uint8 if joint_count <= 256 else np.uint16), w32


def _merge_duplicates(idx: np.ndarray, w: np.ndarray) -> None:
    """Sum the weights of a joint listed twice for one vertex into its first slot (in place)."""
    for a in range(idx.shape[1]):
        for b in range(a + 1, idx.shape[1]):
            same = (idx[:, a] == idx[:, b]) & (w[:, b] > 0)
            w[same, a] += w[same, b]
            w[same, b] = 0.0


def _pad(x: np.ndarray, width: int) -> np.ndarray:
    """(N, k) -> (N, width), zero-filled or truncated."""
    out = np.zeros((x.shape[0], width), dtype=x.dtype)
    out[:, : min(width, x.shape[1])] = x[:, :width]
    return out

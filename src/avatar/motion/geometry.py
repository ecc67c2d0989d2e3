"""Small helpers on arrays of 3-vectors, 3x3 matrices and skeleton trees (batch dims lead).

Per-frame work uses quaternions (``avatar.rig.quaternion``); the 3x3 helpers here serve
frame-independent set-up (rest alignment).
"""

from __future__ import annotations

import numpy as np

from avatar.rig import quaternion
from avatar.rig.kinematics import levels
from avatar.rig.skeleton import Skeleton


def unit(v: np.ndarray) -> np.ndarray:
    """(..., 3) vectors scaled to length 1 (zero vectors stay zero)."""
    n = np.sqrt(np.einsum("...i,...i->...", v, v))[..., None]  # einsum: no temporaries
    return v / np.maximum(n, 1e-12)


def angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(...,) angle in degrees between (..., 3) vectors (robust near 0 and 180)."""
    a, b = np.broadcast_arrays(np.asarray(a), np.asarray(b))
    ax, ay, az, bx, by, bz = a[..., 0], a[..., 1], a[..., 2], b[..., 0], b[..., 1], b[..., 2]
    # atan2(|a x b|, a . b) needs no normalisation
    cross = np.sqrt((ay * bz - az * by) ** 2 + (az * bx - ax * bz) ** 2 + (ax * by - ay * bx) ** 2)
    return np.degrees(np.arctan2(cross, ax * bx + ay * by + az * bz + 0.0))  # no -0.0: 0 deg


def swing(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(..., 3, 3) shortest-arc rotations taking directions a to b (both (..., 3))."""
    a, b = np.broadcast_arrays(unit(a), unit(b))
    axis = np.cross(a, b)
    s = np.linalg.norm(axis, axis=-1)
    c = np.sum(a * b, axis=-1)
    # Opposite vectors: any perpendicular axis will do; pick one away from a.
    other = np.where(np.abs(a[..., :1]) < 0.9, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    flip = unit(np.cross(a, other))
    axis = np.where((s < 1e-9)[..., None] & (c < 0)[..., None], flip, unit(axis))
    theta = np.arctan2(s, c)
    return axis_angle(axis, theta)


def axis_angle(axis: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """(..., 3) unit axes and (...,) radians -> (..., 3, 3) rotations (Rodrigues)."""
    k = np.zeros(axis.shape[:-1] + (3, 3))
    k[..., 0, 1], k[..., 0, 2] = -axis[..., 2], axis[..., 1]
    k[..., 1, 0], k[..., 1, 2] = axis[..., 2], -axis[..., 0]
    k[..., 2, 0], k[..., 2, 1] = -axis[..., 1], axis[..., 0]
    s, c = np.sin(theta)[..., None, None], np.cos(theta)[..., None, None]
    return np.eye(3) + s * k + (1 - c) * (k @ k)


def frame(primary: np.ndarray, secondary: np.ndarray) -> np.ndarray:
    """(..., 3, 3) orthonormal frames, columns (x, y, z): y along ``primary``, x toward
    ``secondary`` (made perpendicular), z = x cross y."""
    y = unit(primary)
    x = unit(secondary - np.sum(secondary * y, axis=-1, keepdims=True) * y)
    return np.stack([x, y, np.cross(x, y)], axis=-1)


def offsets(skeleton: Skeleton) -> np.ndarray:
    """(J, 3) each bone's head in its parent's rest frame (roots: zero)."""
    out = np.zeros((len(skeleton.names), 3))
    has = skeleton.parents >= 0
    p = skeleton.parents[has]
    delta = skeleton.heads[has] - skeleton.heads[p]
    out[has] = np.einsum("jba,jb->ja", skeleton.rest[p, :3, :3], delta)
    return out


def positions(skeleton: Skeleton, world: np.ndarray, roots: dict[int, np.ndarray],
              bones: np.ndarray | None = None) -> np.ndarray:  # fmt: skip
    """(J, T, 3) bone heads (float64) from world bone rotations (J, T, 4) (bone axis first).

    roots: bone index -> (T, 3) head positions of bones placed directly (translated bones);
    other parentless bones stay at their rest heads.
    bones: (J,) bool of the bones to evaluate (closed under parents); rows of the others
    are left undefined (no memory touched) and marked NaN in frame 0.
    """
    off = offsets(skeleton)
    parents = skeleton.parents
    out = np.empty(world.shape[:-1] + (3,))  # float64: leg IK solves triangles from these
    out[:, 0] = np.nan
    for group in levels(parents, bones):
        p = parents[group]
        if p[0] < 0:
            out[group] = skeleton.heads[group, None]
        else:
            out[group] = out[p] + quaternion.rotate(world[p], off[group, None])
        for j in group:
            if int(j) in roots:
                out[j] = roots[int(j)]
    return out


def ancestors(skeleton: Skeleton, bones) -> np.ndarray:
    """(J,) bool: the given bones (negative ones ignored) and all their ancestors."""
    out = np.zeros(len(skeleton.names), dtype=bool)
    for j in bones:
        while j >= 0 and not out[j]:
            out[j] = True
            j = int(skeleton.parents[j])
    return out


def path(skeleton: Skeleton, top: int, bottom: int) -> list[int]:
    """Bones from ``top`` down to ``bottom`` (inclusive); [] when not an ancestor."""
    out = [bottom]
    while out[-1] != top:
        parent = int(skeleton.parents[out[-1]])
        if parent < 0:
            return []
        out.append(parent)
    return out[::-1]

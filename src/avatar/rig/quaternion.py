"""Quaternion maths on arrays, (w, x, y, z), batch dimensions leading.

Results keep their inputs' precision (float32 stays float32; anything else is float64).
"""

from __future__ import annotations

import numpy as np


def multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product a * b, shapes (..., 4) (broadcast)."""
    aw, ax, ay, az = a[..., 0], a[..., 1], a[..., 2], a[..., 3]
    bw, bx, by, bz = b[..., 0], b[..., 1], b[..., 2], b[..., 3]
    # Written component by component into one buffer: for the (T, J, 4) stacks of motion
    # work this is several times faster than a stack of 4x4 or 3x3 matrix products.
    out = np.empty(np.broadcast_shapes(a.shape, b.shape), np.result_type(a, b, np.float32))
    out[..., 0] = aw * bw - ax * bx - ay * by - az * bz
    out[..., 1] = aw * bx + ax * bw + ay * bz - az * by
    out[..., 2] = aw * by - ax * bz + ay * bw + az * bx
    out[..., 3] = aw * bz + ax * by - ay * bx + az * bw
    return out


def right_matrix(b: np.ndarray) -> np.ndarray:
    """(..., 4) -> (..., 4, 4) M with a * b == a @ M for any row quaternions a.

    Multiplying many quaternions by one (a bone's fixed rest or alignment rotation) is then
    one matrix product, several times faster than the component formula.
    """
    w, x, y, z = b[..., 0], b[..., 1], b[..., 2], b[..., 3]
    rows = [(w, x, y, z), (-x, w, -z, y), (-y, z, w, -x), (-z, -y, x, w)]
    return np.stack([np.stack(r, axis=-1) for r in rows], axis=-2)


def left_matrix(a: np.ndarray) -> np.ndarray:
    """(..., 4) -> (..., 4, 4) M with a * b == b @ M for any row quaternions b."""
    w, x, y, z = a[..., 0], a[..., 1], a[..., 2], a[..., 3]
    rows = [(w, x, y, z), (-x, w, z, -y), (-y, -z, w, x), (-z, y, -x, w)]
    return np.stack([np.stack(r, axis=-1) for r in rows], axis=-2)


def rotate(q: np.ndarray, v: np.ndarray, inverse: bool = False) -> np.ndarray:
    """Vectors v (..., 3) turned by unit quaternions q (..., 4) (broadcast) -> (..., 3);
    ``inverse``: turned by the conjugates instead."""
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    vx, vy, vz = v[..., 0], v[..., 1], v[..., 2]
    # v' = v + w t + u x t with t = 2 u x v (u = the vector part); the inverse negates w.
    tx = y * vz
    tx -= z * vy
    tx *= 2.0
    ty = z * vx
    ty -= x * vz
    ty *= 2.0
    tz = x * vy
    tz -= y * vx
    tz *= 2.0
    out = np.empty(
        np.broadcast_shapes(q.shape[:-1], v.shape[:-1]) + (3,), np.result_type(q, v, np.float32)
    )
    for k, (t, a, b, c, d) in enumerate(((tx, vx, y, tz, z * ty), (ty, vy, z, tx, x * tz),
                                         (tz, vz, x, ty, y * tx))):  # fmt: skip
        o = w * t
        if inverse:
            o = np.negative(o, out=o)
        o += a
        o += b * c
        o -= d
        out[..., k] = o
    return out


def between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(..., 4) shortest-arc rotations taking the directions of a to those of b (..., 3).

    Opposite directions turn by half a turn about an axis perpendicular to a; a zero
    vector gives the identity.
    """
    a, b = np.broadcast_arrays(np.asarray(a), np.asarray(b))
    ax, ay, az, bx, by, bz = a[..., 0], a[..., 1], a[..., 2], b[..., 0], b[..., 1], b[..., 2]
    na = np.sqrt(ax * ax + ay * ay + az * az)
    ab = na * np.sqrt(bx * bx + by * by + bz * bz)
    q = np.empty(a.shape[:-1] + (4,), np.result_type(a, b, np.float32))
    q[..., 0] = ab + ax * bx + ay * by + az * bz  # |a||b| (1 + cos): half-angle form, no trig
    q[..., 1] = ay * bz - az * by
    q[..., 2] = az * bx - ax * bz
    q[..., 3] = ax * by - ay * bx
    n = np.sqrt(np.einsum("...i,...i->...", q, q))
    q /= np.where(n > 0, n, 1.0)[..., None]
    opposite = n <= 1e-9 * ab
    if np.any(opposite) or np.any(ab == 0):
        other = np.where((np.abs(ax) < 0.9 * na)[..., None], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
        axis = np.cross(a, other)
        axis /= np.maximum(np.linalg.norm(axis, axis=-1, keepdims=True), 1e-300)
        flip = np.concatenate([np.zeros(a.shape[:-1] + (1,)), axis], -1)
        q = np.where((opposite & (ab > 0))[..., None], flip, q)
        q = np.where((ab == 0)[..., None], [1.0, 0.0, 0.0, 0.0], q)
    return q


def conjugate(q: np.ndarray) -> np.ndarray:
    """Inverse of a unit quaternion, (..., 4)."""
    return q * np.array([1.0, -1.0, -1.0, -1.0], dtype=np.result_type(q, np.float32))


def to_matrix(q: np.ndarray) -> np.ndarray:
    """(..., 4) unit quaternions -> (..., 3, 3) rotation matrices."""
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack(
        [
            1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
            2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
            2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y),
        ],
        axis=-1,
    ).reshape(q.shape[:-1] + (3, 3))  # fmt: skip


def from_matrix(m: np.ndarray) -> np.ndarray:
    """(..., 3, 3) rotation matrices -> (..., 4) unit quaternions with w >= 0."""
    m = np.asarray(m, dtype=np.float64)
    m00, m11, m22 = m[..., 0, 0], m[..., 1, 1], m[..., 2, 2]
    # Four candidate solutions; pick, per matrix, the one with the largest pivot (stable).
    cands = np.stack(
        [
            np.stack([1 + m00 + m11 + m22, m[..., 2, 1] - m[..., 1, 2],
                      m[..., 0, 2] - m[..., 2, 0], m[..., 1, 0] - m[..., 0, 1]], -1),
            np.stack([m[..., 2, 1] - m[..., 1, 2], 1 + m00 - m11 - m22,
                      m[..., 0, 1] + m[..., 1, 0], m[..., 0, 2] + m[..., 2, 0]], -1),
            np.stack([m[..., 0, 2] - m[..., 2, 0], m[..., 0, 1] + m[..., 1, 0],
                      1 - m00 + m11 - m22, m[..., 1, 2] + m[..., 2, 1]], -1),
            np.stack([m[..., 1, 0] - m[..., 0, 1], m[..., 0, 2] + m[..., 2, 0],
                      m[..., 1, 2] + m[..., 2, 1], 1 - m00 - m11 + m22], -1),
        ],
        axis=-2,
    )  # fmt: skip
    pivot = np.stack([1 + m00 + m11 + m22, 1 + m00 - m11 - m22, 1 - m00 + m11 - m22,
                      1 - m00 - m11 + m22], -1)  # fmt: skip
    best = np.argmax(pivot, axis=-1)
    q = np.take_along_axis(cands, best[..., None, None], axis=-2)[..., 0, :]
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return np.where(q[..., :1] < 0, -q, q)


def from_axis_angle(axis: np.ndarray, angle: np.ndarray | float) -> np.ndarray:
    """Rotation of ``angle`` radians (...,) about unit ``axis`` (..., 3) -> (..., 4)."""
    axis = np.asarray(axis, dtype=np.float64)
    half = 0.5 * np.asarray(angle, dtype=np.float64)[..., None]
    axis = axis / np.maximum(np.linalg.norm(axis, axis=-1, keepdims=True), 1e-300)
    return np.concatenate([np.cos(half), np.sin(half) * axis], axis=-1)


_AXIS = {"X": 0, "Y": 1, "Z": 2}


def from_euler(angles: np.ndarray, order: str = "XYZ") -> np.ndarray:
    """Euler angles (..., 3) in radians -> quaternions (..., 4).

    ``order`` is Blender's/BVH's: "XYZ" means rotate about X first, then Y, then Z in a
    fixed frame (R = Rz @ Ry @ Rx); ``angles[..., i]`` is the angle about ``order[i]``.
    """
    angles = np.asarray(angles, dtype=np.float64)
    q = None
    for i, letter in enumerate(order.upper()):
        axis = np.zeros(3)
        axis[_AXIS[letter]] = 1.0
        qi = from_axis_angle(np.broadcast_to(axis, angles.shape), angles[..., i])
        q = qi if q is None else multiply(qi, q)
    assert q is not None
    return q


def to_euler(q: np.ndarray, order: str = "XYZ") -> np.ndarray:
    """Quaternions (..., 4) -> Euler angles (..., 3) for the convention of ``from_euler``."""
    m = to_matrix(q)
    i, j, k = (_AXIS[c] for c in order.upper())
    # R = R_k R_j R_i; sign of the permutation decides the formula's signs.
    sign = 1.0 if (i, j, k) in ((0, 1, 2), (1, 2, 0), (2, 0, 1)) else -1.0
    sj = np.clip(-sign * m[..., k, i], -1.0, 1.0)
    a_j = np.arcsin(sj)
    a_i = np.arctan2(sign * m[..., k, j], m[..., k, k])
    a_k = np.arctan2(sign * m[..., j, i], m[..., i, i])
    gimbal = np.abs(sj) > 1 - 1e-9
    if np.any(gimbal):
        a_i = np.where(gimbal, 0.0, a_i)
        a_k = np.where(gimbal, np.arctan2(-sign * m[..., i, j], m[..., j, j]), a_k)
    out = np.empty(q.shape[:-1] + (3,))
    out[..., 0], out[..., 1], out[..., 2] = a_i, a_j, a_k
    return out


def slerp(a: np.ndarray, b: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Spherical interpolation between unit quaternions (..., 4) at t (...,)."""
    t = np.asarray(t, dtype=np.result_type(a, b, np.float32))[..., None]
    dot = np.sum(a * b, axis=-1, keepdims=True)
    b = np.where(dot < 0, -b, b)
    dot = np.abs(dot)
    theta = np.arccos(np.clip(dot, -1.0, 1.0))
    small = theta < 1e-6
    s = np.sin(np.where(small, 1.0, theta))
    wa = np.where(small, 1 - t, np.sin((1 - t) * theta) / s)
    wb = np.where(small, t, np.sin(t * theta) / s)
    out = wa * a + wb * b
    return out / np.linalg.norm(out, axis=-1, keepdims=True)

"""Small rotation-matrix helpers for the per-frame solver (3x3, float64).

One frame's solve works on a few dozen single bones; at that size 3x3 matrix products are
cheaper than quaternion arrays, so the solver keeps matrices and converts once at the end.
"""

from __future__ import annotations

import math

import numpy as np

EYE = np.eye(3)


def unit(v: np.ndarray) -> np.ndarray:
    n = math.sqrt(float(v @ v))
    return v / n if n > 1e-12 else v


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b for two 3-vectors (numpy's ``cross`` costs ten times more at this size)."""
    a0, a1, a2 = a.tolist()
    b0, b1, b2 = b.tolist()
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    """(3, 3) rotation of ``angle`` radians about unit ``axis`` (Rodrigues)."""
    x, y, z = (float(v) for v in axis)
    s, c = math.sin(angle), math.cos(angle)
    t = 1.0 - c
    return np.array([[c + t * x * x, t * x * y - s * z, t * x * z + s * y],
                     [t * x * y + s * z, c + t * y * y, t * y * z - s * x],
                     [t * x * z - s * y, t * y * z + s * x, c + t * z * z]])  # fmt: skip


def between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(3, 3) shortest-arc rotation taking direction a to direction b (3,)."""
    a, b = unit(a), unit(b)
    c = cross(a, b)
    s = math.sqrt(float(c @ c))
    d = float(a @ b)
    if s < 1e-9:
        if d > 0:
            return EYE.copy()
        other = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        return axis_angle(unit(cross(a, other)), math.pi)
    return axis_angle(c / s, math.atan2(s, d))


def angle_of(r: np.ndarray) -> float:
    """Rotation angle of a (3, 3) rotation, radians in [0, pi]."""
    c = (float(r[0, 0]) + float(r[1, 1]) + float(r[2, 2]) - 1.0) * 0.5
    return math.acos(min(max(c, -1.0), 1.0))


def log(r: np.ndarray) -> tuple[np.ndarray, float]:
    """(axis (3,), angle) of a rotation matrix."""
    angle = angle_of(r)
    if angle < 1e-9:
        return np.array([1.0, 0.0, 0.0]), 0.0
    if angle > np.pi - 1e-6:  # axis from the symmetric part
        m = (r + EYE) * 0.5
        axis = unit(m[int(np.argmax(np.diag(m)))])
        return axis, angle
    axis = np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
    return axis / (2.0 * math.sin(angle)), angle


def power(r: np.ndarray, f: float) -> np.ndarray:
    """r to the power f (the same axis, f times the angle): slerp from identity."""
    axis, angle = log(r)
    return axis_angle(axis, angle * f) if angle else EYE.copy()


def kabsch(a: np.ndarray, b: np.ndarray, w: np.ndarray) -> np.ndarray | None:
    """(3, 3) rotation R minimising sum w_i |R a_i - b_i|^2 (vectors about a fixed centre),
    or None when the points do not fix a rotation (fewer than two independent directions)."""
    h = (a * w[:, None]).T @ b
    u, s, vt = np.linalg.svd(h)
    if s[1] < 1e-9 * max(s[0], 1e-300):
        return None
    r = vt.T @ u.T
    if det3(r) < 0:  # a reflection: flip the least significant axis
        vt[2] = -vt[2]
        r = vt.T @ u.T
    return r


def det3(m: np.ndarray) -> float:
    """Determinant of a (3, 3) matrix (plain floats: a tenth of ``np.linalg.det``'s cost)."""
    (a, b, c), (d, e, f), (g, h, i) = m.tolist()
    return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)


def clamp(r: np.ndarray, max_angle: float) -> np.ndarray:
    """r turned back towards the identity so its angle is at most ``max_angle`` radians."""
    angle = angle_of(r)
    if angle <= max_angle:
        return r
    axis, angle = log(r)
    return axis_angle(axis, max_angle)


# -- batched forms: (n, 3, 3) stacks, a fixed handful of numpy calls per stack --------------
# One frame solves every limb bone of a level (both arms and legs) in one call of these,
# which is what keeps a frame under a millisecond: numpy's per-call cost, not arithmetic,
# dominates at 3x3.

# (3, 9): a @ _SKEW gives the flattened cross-product matrix [a]x of each row of a.
_SKEW = np.zeros((3, 9))
for _k, (_i, _j, _s) in enumerate(((2, 1, 1.0), (1, 2, -1.0), (0, 2, 1.0), (2, 0, -1.0),
                                   (1, 0, 1.0), (0, 1, -1.0))):  # fmt: skip
    _SKEW[[0, 0, 1, 1, 2, 2][_k], _i * 3 + _j] = _s
_NEXT, _AFTER = [1, 2, 0], [2, 0, 1]


def cross_many(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(n, 3) row-wise a x b (cheaper than ``np.cross`` for small n)."""
    return a[:, _NEXT] * b[:, _AFTER] - a[:, _AFTER] * b[:, _NEXT]


def turns_about(axis: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """(n, 3, 3) rotations about one unit ``axis`` (3,) by ``angles`` (n,) radians."""
    c, s = np.cos(angles)[:, None, None], np.sin(angles)[:, None, None]
    skew = (axis @ _SKEW).reshape(3, 3)
    outer = axis[:, None] * axis[None, :]
    return c * (EYE - outer) + s * skew + outer


def axis_angle_many(axes: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """(n, 3, 3) rotations of ``angles`` (n,) radians about unit ``axes`` (n, 3)
    (Rodrigues: c I + s [a]x + (1 - c) a a^T; an angle of 0 gives the identity exactly)."""
    c, s = np.cos(angles)[:, None, None], np.sin(angles)[:, None, None]
    skew = (axes @ _SKEW).reshape(-1, 3, 3)
    return c * EYE + s * skew + (1.0 - c) * (axes[:, :, None] * axes[:, None, :])


def angle_many(r: np.ndarray) -> np.ndarray:
    """(n,) rotation angles of (n, 3, 3) rotations, radians in [0, pi]."""
    c = (r[:, 0, 0] + r[:, 1, 1] + r[:, 2, 2] - 1.0) * 0.5
    return np.arccos(np.clip(c, -1.0, 1.0))


def log_many(r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(axes (n, 3), angles (n,)) of (n, 3, 3) rotations, as ``log`` row by row."""
    angles = angle_many(r)
    vee = np.stack([r[:, 2, 1] - r[:, 1, 2], r[:, 0, 2] - r[:, 2, 0], r[:, 1, 0] - r[:, 0, 1]], 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        axes = vee / (2.0 * np.sin(angles))[:, None]
    odd = (angles < 1e-9) | (angles > np.pi - 1e-6)
    for i in np.flatnonzero(odd):  # identity or a half turn: rare, the scalar form
        axes[i], angles[i] = log(r[i])
    return axes, angles


def power_many(r: np.ndarray, f: float | np.ndarray) -> np.ndarray:
    """(n, 3, 3): each rotation to the power f (scalar or (n,)), as ``power``."""
    axes, angles = log_many(r)
    return axis_angle_many(axes, angles * f)


def between_many(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(n, 3, 3) shortest-arc rotations taking directions a (n, 3) to b (n, 3), as
    ``between`` row by row."""
    na = np.sqrt((a * a).sum(1))[:, None]
    nb = np.sqrt((b * b).sum(1))[:, None]
    a = np.where(na > 1e-12, a / np.where(na > 1e-12, na, 1.0), a)
    b = np.where(nb > 1e-12, b / np.where(nb > 1e-12, nb, 1.0), b)
    c = cross_many(a, b)
    s = np.sqrt((c * c).sum(1))
    d = (a * b).sum(1)
    flat = s < 1e-9
    axes = c / np.where(flat, 1.0, s)[:, None]
    out = axis_angle_many(axes, np.where(flat, 0.0, np.arctan2(s, d)))
    for i in np.flatnonzero(flat & (d <= 0)):  # opposite directions: rare, the scalar form
        out[i] = between(a[i], b[i])
    return out


def kabsch_many(a: np.ndarray, b: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``kabsch`` for n point sets at once: a, b (n, m, 3), w (n, m) (zero weights pad sets
    of fewer points). Returns rotations (n, 3, 3) and (n,) bool: False where the points do
    not fix a rotation (that row's matrix is then meaningless)."""
    h = (a * w[:, :, None]).transpose(0, 2, 1) @ b
    u, s, vt = np.linalg.svd(h)
    ok = s[:, 1] >= 1e-9 * np.maximum(s[:, 0], 1e-300)
    v = vt.transpose(0, 2, 1)
    ut = u.transpose(0, 2, 1)
    d = np.sign(np.linalg.det(v @ ut))
    d[d == 0] = 1.0
    v[:, :, 2] *= d[:, None]
    return v @ ut, ok


# Matrix -> quaternion in one product: the four candidate quaternions of Shepperd's method
# are linear in the matrix entries (plus a constant); candidate i's component i is its
# pivot, and the largest pivot is the stable choice.
_QUAT_MAP = np.zeros((9, 16))
_QUAT_ONE = np.zeros(16)
for _row, _terms in enumerate((
        ((1, 1, 1, 1), (7, -5), (2, -6), (3, -1)),
        ((7, -5), (1, 1, -1, -1), (1, 3), (2, 6)),
        ((2, -6), (1, 3), (1, -1, 1, -1), (5, 7)),
        ((3, -1), (2, 6), (5, 7), (1, -1, -1, 1)))):  # fmt: skip
    for _col, _t in enumerate(_terms):
        if len(_t) == 4:  # 1 +- m00 +- m11 +- m22: (1, sign, sign, sign)
            _QUAT_ONE[_row * 4 + _col] = 1.0
            for _sign, _entry in zip(_t[1:], (0, 4, 8), strict=True):
                _QUAT_MAP[_entry, _row * 4 + _col] = _sign
        else:  # m[a] + m[b] or m[a] - m[b] (entries flattened row-major)
            _QUAT_MAP[_t[0], _row * 4 + _col] = 1.0
            _QUAT_MAP[abs(_t[1]), _row * 4 + _col] = 1.0 if _t[1] > 0 else -1.0


def quaternions(r: np.ndarray) -> np.ndarray:
    """(n, 3, 3) rotations -> (n, 4) unit quaternions (w, x, y, z) with w >= 0
    (``avatar.rig.quaternion.from_matrix``, in a few calls)."""
    n = len(r)
    cands = (r.reshape(n, 9) @ _QUAT_MAP + _QUAT_ONE).reshape(n, 4, 4)
    best = np.argmax(cands[:, [0, 1, 2, 3], [0, 1, 2, 3]], axis=1)
    q = cands[np.arange(n), best]
    q /= np.sqrt((q * q).sum(1))[:, None]
    return np.where(q[:, :1] < 0, -q, q)

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
    d = np.sign(np.linalg.det(vt.T @ u.T)) or 1.0
    return vt.T @ np.diag([1.0, 1.0, d]) @ u.T


def clamp(r: np.ndarray, max_angle: float) -> np.ndarray:
    """r turned back towards the identity so its angle is at most ``max_angle`` radians."""
    angle = angle_of(r)
    if angle <= max_angle:
        return r
    axis, angle = log(r)
    return axis_angle(axis, max_angle)

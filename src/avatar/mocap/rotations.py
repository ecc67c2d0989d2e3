"""Rotation helpers for the per-frame solver, on plain floats.

A frame's solve turns a couple of dozen bones one after another, each a handful of 3x3
products: at that size a numpy call's fixed cost (~1 us) dwarfs its arithmetic, so the solver
keeps its matrices as row-major 9-tuples and its vectors as 3-tuples of Python floats
(``M`` and ``V`` below) and goes to numpy only where a call does real work: the SVD of a
rigid fit and the final matrix -> quaternion conversion of all bones at once.

Conventions: ``M`` (m00, m01, m02, m10, ..., m22); rotations act on column vectors
(``apply(m, v)`` is ``m @ v``); angles in radians.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Sequence

import numpy as np

M = tuple[float, float, float, float, float, float, float, float, float]
V = tuple[float, float, float]

EYE: M = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
ZERO: V = (0.0, 0.0, 0.0)

# The SVD gufunc behind ``np.linalg.svd``: the same LAPACK call, without the wrapper's
# argument checks and error-state context (half the cost of a 3x3 SVD). numpy 2 names it
# ``svd_f``, 1.x ``svd_m_f``; anything else falls back to the public function.
try:
    _LINALG = importlib.import_module("numpy.linalg._umath_linalg")
    _SVD = getattr(_LINALG, "svd_f", None) or getattr(_LINALG, "svd_m_f", None)
except ImportError:  # pragma: no cover - a numpy without the private module
    _SVD = None


def svd3(h: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(u, s, vt) of a (3, 3) float64 matrix, as ``np.linalg.svd``."""
    if _SVD is None:
        return np.linalg.svd(h)
    return _SVD(h, signature="d->ddd")


def mul(a: Sequence[float], b: Sequence[float]) -> M:
    """a @ b."""
    a0, a1, a2, a3, a4, a5, a6, a7, a8 = a
    b0, b1, b2, b3, b4, b5, b6, b7, b8 = b
    return (a0 * b0 + a1 * b3 + a2 * b6, a0 * b1 + a1 * b4 + a2 * b7, a0 * b2 + a1 * b5 + a2 * b8,
            a3 * b0 + a4 * b3 + a5 * b6, a3 * b1 + a4 * b4 + a5 * b7, a3 * b2 + a4 * b5 + a5 * b8,
            a6 * b0 + a7 * b3 + a8 * b6, a6 * b1 + a7 * b4 + a8 * b7,
            a6 * b2 + a7 * b5 + a8 * b8)  # fmt: skip


def tmul(a: Sequence[float], b: Sequence[float]) -> M:
    """a.T @ b."""
    a0, a1, a2, a3, a4, a5, a6, a7, a8 = a
    b0, b1, b2, b3, b4, b5, b6, b7, b8 = b
    return (a0 * b0 + a3 * b3 + a6 * b6, a0 * b1 + a3 * b4 + a6 * b7, a0 * b2 + a3 * b5 + a6 * b8,
            a1 * b0 + a4 * b3 + a7 * b6, a1 * b1 + a4 * b4 + a7 * b7, a1 * b2 + a4 * b5 + a7 * b8,
            a2 * b0 + a5 * b3 + a8 * b6, a2 * b1 + a5 * b4 + a8 * b7,
            a2 * b2 + a5 * b5 + a8 * b8)  # fmt: skip


def apply(m: Sequence[float], v: Sequence[float]) -> V:
    """m @ v."""
    x, y, z = v
    return (m[0] * x + m[1] * y + m[2] * z, m[3] * x + m[4] * y + m[5] * z,
            m[6] * x + m[7] * y + m[8] * z)  # fmt: skip


def tapply(m: Sequence[float], v: Sequence[float]) -> V:
    """m.T @ v."""
    x, y, z = v
    return (m[0] * x + m[3] * y + m[6] * z, m[1] * x + m[4] * y + m[7] * z,
            m[2] * x + m[5] * y + m[8] * z)  # fmt: skip


def add(a: Sequence[float], b: Sequence[float]) -> V:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def sub(a: Sequence[float], b: Sequence[float]) -> V:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def dot(a: Sequence[float], b: Sequence[float]) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a: Sequence[float], b: Sequence[float]) -> V:
    a0, a1, a2 = a
    b0, b1, b2 = b
    return (a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0)


def unit(v: Sequence[float]) -> V:
    """v / |v|, or v itself when shorter than 1e-12."""
    x, y, z = v
    n = math.sqrt(x * x + y * y + z * z)
    return (x / n, y / n, z / n) if n > 1e-12 else (x, y, z)


def weighted_sum(vectors: Sequence[Sequence[float]], weights: Sequence[float]) -> V:
    """sum_i w_i v_i of 3-vectors."""
    x = y = z = 0.0
    for (a, b, c), w in zip(vectors, weights, strict=True):
        x += w * a
        y += w * b
        z += w * c
    return (x, y, z)


def turn(axis: Sequence[float], angle: float) -> M:
    """Rotation of ``angle`` about unit ``axis`` (Rodrigues: c I + s [a]x + (1 - c) a a^T;
    an angle of 0 gives the identity exactly)."""
    x, y, z = axis
    s, c = math.sin(angle), math.cos(angle)
    t = 1.0 - c
    return (c + t * x * x, t * x * y - s * z, t * x * z + s * y,
            t * x * y + s * z, c + t * y * y, t * y * z - s * x,
            t * x * z - s * y, t * y * z + s * x, c + t * z * z)  # fmt: skip


def rotate(axis: Sequence[float], c: float, s: float, v: Sequence[float]) -> V:
    """v turned about unit ``axis`` by the angle of cosine c and sine s (Rodrigues on a
    vector: ``turn(axis, angle) @ v`` without the matrix)."""
    x, y, z = axis
    vx, vy, vz = v
    k = (1.0 - c) * (x * vx + y * vy + z * vz)
    return (c * vx + s * (y * vz - z * vy) + k * x, c * vy + s * (z * vx - x * vz) + k * y,
            c * vz + s * (x * vy - y * vx) + k * z)  # fmt: skip


def arc(a: Sequence[float], b: Sequence[float]) -> M:
    """Shortest-arc rotation taking direction a to direction b (either of length 0 or the
    two opposite: a half turn about an axis across a)."""
    a, b = unit(a), unit(b)
    c = cross(a, b)
    s = math.sqrt(dot(c, c))
    d = dot(a, b)
    if s < 1e-9:
        if d > 0:
            return EYE
        other = (1.0, 0.0, 0.0) if abs(a[0]) < 0.9 else (0.0, 1.0, 0.0)
        return turn(unit(cross(a, other)), math.pi)
    return turn((c[0] / s, c[1] / s, c[2] / s), math.atan2(s, d))


def angle(r: Sequence[float]) -> float:
    """Rotation angle of r, in [0, pi]."""
    c = (r[0] + r[4] + r[8] - 1.0) * 0.5
    return math.acos(min(max(c, -1.0), 1.0))


def log(r: Sequence[float]) -> tuple[V, float]:
    """(unit axis, angle) of a rotation; (x axis, 0) for the identity."""
    a = angle(r)
    if a < 1e-9:
        return (1.0, 0.0, 0.0), 0.0
    if a > math.pi - 1e-6:  # near a half turn: the axis from the symmetric part
        diag = (r[0], r[4], r[8])
        i = diag.index(max(diag))
        row = [(r[3 * i + j] + (1.0 if i == j else 0.0)) * 0.5 for j in range(3)]
        return unit(row), a
    s = 2.0 * math.sin(a)
    return ((r[7] - r[5]) / s, (r[2] - r[6]) / s, (r[3] - r[1]) / s), a


def power(r: Sequence[float], f: float) -> M:
    """r to the power f: the same axis, f times the angle (a slerp from the identity)."""
    axis, a = log(r)
    return turn(axis, a * f) if a else EYE


def clamp(r: M, max_angle: float) -> M:
    """r turned back towards the identity so its angle is at most ``max_angle``."""
    if angle(r) <= max_angle:
        return r
    axis, _ = log(r)
    return turn(axis, max_angle)


def kabsch(a: Sequence[Sequence[float]], b: Sequence[Sequence[float]],
           w: Sequence[float]) -> M | None:  # fmt: skip
    """Rotation R minimising sum w_i |R a_i - b_i|^2 (vectors about a fixed centre), or None
    when the points do not fix one (fewer than two independent directions)."""
    h0 = h1 = h2 = h3 = h4 = h5 = h6 = h7 = h8 = 0.0  # H = sum w a b^T (locals: fast)
    for (a0, a1, a2), (b0, b1, b2), wi in zip(a, b, w, strict=True):
        a0, a1, a2 = a0 * wi, a1 * wi, a2 * wi
        h0 += a0 * b0
        h1 += a0 * b1
        h2 += a0 * b2
        h3 += a1 * b0
        h4 += a1 * b1
        h5 += a1 * b2
        h6 += a2 * b0
        h7 += a2 * b1
        h8 += a2 * b2
    u, s, vt = svd3(np.array(((h0, h1, h2), (h3, h4, h5), (h6, h7, h8))))
    s0, s1, _ = s.tolist()
    if not s1 >= 1e-9 * max(s0, 1e-300):  # (NaN from a non-finite input too)
        return None
    (r0, r3, r6), (r1, r4, r7), (r2, r5, r8) = (u @ vt).tolist()  # R = V U^T: its transpose
    r: M = (r0, r1, r2, r3, r4, r5, r6, r7, r8)
    if det(r) < 0:  # a reflection: flip the least significant axis (V's last column)
        v = vt.T.ravel().tolist()
        v[2], v[5], v[8] = -v[2], -v[5], -v[8]
        r = mul(v, u.T.ravel().tolist())
    return r


def det(m: Sequence[float]) -> float:
    a, b, c, d, e, f, g, h, i = m
    return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)


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
    """(n, 3, 3) or (n, 9) rotations -> (n, 4) unit quaternions (w, x, y, z) with w >= 0
    (``avatar.rig.quaternion.from_matrix``, in a few calls)."""
    n = len(r)
    flat = r.reshape(n, 9) @ _QUAT_MAP
    flat += _QUAT_ONE
    best = flat[:, ::5].argmax(axis=1)  # the pivots: entries 0, 5, 10, 15 of each 4x4
    q = flat.reshape(n, 4, 4)[np.arange(n), best]
    q *= (np.where(q[:, 0] < 0, -1.0, 1.0) / np.sqrt((q * q).sum(1)))[:, None]
    return q

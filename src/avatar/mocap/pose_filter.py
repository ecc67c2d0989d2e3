"""The One Euro filter on poses: bone rotations (quaternions) and root locations.

Streams that carry rotations (VMC, BVH over TCP) are smoothed on the rig, after the
conversion, with the parameters of ``filters.OneEuro`` (one smoothing strength in the UI:
``OneEuro.strength``). Per bone, with ``dt`` the step between samples::

    w      = angle(q, q_previous_raw) / dt         (rad/s, the bone's angular speed)
    speed  = reach * lowpass(w, d_cutoff)          (m/s of a point ``reach`` m from the joint)
    cutoff = min_cutoff + beta * speed             (Hz)
    q_hat  = normalise(q_hat + alpha(cutoff, dt) * (q - q_hat))   (q on q_hat's hemisphere)

``reach`` (0.5 m: about a forearm with its hand) turns an angular speed into the m/s the
keypoint filter's ``beta`` is defined in, so one strength means the same on every source.
Latency is ``OneEuro.lag(speed)``: with the defaults (strength 0.5) 106 ms on a still bone
(jitter only), 24 ms on a bone whose tip moves at 1 m/s. Root locations (``translations``)
go through ``filters.PointFilter`` (m/s directly). A gap longer than ``reset_after``
seconds restarts the filter from the next sample.
"""

from __future__ import annotations

import numpy as np

from avatar.mocap.filters import OneEuro, PointFilter, _alpha

REACH = 0.5  # metres from a joint at which a bone's angular speed is read as m/s


class RotationFilter:
    """One Euro state for J unit quaternions; ``__call__(q (J, 4) wxyz, t seconds) -> (J, 4)``."""

    def __init__(self, count: int, params: OneEuro | None = None, reach: float = REACH):
        self.params = params or OneEuro()
        self.reach = float(reach)
        self.count = count
        self.x: np.ndarray | None = None  # (J, 4) filtered
        self.raw = np.zeros((count, 4))  # (J, 4) the previous sample
        self.speed = np.zeros(count)  # (J,) low-passed angular speed, rad/s
        self.t = -np.inf

    def __call__(self, q: np.ndarray, t: float) -> np.ndarray:
        p = self.params
        q = np.asarray(q, dtype=np.float64)
        if not p.enabled:
            return q
        if self.x is None or t - self.t > p.reset_after:
            self.x, self.raw, self.speed, self.t = q.copy(), q.copy(), np.zeros(self.count), t
            return q.copy()
        dt = t - self.t
        if dt <= 0.0:  # no time passed (a repeated timestamp): nothing to blend over
            return self.x.copy()
        q = _same_hemisphere(q, self.x)
        cos = np.clip(np.abs(np.sum(q * self.raw, axis=1)), 0.0, 1.0)
        turn = 2.0 * np.arccos(cos) / dt
        self.speed += _alpha(p.d_cutoff, dt) * (turn - self.speed)
        a = _alpha(p.min_cutoff + p.beta * self.reach * self.speed, dt)[:, None]
        x = self.x + a * (q - self.x)
        self.x = x / np.linalg.norm(x, axis=1, keepdims=True)
        self.raw, self.t = q, t
        return self.x.copy()


class PoseFilter:
    """Rotations (J, 4) and translations (J, 3) of a rig's poses, filtered together."""

    def __init__(self, count: int, params: OneEuro | None = None, reach: float = REACH):
        self.params = params or OneEuro()
        self.rotations = RotationFilter(count, self.params, reach)
        self.translations = PointFilter(count, self.params)

    def __call__(self, rotations: np.ndarray, translations: np.ndarray,
                 t: float) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
        if not self.params.enabled:
            return rotations, translations
        return self.rotations(rotations, t), self.translations(np.asarray(translations), t)


def _same_hemisphere(q: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """q (J, 4) with each row's sign chosen so it lies within 90 degrees of ``ref``'s row
    (q and -q are one rotation; blending across hemispheres would pass through zero)."""
    return q * np.where(np.sum(q * ref, axis=1, keepdims=True) < 0.0, -1.0, 1.0)

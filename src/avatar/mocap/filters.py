"""The One Euro filter (Casiez, Roussel, Vogel, CHI 2012) on keypoint positions.

A first-order low-pass whose cutoff rises with speed: still joints are smoothed hard (no
jitter), fast ones barely (little lag). Per keypoint, with its speed ``v`` (m/s: the step
between raw samples, as MediaPipe's implementation takes it, low-passed at ``d_cutoff``)::

    cutoff = min_cutoff + beta * |v|          (Hz)
    tau    = 1 / (2 pi cutoff)                (s)
    alpha  = 1 / (1 + tau / dt)
    x_hat  = x_hat + alpha * (x - x_hat)

Latency: on a joint moving steadily at speed ``v`` the output trails the input by exactly
``tau(v) = 1 / (2 pi (min_cutoff + beta v))`` seconds (the steady-state lag of that
exponential average; ``lag()`` computes it and a test measures it). With the defaults
(1.5 Hz, 5 Hz per m/s): 106 ms for a still joint (jitter only), 24 ms at 1 m/s (a hand
waving), 10 ms at 3 m/s (a kick). MediaPipe's own graph smooths its landmarks with the
same filter; pass ``OneEuro.off()`` to the solver to take its output unfiltered.

Missing samples (NaN) leave a keypoint's state unchanged; after a gap longer than
``reset_after`` seconds it restarts from the next sample instead of sliding over.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class OneEuro:
    """Filter parameters: ``min_cutoff`` Hz, ``beta`` Hz per m/s, ``d_cutoff`` Hz;
    ``enabled`` False passes samples through."""

    min_cutoff: float = 1.5
    beta: float = 5.0
    d_cutoff: float = 1.0
    reset_after: float = 0.5
    enabled: bool = True

    @classmethod
    def off(cls) -> OneEuro:
        return cls(enabled=False)

    @classmethod
    def strength(cls, s: float) -> OneEuro:
        """Parameters from one smoothing strength in [0, 1] (a UI slider): 0 is off,
        0.5 the defaults, 1 holds still joints to a 0.3 Hz cutoff."""
        s = min(max(float(s), 0.0), 1.0)
        if s == 0.0:
            return cls.off()
        return cls(min_cutoff=1.5 * 5.0 ** (1.0 - 2.0 * s), beta=5.0 * 4.0 ** (1.0 - 2.0 * s))

    def lag(self, speed: float) -> float:
        """Steady-state latency in seconds for a joint moving at ``speed`` m/s."""
        if not self.enabled:
            return 0.0
        return 1.0 / (2.0 * math.pi * (self.min_cutoff + self.beta * abs(speed)))


def _alpha(cutoff: np.ndarray | float, dt: np.ndarray | float) -> np.ndarray:
    tau = 1.0 / (2.0 * np.pi * np.asarray(cutoff))
    return 1.0 / (1.0 + tau / dt)


class PointFilter:
    """One Euro state for K points in 3D; ``__call__(points (K, 3), t seconds) -> (K, 3)``."""

    def __init__(self, count: int, params: OneEuro | None = None):
        self.params = params or OneEuro()
        self.x = np.full((count, 3), np.nan)
        self.raw = np.full((count, 3), np.nan)
        self.dx = np.zeros((count, 3))
        self.t = np.full(count, -np.inf)
        # The time every point was last updated at, when all were (together) and all have a
        # state: then a frame with every point seen takes the short path below.
        self.together: float | None = None

    def __call__(self, points: np.ndarray, t: float) -> np.ndarray:
        p = self.params
        if not p.enabled:
            return points
        last = self.together
        if last is not None and 0.0 < t - last <= p.reset_after and np.isfinite(points).all():
            # The usual frame, as the masked path computes it for "every point seen and
            # moving on", with the shared time step as a Python float (fewer numpy calls).
            dt = t - last
            raw = (points - self.raw) / dt
            self.dx += (1.0 / (1.0 + (1.0 / (2.0 * np.pi * p.d_cutoff)) / dt)) * (raw - self.dx)
            speed = np.sqrt((self.dx * self.dx).sum(axis=1, keepdims=True))
            tau = 1.0 / (2.0 * np.pi * (p.min_cutoff + p.beta * speed))
            self.x += (1.0 / (1.0 + tau / dt)) * (points - self.x)
            self.raw[:] = points
            self.t.fill(t)
            self.together = t
            return self.x.copy()
        out = self._masked(points, t)
        self.together = t if (self.t == t).all() and np.isfinite(self.x).all() else None
        return out

    def _masked(self, points: np.ndarray, t: float) -> np.ndarray:
        p = self.params
        seen = np.isfinite(points).all(axis=1)
        fresh = seen & ((t - self.t > p.reset_after) | ~np.isfinite(self.x).all(axis=1))
        if fresh.any():
            self.x[fresh], self.dx[fresh], self.t[fresh] = points[fresh], 0.0, t
            self.raw[fresh] = points[fresh]
        go = seen & ~fresh & (t > self.t)
        if go.all():  # the usual frame: every point seen and moving on; no masks needed
            dt = (t - self.t)[:, None]
            raw = (points - self.raw) / dt
            self.dx += _alpha(p.d_cutoff, dt) * (raw - self.dx)
            speed = np.linalg.norm(self.dx, axis=1, keepdims=True)
            self.x += _alpha(p.min_cutoff + p.beta * speed, dt) * (points - self.x)
            self.raw[:] = points
            self.t[:] = t
            return self.x.copy()
        if np.any(go):
            dt = (t - self.t[go])[:, None]
            raw = (points[go] - self.raw[go]) / dt
            self.dx[go] += _alpha(p.d_cutoff, dt) * (raw - self.dx[go])
            speed = np.linalg.norm(self.dx[go], axis=1, keepdims=True)
            a = _alpha(p.min_cutoff + p.beta * speed, dt)
            self.x[go] += a * (points[go] - self.x[go])
            self.raw[go] = points[go]
            self.t[go] = t
        out = np.where(seen[:, None], self.x, np.nan)
        return out

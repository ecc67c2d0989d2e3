"""Planted feet for the streaming solver: contact detection and two-bone leg IK.

A foot is in contact while its ankle is within ``height`` of the lowest ankle level seen
(the floor) and moves slower than ``speed`` m/s (measured on the ankle path smoothed with
a 0.1 s time constant, so an estimator's jitter does not read as motion). At contact
start the ankle's position is pinned; while the contact lasts the leg is bent (thigh and
shin, the foot keeping its world rotation) so the ankle stays on the pin; at release the
correction fades with time constant ``release`` seconds instead of snapping. A pin the
ankle has left by more than ``reach`` metres is dropped and set again (a slow slide is
followed, in steps). This removes the foot skating and jitter that estimators leave on
standing feet.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from avatar.mocap import rotations as rot


class FootPlanter:
    """Per-foot contact state over a stream; ``__call__`` edits a solver frame in place."""

    def __init__(self, plan, height: float = 0.04, speed: float = 0.25, release: float = 0.1,
                 reach: float = 0.03):  # fmt: skip
        self.plan = plan
        self.height, self.speed, self.release, self.reach = height, speed, release, reach
        self.legs = []
        for side in "LR":
            ids = [plan.role_steps.get(f"{r}.{side}") for r in ("thigh", "shin", "foot")]
            self.legs.append(ids if all(i is not None for i in ids) else None)
        self.reset()

    def reset(self) -> None:
        self.pins: list[np.ndarray | None] = [None, None]
        self.offsets = [np.zeros(3), np.zeros(3)]
        self.previous: list[np.ndarray | None] = [None, None]
        self.floor = math.inf

    def __call__(self, f, dt: float, inherit: Callable) -> np.ndarray:
        contacts = np.zeros(2, dtype=bool)
        ankles = [f.heads[leg[2]] for leg in self.legs if leg is not None]
        if ankles:
            self.floor = min(self.floor, min(float(a[2]) for a in ankles))
        for side, leg in enumerate(self.legs):
            if leg is None or not f.solved[leg[1]]:  # the shin places the ankle
                self.pins[side], self.previous[side] = None, None
                continue
            ankle = f.heads[leg[2]].copy()
            prev = self.previous[side]
            smooth = ankle if prev is None else prev + (1 - math.exp(-dt / 0.1)) * (ankle - prev)
            self.previous[side] = smooth
            speed = math.inf if prev is None else float(np.linalg.norm(smooth - prev)) / dt
            down = ankle[2] - self.floor < self.height and speed < self.speed
            if down:
                if self.pins[side] is None:
                    self.pins[side] = ankle - self.offsets[side]  # continue a fading offset
                pin = self.pins[side]
                assert pin is not None
                if float(np.linalg.norm(pin - ankle)) > self.reach:
                    pin = self.pins[side] = ankle
                self.offsets[side] = pin - ankle
                contacts[side] = True
            else:
                self.pins[side] = None
                self.offsets[side] = self.offsets[side] * math.exp(-dt / self.release)
            if float(self.offsets[side] @ self.offsets[side]) > 1e-10:
                _reach(f, leg, ankle + self.offsets[side], inherit, self.plan.steps)
        return contacts


def _reach(f, leg: list[int], goal: np.ndarray, inherit: Callable, steps) -> None:
    """Two-bone IK: bend the knee and swing the thigh so the ankle reaches ``goal``; the
    foot keeps its world rotation."""
    thigh, shin, foot = leg
    hip, knee, ankle = f.heads[thigh], f.heads[shin], f.heads[foot]
    l1 = float(np.linalg.norm(knee - hip))
    l2 = float(np.linalg.norm(ankle - knee))
    d = float(np.linalg.norm(goal - hip))
    d = min(max(d, abs(l1 - l2) + 1e-6), l1 + l2 - 1e-6)
    upper, lower = knee - hip, ankle - knee
    normal = rot.cross(upper, lower)
    if normal @ normal < 1e-12:
        normal = f.world[thigh][:, 0]  # straight leg: bend about the thigh's X axis
    normal = rot.unit(normal)
    cos_now = float(np.clip(-(upper @ lower) / (l1 * l2), -1.0, 1.0))
    cos_want = (l1 * l1 + l2 * l2 - d * d) / (2 * l1 * l2)
    bend = rot.axis_angle(normal, math.acos(cos_now) - math.acos(min(max(cos_want, -1.0), 1.0)))
    foot_world = f.world[foot].copy()
    f.world[shin] = bend @ f.world[shin]
    new_ankle = knee + bend @ lower
    swing = rot.between(new_ankle - hip, goal - hip)
    f.world[thigh] = swing @ f.world[thigh]
    f.world[shin] = swing @ f.world[shin]
    f.world[foot] = foot_world
    for i in (thigh, shin, foot):
        base, f.heads[i] = inherit(f, i)
        f.local[i] = base.T @ f.world[i]

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
    """Per-foot contact state over a stream; ``__call__`` edits a solver frame in place
    (its heads, world and local rotations: 3- and 9-tuples of floats, see ``rotations``)."""

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
        self.pins: list[rot.V | None] = [None, None]
        self.offsets: list[rot.V] = [rot.ZERO, rot.ZERO]
        self.previous: list[rot.V | None] = [None, None]
        self.floor = math.inf

    def __call__(self, f, dt: float, inherit: Callable) -> np.ndarray:
        contacts = [False, False]
        ankles = [f.heads[leg[2]][2] for leg in self.legs if leg is not None]
        if ankles:
            self.floor = min(self.floor, min(ankles))
        follow = 1 - math.exp(-dt / 0.1)
        for side, leg in enumerate(self.legs):
            if leg is None or not f.solved[leg[1]]:  # the shin places the ankle
                self.pins[side], self.previous[side] = None, None
                continue
            ankle = f.heads[leg[2]]
            prev = self.previous[side]
            smooth = ankle if prev is None else rot.add(prev, _scaled(rot.sub(ankle, prev), follow))
            self.previous[side] = smooth
            speed = math.inf if prev is None else _length(rot.sub(smooth, prev)) / dt
            down = ankle[2] - self.floor < self.height and speed < self.speed
            if down:
                if self.pins[side] is None:
                    self.pins[side] = rot.sub(ankle, self.offsets[side])  # continue a fading offset
                pin = self.pins[side]
                assert pin is not None
                if _length(rot.sub(pin, ankle)) > self.reach:
                    pin = self.pins[side] = ankle
                self.offsets[side] = rot.sub(pin, ankle)
                contacts[side] = True
            else:
                self.pins[side] = None
                self.offsets[side] = _scaled(self.offsets[side], math.exp(-dt / self.release))
            offset = self.offsets[side]
            if rot.dot(offset, offset) > 1e-10:
                _reach(f, leg, rot.add(ankle, offset), inherit)
        return np.array(contacts)


def _length(v) -> float:
    return math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])


def _scaled(v, s: float) -> rot.V:
    return (v[0] * s, v[1] * s, v[2] * s)


def _reach(f, leg: list[int], goal: rot.V, inherit: Callable) -> None:
    """Two-bone IK: bend the knee and swing the thigh so the ankle reaches ``goal``; the
    foot keeps its world rotation."""
    thigh, shin, foot = leg
    hip, knee, ankle = f.heads[thigh], f.heads[shin], f.heads[foot]
    upper, lower = rot.sub(knee, hip), rot.sub(ankle, knee)
    l1, l2 = _length(upper), _length(lower)
    d = _length(rot.sub(goal, hip))
    d = min(max(d, abs(l1 - l2) + 1e-6), l1 + l2 - 1e-6)
    normal = rot.cross(upper, lower)
    if rot.dot(normal, normal) < 1e-12:
        w = f.world[thigh]
        normal = (w[0], w[3], w[6])  # straight leg: bend about the thigh's X axis
    normal = rot.unit(normal)
    cos_now = min(max(-rot.dot(upper, lower) / (l1 * l2), -1.0), 1.0)
    cos_want = (l1 * l1 + l2 * l2 - d * d) / (2 * l1 * l2)
    bend = rot.turn(normal, math.acos(cos_now) - math.acos(min(max(cos_want, -1.0), 1.0)))
    foot_world = f.world[foot]
    new_ankle = rot.add(knee, rot.apply(bend, lower))
    swing = rot.arc(rot.sub(new_ankle, hip), rot.sub(goal, hip))
    f.world[thigh] = rot.mul(swing, f.world[thigh])
    f.world[shin] = rot.mul(swing, rot.mul(bend, f.world[shin]))
    f.world[foot] = foot_world
    for i in (thigh, shin, foot):
        base, f.heads[i] = inherit(f, i)
        f.local[i] = rot.tmul(base, f.world[i])

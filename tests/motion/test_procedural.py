"""The built-in walk: arms hang at the sides and swing fore and aft, legs alternate."""

from __future__ import annotations

import numpy as np
import pytest

import avatar
from avatar.rig import kinematics


@pytest.fixture(scope="module")
def walking():
    human = avatar.Human({"gender": 0.8})
    clip = human.walk(seconds=1.0, fps=30)
    world = kinematics.forward(human.skeleton, clip.rotations, clip.translations)
    return human.skeleton, np.asarray(world)


def _point(skeleton, world, name):
    return world[:, skeleton.names.index(name), :3, 3]


@pytest.mark.parametrize("side", [".L", ".R"])
def test_arms_hang_at_the_sides_and_swing(walking, side):
    skeleton, world = walking
    elbow = _point(skeleton, world, "lowerarm01" + side)
    arm = elbow - _point(skeleton, world, "upperarm01" + side)
    arm /= np.linalg.norm(arm, axis=1, keepdims=True)
    out = np.degrees(np.arctan2(np.abs(arm[:, 0]), -arm[:, 2]))  # seen from the front
    assert out.max() < 35  # never held out in the rest A-pose (45 degrees)
    assert np.ptp(arm[:, 1]) > np.sin(np.radians(20))  # swings fore and aft
    # The forearm bends forward, not across the body: the wrist stays as far out as the elbow.
    wrist = _point(skeleton, world, "wrist" + side)
    assert (np.abs(wrist[:, 0]) > np.abs(elbow[:, 0]) - 0.01).all()


def test_heavier_bodies_hold_their_arms_further_out():
    from avatar.motion.procedural import _clear_hang

    thin, heavy = (avatar.Human({"gender": 1.0, "weight": w}) for w in (0.0, 1.0))
    assert 15 <= _clear_hang(thin.body, ".L") < _clear_hang(heavy.body, ".L") < 45


def test_legs_alternate(walking):
    skeleton, world = walking
    left = _point(skeleton, world, "foot.L")[:, 1]
    right = _point(skeleton, world, "foot.R")[:, 1]
    assert np.corrcoef(np.diff(left), np.diff(right))[0, 1] < 0.5

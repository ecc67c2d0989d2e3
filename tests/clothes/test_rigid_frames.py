"""Posed frames leave out of the remote-contact search the garment points that moved with
one bone as the skin round them did (``outfit._RigidPoints``): short hair on the head in a
walk or a nod. Left out or searched, a point must land in the same place."""

from __future__ import annotations

import numpy as np
import pytest

from avatar.clothes import outfit as outfit_module
from avatar.human import Human
from avatar.rig import kinematics, skinning

WEAR = ("tshirt", "jeans", "shoes", "hair-short")


@pytest.fixture(scope="module")
def dressed(model):
    return Human({"gender": 0.6}, model=model).dressed(*WEAR)


def _matrices(human, rotations, translations):
    world = kinematics.forward(human.skeleton, rotations, translations)
    return kinematics.skinning_matrices(human.skeleton, world)


def _nod(human, degrees: float):
    """One frame: the head bent forward on the neck, the neck turned (the skin under the
    hair moves in the head's frame)."""
    names = list(human.skeleton.names)
    rotations = np.tile([1.0, 0.0, 0.0, 0.0], (1, len(names), 1))
    half = np.radians(degrees) / 2
    rotations[0, names.index("head")] = [np.cos(half), np.sin(half), 0.0, 0.0]
    rotations[0, names.index("neck01")] = [np.cos(half), 0.0, 0.0, np.sin(half)]
    return _matrices(human, rotations, np.zeros((1, 3)))[0]


def _searched_everywhere(monkeypatch, outfit, body, matrices):
    with monkeypatch.context() as m:
        m.setattr(outfit_module._RigidPoints, "changed",
                  lambda self, skin, points, mats: np.ones(self.count, bool))  # fmt: skip
        return outfit.frame(body, matrices)


def test_points_left_out_land_where_the_search_puts_them(dressed, monkeypatch):
    outfit = dressed.outfit
    rigid = outfit._rigid
    head = list(dressed.skeleton.names).index("head")
    assert head in rigid.bones  # the short hair moves with the head
    hair = rigid.rows[rigid.bones.index(head)]
    walk = dressed.walk(seconds=1.0, fps=10)
    frames = list(_matrices(dressed, walk.rotations, walk.translations))
    frames += [_nod(dressed, 35.0), _nod(dressed, -25.0)]
    left_out = []
    spy = outfit_module._RigidPoints.changed

    def counting(self, skin, points, mats):
        check = spy(self, skin, points, mats)
        left_out.append(int((~check[hair]).sum()))
        return check

    for matrices in frames:
        body = skinning.linear_blend(dressed.vertices, dressed.weights, matrices)
        with monkeypatch.context() as m:
            m.setattr(outfit_module._RigidPoints, "changed", counting)
            quick = outfit.frame(body, matrices)
        full = _searched_everywhere(monkeypatch, outfit, body, matrices)
        for g, a, b in zip(outfit.garments, quick, full, strict=True):
            worst = np.abs(a - b).max()
            assert worst <= 2 * outfit_module.STILL + 1e-6, (g.name, worst)
    # The shortcut is taken: most of the hair in the walk, a good part of it in a nod.
    assert min(left_out[:-2]) > 0.8 * len(hair)
    assert 0 < min(left_out[-2:]) < max(left_out[:-2])


def test_skin_that_comes_near_brings_the_points_back(dressed):
    """A hand at the hair (skin of the feet moved onto the crown stands in for it): the hair
    points within its reach are searched again, the rest of the hair still is not."""
    outfit = dressed.outfit
    rigid = outfit._rigid
    at = rigid.bones.index(list(dressed.skeleton.names).index("head"))
    rows, rest_points = rigid.rows[at], rigid.rest_points[at]
    matrices = np.tile(np.eye(4, dtype=np.float32), (len(dressed.skeleton.names), 1, 1))
    skin = rigid.rest.copy()
    crown = rest_points[np.argmax(rest_points[:, 2])]
    feet = np.argsort(skin[:, 2])[:40]
    spread = 0.01 * np.random.default_rng(0).random((40, 3))
    skin[feet] = crown + np.array([0.0, 0.0, 0.005]) + spread
    points = np.zeros((rigid.count, 3), np.float32)
    points[rows] = rest_points
    check = rigid.changed(skin, points, matrices)
    near = np.linalg.norm(rest_points - crown, axis=1) < 0.01
    far = np.linalg.norm(rest_points - crown, axis=1) > 0.08
    assert near.any() and check[rows[near]].all()
    assert far.any() and not check[rows[far]].any()
    assert not rigid.changed(rigid.rest, points, matrices)[rows].all()  # at rest: left out

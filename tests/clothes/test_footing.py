"""Shoes stand on the floor: the sole's bottom at z = 0 and the body raised onto it."""

from __future__ import annotations

import numpy as np
import pytest

from avatar.clothes import footing
from avatar.human import Human
from avatar.rig import kinematics, skinning

BODIES = {
    "child": {"gender": 0.5, "age": 0.12},
    "woman": {"gender": 0.0},
    "heavy man": {"gender": 1.0, "weight": 1.0},
    "tall man": {"gender": 1.0, "height": 1.0, "muscle": 1.0},
}


@pytest.mark.parametrize("who", list(BODIES))
@pytest.mark.parametrize("shoe", ["shoes", "sneakers", "boots"])
def test_soles_rest_on_the_floor_and_the_body_stands_on_them(who, shoe):
    bare = Human(BODIES[who])
    human = bare.dressed(shoe, "jeans")
    worn = next(g for g in human.outfit.garments if g.name == shoe)
    lowest = float(worn.mesh.vertices[:, 2].min())
    assert abs(lowest) < 0.002, lowest  # the sole's bottom is on the floor...
    assert lowest > -0.001  # ...not in it
    # The body stands up on the sole: everything rose by the sole's depth.
    assert human.sole_height > 0.008
    rise = human.vertices[:, 2] - bare.vertices[:, 2]
    assert np.allclose(rise, human.sole_height, atol=1e-5)
    assert np.allclose(human.skeleton.heads[:, 2] - bare.skeleton.heads[:, 2], human.sole_height,
                       atol=1e-5)  # fmt: skip
    # The foot is above the sole, inside the shoe.
    skin = human.mesh.vertices
    assert skin[:, 2].min() > lowest + 0.006


def test_barefoot_and_makehuman_clothes_keep_feet_on_the_floor():
    human = Human({}).dressed("tshirt", "jeans", "socks")
    assert human.sole_height == 0.0
    assert np.array_equal(human.vertices, Human({}).vertices)
    assert footing.worn_footwear(["tshirt", "shoes", "boots", "x.mhclo"]) == ["shoes", "boots"]


def test_a_settled_pose_stands_on_the_soles_too():
    human = Human(BODIES["woman"]).dressed("shoes")
    pose = human.pose("t-pose")
    world = kinematics.forward(human.skeleton, pose.rotations, pose.translations)
    matrices = kinematics.skinning_matrices(human.skeleton, world)[0]
    body = skinning.linear_blend(human.vertices, human.weights, matrices)
    shoes = human.outfit.frame(body, matrices)[0]
    assert abs(float(shoes[:, 2].min())) < 0.003

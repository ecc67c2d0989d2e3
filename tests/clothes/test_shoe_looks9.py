"""Shoes up close, the ninth look pass: a rounder, shorter toe box in profile, a smooth
toe cap, flex creases across the vamp, boots laced up the shaft, a child's sneakers as
narrow for the foot as an adult's.

Measured on the built meshes and maps; each check failed on the code before the pass.
"""

from __future__ import annotations

import numpy as np
import pytest

from avatar.clothes import library, shoes


@pytest.fixture(scope="module")
def body():
    return library.authoring_body()


@pytest.fixture(scope="module", params=(0, 1))
def foot(request, body):
    return shoes.Foot(body, request.param)


@pytest.fixture(scope="module")
def top(body, foot):
    return shoes.upper(body, foot)


@pytest.fixture(scope="module")
def worn(body, foot, top):
    """(the upper as worn, its toe cap)."""
    return shoes.capped(body, foot, top)


def test_toe_box_ends_in_a_round_nose(foot, worn):
    """The toe box ends 12-15 mm past the toes (it was 16) and 5 mm behind its tip still
    stands 20 mm and more over the ground (it was 18, under the wall's top: a beak whose
    point the toe spring rose to meet)."""
    box = np.concatenate([p.mesh.vertices for p in worn]).astype(np.float64)
    tip = box[:, 1].min()
    assert 0.012 < foot.toe_y - tip < 0.015
    near = box[np.abs(box[:, 1] - (tip + 0.005)) < 0.0015]
    assert near[:, 2].max() - foot.ground > 0.02

"""Hair under a cap (issue 14): the built-in hair is pressed under the crown, so the cap
sits on the head where it sits without hair, every hair point under it stays inside it by
more than the layer gap, and the hair still shows, full, below the band at the back."""

from __future__ import annotations

import numpy as np
import pytest

from avatar.clothes import headwear
from avatar.clothes.fitting import LAYER_GAP
from avatar.geometry import collision
from avatar.human import Human


def _fitted(names):
    human = Human({"gender": 1.0}).dressed(*names)
    garments = {g.name: g.mesh.vertices for g in human.outfit.garments}
    base = human.model.base
    surface = collision.skin_surface(base.faces[base.face_groups["body"]])

    def height(points):
        return collision.query(human.vertices[:13380], surface, points, k=4).distance

    return human, garments, height


@pytest.fixture(scope="module")
def capped():
    return _fitted(["hair-short", "cap"])


def test_the_cap_sits_on_the_head_not_on_the_hair(capped):
    _, alone, height_alone = _fitted(["cap"])
    _, worn, height = capped
    lift = np.median(height(worn["cap"])) - np.median(height_alone(alone["cap"]))
    assert lift < 0.0005  # was 7.7 mm higher over hair standing 1.5 cm off the scalp


def test_hair_under_the_crown_is_below_the_caps_inside(capped):
    human, worn, height = capped
    hair, cap = worn["hair-short"], worn["cap"]
    centre = np.array([0.0, human.vertices[:13380, 1].mean(), hair[:, 2].max() - 0.12])

    def unit(p):
        d = p - centre
        return d / np.linalg.norm(d, axis=1, keepdims=True)

    top = cap[:, 2] > cap[:, 2].max() - 0.06  # the crown, above the band and brim
    from scipy.spatial import cKDTree

    angle, i = cKDTree(unit(cap[top])).query(unit(hair))
    under = angle < 0.02  # hair points with crown right above them
    assert under.sum() > 2000
    inside = np.linalg.norm(cap[top][i[under]] - centre, axis=1)
    radius = np.linalg.norm(hair[under] - centre, axis=1)
    assert np.percentile(inside - radius, 1) > LAYER_GAP
    assert height(hair[under]).max() < headwear.HAIR_UNDER + 0.0006


def test_hair_shows_full_below_the_band_at_the_back(capped):
    human, worn, height = capped
    hair, cap = worn["hair-short"], worn["cap"]
    head = human.vertices[:13380][human.vertices[:13380, 2] > hair[:, 2].min()]
    middle = (head[:, 1].min() + head[:, 1].max()) / 2
    band = cap[cap[:, 1] > middle + 0.04, 2].min()  # the band's lowest point at the back
    low = (hair[:, 1] > middle + 0.04) & (hair[:, 2] < band - 0.005)
    assert low.sum() > 300
    assert np.percentile(height(hair[low]), 90) > 0.008  # standing off the nape, not pressed

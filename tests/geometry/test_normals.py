"""The collision surface's per-frame vertex normals (sparse incidence, float32) are the
record's area-weighted normals (``avatar.mesh.vertex_normals``, float64 sums): two
summation orders of one definition, kept apart for speed, checked to agree."""

from __future__ import annotations

import numpy as np

from avatar.body.model import BODY_VERTICES
from avatar.geometry import collision
from avatar.mesh import vertex_normals


def test_collision_normals_equal_mesh_normals(model):
    skin = model.shape({"weight": 0.9, "gender": 0.2})[:BODY_VERTICES]
    surface = collision.skin_surface(model.base.faces)
    fast = surface.normals(skin)
    plain = vertex_normals(skin, surface.faces)
    assert fast.shape == plain.shape == (BODY_VERTICES, 3)
    np.testing.assert_allclose(fast, plain, atol=2e-5)

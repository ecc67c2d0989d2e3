"""Short hair (``hair-short``) reads as a short haircut, not spiky clumps: many narrow
cards lying close to the scalp along a combed flow, none sticking out, the crown covered."""

from __future__ import annotations

import inspect

import numpy as np
import pytest

from avatar.clothes import builtin, hair
from avatar.clothes.library import authoring_body


@pytest.fixture(scope="module")
def short():
    body = authoring_body()
    mesh = builtin.BY_NAME["hair-short"].make(body).mesh
    cap = len(hair.base_cap(body).mesh.vertices)  # the hair's first part, then the cards
    v = mesh.vertices[cap:].astype(np.float64)
    points = inspect.signature(hair.grow_cards).parameters["segments"].default + 1
    cards = v.reshape(-1, 2, points, 3)  # each card: one long side, then the other, root first
    return body, cards


def test_short_hair_fits_a_game_characters_vertex_budget():
    """hair-short is worn by default and posed every frame: at most 10,000 vertices (it
    was 15,300 with four segments a card), and still many cards (see below)."""
    mesh = builtin.BY_NAME["hair-short"].make(authoring_body()).mesh
    assert len(mesh.vertices) <= 10_000


def test_many_narrow_cards(short):
    _, cards = short
    width = np.linalg.norm(cards[:, 0] - cards[:, 1], axis=-1)[:, 0]  # at the root
    assert len(cards) >= 1000 and np.median(width) < 0.01  # was 380 cards 2 cm wide


def test_cards_lie_close_to_the_scalp_none_sticking_out(short):
    body, cards = short
    height, _ = body.skin_tree.query(cards.reshape(-1, 3))
    assert np.percentile(height, 99) < 0.018 and height.max() < 0.025
    line = cards.mean(axis=1)  # (N, 5, 3) centre lines
    chord = line[:, -1] - line[:, 0]
    chord /= np.linalg.norm(chord, axis=1, keepdims=True)
    normal = body.outward(line[:, 0])
    rise = np.degrees(np.arcsin(np.clip(np.einsum("nd,nd->n", chord, normal), -1, 1)))
    assert np.median(rise) < 15 and np.percentile(rise, 95) < 30  # along the head, not up


def test_cards_follow_the_combed_flow_from_the_crown(short):
    body, cards = short
    centre, eye_z = hair.head_frame(body)
    line = cards.mean(axis=1)
    root, next_ = line[:, 0], line[:, 1]
    along = next_ - root
    flow = hair._tangent(body, root, hair.flow_crown()(root, centre, eye_z))
    cos = np.einsum("nd,nd->n", along, flow) / np.linalg.norm(along, axis=1)
    assert np.percentile(cos, 10) > 0.7


def test_crown_has_no_gaps(short):
    """Every bit of scalp at the crown has hair over it within a few millimetres."""
    body, cards = short
    centre, eye_z = hair.head_frame(body)
    scalp = hair.base_cap(body).mesh.vertices.astype(np.float64)
    crown = scalp[scalp[:, 2] > eye_z + 0.08]
    from scipy.spatial import cKDTree

    distance, _ = cKDTree(cards.mean(axis=1).reshape(-1, 3)).query(crown)
    assert len(crown) > 50 and np.percentile(distance, 98) < 0.012

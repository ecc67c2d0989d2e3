"""Issue 14's hair styles up close: a ponytail is a bundle of strands (not one flat
ribbon), a bob's ends are cut blunt (not frayed), and every built-in hair style keeps to
a game character's vertex budget."""

from __future__ import annotations

import numpy as np
import pytest

from avatar.clothes import builtin, hair
from avatar.clothes.library import authoring_body, load_garment


@pytest.fixture(scope="module")
def body():
    return authoring_body()


def test_ponytail_is_a_bundle_of_cards_facing_every_way(body):
    """Cards fill the tail's section (not only its surface) and face every way round it:
    from behind, some are seen face on and some edge on, as strands of a bundle."""
    mesh = hair.ponytail(body).mesh
    cards = mesh.vertices.reshape(-1, 2, 13, 3).astype(np.float64)  # side, along, xyz
    assert len(cards) >= 120
    middle = cards[:, :, 6].mean(axis=1)  # (N, 3) each card's centre half way down
    spine = np.median(middle, axis=0)
    reach = np.hypot(*(middle - spine)[:, :2].T)
    assert np.percentile(reach, 20) < 0.65 * np.percentile(reach, 90)  # a core, not a shell
    across = cards[:, 1, 6] - cards[:, 0, 6]  # each card's width direction half way down
    across /= np.linalg.norm(across, axis=1, keepdims=True)
    out = (middle - spine) * [1, 1, 0]
    out /= np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-9)
    # A card on a ribbon-like shell lies across the radius (|cos| ~ 0); a bundle's cards
    # turn every way.
    cos = np.abs(np.einsum("nd,nd->n", across, out))
    assert np.percentile(cos, 75) > 0.4


def test_bob_ends_are_cut_blunt(body):
    """The hanging cards' ends show the strands cut (the texture's alpha at their tips is
    well covered), over a level line, not thinned-out tips spread over a few centimetres."""
    piece = hair.hang_cards(body, hair.flow_parted())
    mesh = piece.mesh
    alpha = load_garment("hair-bob", texture_size=256).material.base_color_texture[..., 3]
    uv = mesh.uvs[mesh.face_uvs].reshape(-1, 2)
    tips = uv[np.isclose(uv[:, 1], uv[:, 1].min())]
    rows = np.clip(((1 - tips[:, 1]) * 255).astype(int), 0, 255)
    cols = np.clip((np.mod(tips[:, 0], 1) * 255).astype(int), 0, 255)
    assert (alpha[rows, cols] > 127).mean() > 0.5  # was ~0: faded tips
    centre, eye_z = hair.head_frame(body)
    v = mesh.vertices
    low = v[(np.abs(v[:, 0]) > 0.06) & (v[:, 2] < eye_z - 0.06)]
    assert np.ptp(np.percentile(low[:, 2], [1, 10])) < 0.01  # one level line


def test_every_hair_style_keeps_to_a_vertex_budget(body):
    counts = {s.name: len(s.make(body).mesh.vertices) for s in builtin.SPECS
              if s.category == "hair"}  # fmt: skip
    assert counts["hair-short"] <= 10_000
    assert max(counts.values()) <= 16_000, counts


def test_long_hair_is_locks_not_one_sheet(body):
    """Long hair's cards are turned about their paths, each its own way (their faces not
    all lying on one surface), and wander sideways as locks do."""
    mesh = hair.long_cards(body).mesh
    cards = mesh.vertices.reshape(-1, 2, 10, 3).astype(np.float64)
    middle = cards[:, :, 6].mean(axis=1)
    across = cards[:, 1, 6] - cards[:, 0, 6]
    across /= np.linalg.norm(across, axis=1, keepdims=True)
    outward = body.outward(middle)
    tilt = np.abs(np.einsum("nd,nd->n", across, outward))  # 0: lying flat on the surface
    assert np.percentile(tilt, 75) > 0.2

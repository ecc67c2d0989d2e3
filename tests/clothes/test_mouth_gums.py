"""Gums and the mouth's lining: the teeth part's UVs spread it over a teeth-and-gums
texture (pink gums along the gum side, enamel with gaps between teeth, both rows), and
the skin texture's inside of the mouth is a lit pink-red, not a black hole."""

from __future__ import annotations

import numpy as np
import pytest

from avatar.human import Human
from avatar.looks import skin


@pytest.fixture(scope="module")
def teeth(model):
    human = Human({"expression/jawOpen": 0.8}, model=model)
    part = next(p for p in human.parts() if p.name == "teeth")
    base = model.base
    upper = np.isin(human.part_vertices("teeth"),
                    np.unique(base.faces[base.face_groups["helper-upper-teeth"]]))  # fmt: skip
    return part, upper


def _sample(image: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """(N, C) texels at UVs (N, 2) (v up, row 0 on top)."""
    h, w = image.shape[:2]
    rows = np.clip(((1 - uv[:, 1]) * h).astype(int), 0, h - 1)
    cols = np.clip((uv[:, 0] * w).astype(int), 0, w - 1)
    return image[rows, cols].astype(np.float32)


def _vertex_uvs(mesh) -> np.ndarray:
    out = np.zeros((len(mesh.vertices), 2), np.float32)
    out[mesh.faces.ravel()] = mesh.uvs[mesh.face_uvs.ravel()]
    return out


def test_teeth_have_gums_on_the_gum_side_and_enamel_at_the_biting_edge(teeth):
    part, upper = teeth
    mesh, material = part.mesh, part.material
    assert material.base_color_texture is not None and material.name == "teeth"
    uv = _vertex_uvs(mesh)
    assert uv.min() >= 0 and uv.max() <= 1
    z = mesh.vertices[:, 2]
    for row, sign in ((upper, 1.0), (~upper, -1.0)):
        ids = np.flatnonzero(row)
        columns = np.unique(uv[ids, 0])
        assert len(columns) == 17
        np.testing.assert_allclose(np.unique(uv[ids, 1]), [0, 1 / 3, 2 / 3, 1], atol=1e-6)
        for u in columns:
            column = ids[uv[ids, 0] == u]
            # The gum side (v = 1) is the top of each column of the upper row, the bottom
            # of the lower row's (jaw open: a lowered jaw keeps its layout).
            assert uv[column[np.argmax(sign * z[column])], 1] == 1.0
    texture = material.base_color_texture
    gum = _sample(texture, np.array([[u, 0.98] for u in np.linspace(0.05, 0.95, 19)]))
    enamel = _sample(texture, np.array([[u, 0.5] for u in np.linspace(0.03, 0.97, 40)]))
    assert np.all(gum[:, 0] > 1.5 * gum[:, 1])  # pink along the whole arch
    assert np.median(enamel, axis=0).min() > 220  # white teeth (the factor tints them)
    # Gaps between teeth: darker columns along the outer face, about 14 teeth in a row.
    row = texture[int(0.4 * texture.shape[0]), :, 0].astype(np.float32)
    gaps = np.flatnonzero((row[1:-1] < row[:-2]) & (row[1:-1] <= row[2:]) & (row[1:-1] < 200))
    assert 10 <= len(gaps) <= 18


def test_gum_line_is_scalloped(teeth):
    """Gums reach lower between teeth (papillae) than over a tooth's middle."""
    texture = skin.teeth_texture()
    pink = texture[..., 0].astype(int) - texture[..., 1] > 60  # (H, W) gum texels
    depth = pink[: texture.shape[0] // 2].sum(axis=0)  # gum rows from the top, per column
    assert depth.max() - depth.min() >= 0.07 * texture.shape[0]


def test_inside_of_the_mouth_is_a_pink_red_lining(model):
    material = Human({}, model=model).material("body")
    masks = skin.region_masks(material.base_color_texture.shape[0])
    inside = masks["inside-mouth"] > 0.9
    lining = material.base_color_texture[inside].astype(np.float32).mean(axis=0)
    r, g, b = lining
    assert r > 150 and r > 1.7 * g and r > 1.6 * b  # pink-red, not a dark hole


def test_old_teeth_keep_pink_gums(model):
    old = skin.mouth_material("teeth", 1.0)
    assert old.base_color_texture is skin.mouth_material("teeth", 0.2).base_color_texture
    gum = skin.teeth_texture()[2, 256].astype(np.float32) / 255
    tinted = skin.srgb_to_linear(gum) * np.asarray(old.base_color[:3])
    assert tinted[0] > 2 * tinted[1]


def _luminance(srgb8) -> float:
    """Linear luminance (Rec. 709) of an sRGB colour (0..255)."""
    linear = skin.srgb_to_linear(np.asarray(srgb8, np.float32) / 255.0)
    return float(linear @ np.array([0.2126, 0.7152, 0.0722], np.float32))


def test_mouth_lining_and_tongue_are_light_enough_to_read_in_shadow(model):
    """Inside an open mouth only bounced light reaches the lining: at the old lining
    colour (luminance 0.16) the palate rendered nearly black (sRGB ~(36, 10, 10)). Wet
    mucosa is a lighter pink-red than the lips; the tongue a little lighter still."""
    material = Human({}, model=model).material("body")
    masks = skin.region_masks(material.base_color_texture.shape[0])
    lining = material.base_color_texture[masks["inside-mouth"] > 0.9].mean(axis=0)
    lips = material.base_color_texture[masks["lips"] > 0.9].mean(axis=0)
    assert _luminance(lining) > 0.2 and _luminance(lining) > _luminance(lips) * 0.9
    r, g, b = lining
    assert 1.5 * g < r < 2.2 * g and b < 1.1 * g  # pink-red, not orange, purple or grey
    tongue = skin.mouth_material("tongue")
    assert float(np.asarray(tongue.base_color[:3]) @ [0.2126, 0.7152, 0.0722]) > 0.22

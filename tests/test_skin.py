"""Procedural skin and eyes: tones follow the ethnicity mix, regions are tinted, eyes line up."""

from __future__ import annotations

import time

import numpy as np
import pytest

from avatar.body import assets
from avatar.errors import AssetError
from avatar.looks import skin


def _luma(rgb) -> float:
    return float(np.dot(np.asarray(rgb, float), [0.2126, 0.7152, 0.0722]))


@pytest.fixture(scope="module")
def data_dir():
    try:
        return assets.find_data_dir()
    except AssetError as exc:
        pytest.skip(str(exc))


def test_tone_follows_the_ethnicity_mix():
    african, asian, caucasian = (skin.skin_tone(*w) for w in np.eye(3))
    assert _luma(african) < 0.3 * _luma(caucasian)
    assert asian[2] / asian[0] < caucasian[2] / caucasian[0]  # more yellow
    np.testing.assert_allclose(skin.skin_tone(2, 2, 2), skin.skin_tone(), rtol=1e-6)  # normalised
    np.testing.assert_allclose(skin.skin_tone(0, 0, 0), skin.skin_tone(), rtol=1e-6)
    mix = skin.skin_tone(0.5, 0, 0.5)
    np.testing.assert_allclose(mix, (african + caucasian) / 2, rtol=1e-6)  # linear-light mix
    assert _luma(skin.skin_tone(age=0.0)) > _luma(skin.skin_tone(age=0.5))  # babies lighter


def test_srgb_round_trip():
    x = np.linspace(0, 1, 101)
    np.testing.assert_allclose(skin.linear_to_srgb(skin.srgb_to_linear(x)), x, atol=1e-6)


def test_noise_is_smooth_bounded_and_seeded():
    a = skin.value_noise(np.random.default_rng(1), 256, 8)
    b = skin.value_noise(np.random.default_rng(1), 256, 8)
    np.testing.assert_array_equal(a, b)
    assert a.shape == (256, 256) and a.dtype == np.float32 and np.abs(a).max() <= 1
    assert np.abs(np.diff(a, axis=1)).max() < 0.1  # 32 px per cell: no jumps


def test_skin_texture_looks_like_skin(data_dir):
    m = skin.skin_material(0, 0, 1, size=512, data_dir=data_dir)
    image = m.base_color_texture
    assert image.shape == (512, 512, 3) and image.dtype == np.uint8
    assert m.roughness_texture.shape == (512, 512)
    masks = skin.region_masks(512, data_dir)
    plain = np.ones((512, 512), bool)
    for mask in masks.values():
        plain &= mask == 0
    plain &= ~skin._uv_box_mask(512, skin.TEETH_UV) & ~skin._uv_box_mask(512, skin.TONGUE_UV)
    expected = skin.linear_to_srgb(skin.skin_tone(0, 0, 1)) * 255
    skin_pixels = image[plain].astype(float)
    np.testing.assert_allclose(skin_pixels.mean(axis=0), expected, rtol=0.04)
    assert 0.5 < skin_pixels.std(axis=0).mean() < 8  # subtle noise, not flat, not noisy
    lips = image[masks["lips"] > 0.9].astype(float).mean(axis=0)
    cheek = skin_pixels.mean(axis=0)
    redder = (lips[0] / lips[1]) / (cheek[0] / cheek[1])
    assert 1.12 < redder < 1.35  # lips are redder, but not painted (over-saturated)
    nails = image[masks["fingernails"] > 0.9].astype(float).mean(axis=0)
    assert _luma(nails) > _luma(cheek)
    rough = m.roughness_texture
    assert rough[masks["lips"] > 0.9].mean() < rough[plain].mean() - 20


def test_skin_material_is_cached_and_fast(data_dir):
    skin.skin_material(size=1024, seed=3, data_dir=data_dir)  # decode and cache the masks
    skin._skin_material.cache_clear()
    start = time.perf_counter()
    m = skin.skin_material(size=1024, seed=3, data_dir=data_dir)
    assert time.perf_counter() - start < 1.0
    assert skin.skin_material(size=1024, seed=3, data_dir=data_dir) is m
    assert not m.base_color_texture.flags.writeable
    other = skin.skin_material(size=1024, seed=4, data_dir=data_dir)
    assert not np.array_equal(other.base_color_texture, m.base_color_texture)


def test_masks_are_in_the_body_uv_layout(data_dir):
    """The aureolae sit on the chest, symmetric about the body's UV centre line (u = 0.38)."""
    masks = skin.region_masks(256, data_dir)
    assert set(masks) == set(skin.REGIONS)
    rows, cols = np.nonzero(masks["aureolae"] > 0.5)
    left, right = cols[cols < 97], cols[cols >= 97]
    assert len(left) and len(right)
    assert abs((left.mean() + right.mean()) / 2 / 256 - 0.378) < 0.02


def test_eye_texture_centre_is_pupil_and_edge_is_sclera():
    m = skin.eye_material("blue", size=256)
    image = m.base_color_texture.astype(float)
    row = int((1 - skin.CORNEA_CENTRE[1]) * 256)
    col = int(skin.CORNEA_CENTRE[0] * 256)
    assert image[row, col].max() < 30  # pupil
    iris = image[row, col + 11]  # about 18 degrees out: iris
    assert iris[2] > iris[0] + 20  # blue
    assert image[250, 250].min() > 170  # sclera far from the cornea
    assert skin.eye_material("blue", size=256) is m


def test_eye_uvs_put_the_front_of_the_eyeball_on_the_iris(data_dir):
    from avatar.io import obj

    base = obj.read(data_dir / "3dobjs/base.obj", axes="makehuman")
    image = skin.eye_material("brown", size=512).base_color_texture.astype(float)
    for side in ("l", "r"):
        faces = base.face_groups[f"helper-{side}-eye"]
        vi, ui = base.faces[faces].reshape(-1), base.face_uvs[faces].reshape(-1)
        uv = skin.eye_uvs(base.uvs[ui], side)
        p = base.vertices[vi] - base.vertices[vi].mean(axis=0)
        front = np.argmin(p[:, 1] / np.linalg.norm(p, axis=1))  # the eyes look along -Y
        side_vertex = np.argmax(np.abs(p[:, 0]))
        rows, cols = ((1 - uv[:, 1]) * 511).astype(int), (uv[:, 0] * 511).astype(int)
        assert image[rows[front], cols[front]].max() < 120  # pupil or iris, dark
        assert image[rows[side_vertex], cols[side_vertex]].min() > 150  # sclera
    with pytest.raises(ValueError):
        skin.eye_uvs(np.array([[0.1, 0.1]]), "l")


# ---------------------------------------------------------------------------- relief, age


def _face_pixels(size: int) -> dict[str, np.ndarray]:
    """Masks of the skin map: forehead, crow's-feet corner, bald scalp, cheek (by the
    default body's position of each pixel, relative to the eyes' midpoint)."""
    from avatar.looks import wrinkles

    p = wrinkles.uv_positions(size)
    x, y, z = np.abs(p[..., 0]), p[..., 1], p[..., 2]
    with np.errstate(invalid="ignore"):
        return {
            "forehead": (z > 0.03) & (z < 0.055) & (x < 0.03) & (y < 0.02),
            "crow": (np.hypot(x - 0.041, z) < 0.018) & (x > 0.045),
            "scalp": (z > 0.1) & np.isfinite(z),
        }


def _slope(normal: np.ndarray, mask: np.ndarray) -> float:
    """Mean tilt of a normal map's normals away from flat, over ``mask``."""
    n = normal[mask].astype(float) / 127.5 - 1.0
    return float(np.mean(np.hypot(n[:, 0], n[:, 1])))


def test_skin_has_a_normal_map_and_wrinkles_come_with_age(data_dir):
    masks = _face_pixels(512)
    ages = (0.1, 0.5, 0.75, 1.0)
    mats = {a: skin.skin_material(age=a, size=512, data_dir=data_dir) for a in ages}
    for m in mats.values():
        assert m.normal_texture.shape == (512, 512, 3) and m.normal_texture.dtype == np.uint8
    for region in ("forehead", "crow"):
        slopes = [_slope(mats[a].normal_texture, masks[region]) for a in ages]
        assert slopes[1] < 1.5 * slopes[0]  # 25 years: pores, no wrinkles yet
        assert slopes[1] < slopes[2] < slopes[3]  # deeper with age
        assert slopes[3] > 3 * slopes[1], region  # an old face reads as old
    rough = [mats[a].roughness_texture[masks["forehead"]].mean() for a in (0.5, 1.0)]
    assert rough[1] > rough[0] + 10  # old skin is drier


def test_wrinkles_lie_across_the_forehead():
    """Forehead lines run side to side: depth varies far more going up the face than
    along a line."""
    from avatar.looks import wrinkles

    z = np.linspace(0.03, 0.055, 400)
    up = wrinkles._depth(np.stack([np.full_like(z, 0.01), np.zeros_like(z), z], -1))
    x = np.linspace(0.0, 0.025, 400)
    along = wrinkles._depth(np.stack([x, np.zeros_like(x), np.full_like(x, 0.0425)], -1))
    assert up.max() > 0.2 and up.min() < 0.03  # grooves and flat skin between them
    assert np.abs(np.diff(along)).sum() < 0.5 * np.abs(np.diff(up)).sum()
    assert wrinkles.age_amount(0.5) == 0.0 and wrinkles.age_amount(1.0) == pytest.approx(1.0)


def test_uv_positions_put_each_vertex_where_it_is(model):
    """A pixel at a head vertex's UV holds that vertex's place (relative to the eyes)."""
    from avatar.body.shaped import default_vertices
    from avatar.looks import wrinkles

    size = 1024
    p = wrinkles.uv_positions(size)
    base = model.base
    v = default_vertices(model)
    eyes = (v[np.unique(base.faces[base.face_groups["helper-l-eye"]])].mean(0)
            + v[np.unique(base.faces[base.face_groups["helper-r-eye"]])].mean(0)) / 2
    rows = base.face_groups["body"]
    corners, uv_index = base.faces[rows].ravel(), base.face_uvs[rows].ravel()
    head = v[corners, 2] > eyes[2] - 0.1
    uv = base.uvs[uv_index[head]]
    r = np.clip(((1 - uv[:, 1]) * size).astype(int), 0, size - 1)
    c = np.clip((uv[:, 0] * size).astype(int), 0, size - 1)
    got, want = p[r, c], v[corners[head]] - eyes
    ok = np.isfinite(got[:, 0])
    assert ok.mean() > 0.9
    assert np.median(np.linalg.norm(got[ok] - want[ok], axis=1)) < 0.003


def test_bald_scalp_has_no_dirt(data_dir):
    """Blotches on the scalp change redness, hardly lightness: no dark patches."""
    mask = _face_pixels(512)["scalp"]
    image = skin.skin_material(0, 0, 1, age=1.0, gender=1.0, size=512, data_dir=data_dir)
    lin = skin.srgb_to_linear(image.base_color_texture[mask].astype(np.float32) / 255)
    luma = lin @ np.array([0.2126, 0.7152, 0.0722], np.float32)
    assert luma.std() / luma.mean() < 0.06
    assert np.percentile(luma, 1) > 0.8 * np.median(luma)  # no dark patches

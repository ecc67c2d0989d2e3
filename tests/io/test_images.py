"""PNG write -> read is lossless; every PNG filter decodes; JPEGs decode like Blender's."""

from __future__ import annotations

import importlib.util
import os
import struct
import tempfile
import zlib

import numpy as np
import pytest

from avatar.body import assets
from avatar.errors import AssetError, FormatError
from avatar.io import images, png


@pytest.mark.parametrize("channels", [1, 2, 3, 4])
def test_png_round_trip(tmp_path, channels):
    rng = np.random.default_rng(channels)
    image = rng.integers(0, 256, (37, 53, channels), dtype=np.uint8)
    png.write(tmp_path / "a.png", image)
    back = images.read(tmp_path / "a.png")
    if channels == 2:  # grey + alpha comes back as RGBA
        image = np.concatenate([image[..., :1].repeat(3, axis=2), image[..., 1:]], axis=2)
    np.testing.assert_array_equal(back, image[..., 0] if channels == 1 else image)


def _filtered_png(image: np.ndarray, kinds: list[int]) -> bytes:
    """A PNG whose row y uses filter kinds[y] (encoded here by the spec's definitions)."""
    h, w, c = image.shape
    rows = image.reshape(h, w * c).astype(np.int64)
    out = []
    for y in range(h):
        prior = rows[y - 1] if y else np.zeros(w * c, np.int64)
        left = np.concatenate([np.zeros(c, np.int64), rows[y, :-c]])
        upleft = np.concatenate([np.zeros(c, np.int64), prior[:-c]])
        p = left + prior - upleft
        pa, pb, pc = abs(p - left), abs(p - prior), abs(p - upleft)
        paeth = np.where((pa <= pb) & (pa <= pc), left, np.where(pb <= pc, prior, upleft))
        pred = [0, left, prior, (left + prior) // 2, paeth][kinds[y]]
        out.append(bytes([kinds[y]]) + ((rows[y] - pred) % 256).astype(np.uint8).tobytes())
    header = struct.pack(">IIBBBBB", w, h, 8, {3: 2, 4: 6}[c], 0, 0, 0)
    chunk = lambda k, d: (struct.pack(">I", len(d)) + k + d  # noqa: E731
                          + struct.pack(">I", zlib.crc32(k + d)))  # fmt: skip
    return (png.SIGNATURE + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(b"".join(out)))
            + chunk(b"IEND", b""))  # fmt: skip


def test_png_decodes_every_filter():
    image = np.random.default_rng(0).integers(0, 256, (10, 7, 4), dtype=np.uint8)
    data = _filtered_png(image, [0, 1, 2, 3, 4, 4, 3, 2, 1, 0])
    np.testing.assert_array_equal(images.decode(data), image)


def test_bad_images_raise_format_error_naming_the_file(tmp_path):
    good = png.encode(np.zeros((4, 4, 3), np.uint8))
    for name, data in [("a.png", b"not a png"), ("b.png", good[:40]),
                       ("c.jpg", b"\xff\xd8\xff\xc2\x00\x02"), ("d.gif", b"GIF89a")]:  # fmt: skip
        (tmp_path / name).write_bytes(data)
        with pytest.raises(FormatError, match=name):
            images.read(tmp_path / name)
    with pytest.raises(FormatError, match="missing.png"):
        images.read(tmp_path / "missing.png")


@pytest.fixture(scope="module")
def mask_path():
    try:
        return assets.find_data_dir() / "textures" / "mpfb_lips.jpg"
    except AssetError as exc:
        pytest.skip(str(exc))


def test_jpeg_mask_decodes(mask_path):
    mask = images.read(mask_path)
    assert mask.shape == (2048, 2048) and mask.dtype == np.uint8
    assert mask.max() == 255 and (mask > 128).mean() < 0.01  # a small white region on black


@pytest.mark.skipif(importlib.util.find_spec("bpy") is None, reason="bpy not installed")
def test_jpeg_matches_blender(mask_path):
    """Blender's (libjpeg) decoding of the same file, within IDCT rounding."""
    os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="avatar-bpy-"))
    import bpy

    image = bpy.data.images.load(str(mask_path))
    try:
        pixels = np.empty(image.size[0] * image.size[1] * 4, np.float32)
        image.pixels.foreach_get(pixels)
        theirs = np.rint(pixels.reshape(image.size[1], image.size[0], 4)[::-1, :, 0] * 255)
    finally:
        bpy.data.images.remove(image)
    ours = images.read(mask_path).astype(float)
    assert np.abs(ours - theirs).max() <= 3 and np.abs(ours - theirs).mean() < 0.05

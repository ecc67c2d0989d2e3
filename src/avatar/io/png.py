"""PNG writer on numpy arrays (ISO/IEC 15948, W3C PNG 2nd edition), zlib only.

Writes 8-bit greyscale, grey+alpha, RGB or RGBA with the Sub filter on every row (one
vectorised subtraction; compresses smooth procedural textures well). Reading any image
is ``avatar.io.images`` (Pillow).
"""

from __future__ import annotations

import os
import struct
import zlib

import numpy as np

from avatar.io import atomic

SIGNATURE = b"\x89PNG\r\n\x1a\n"
COLOR_TYPES = {1: 0, 2: 4, 3: 2, 4: 6}  # channels -> PNG colour type


def write(path: str | os.PathLike[str], image: np.ndarray, level: int = 6) -> None:
    """Write (H, W) or (H, W, C) uint8 pixels, C in 1..4, as a PNG file (atomically)."""
    atomic.write_bytes(path, encode(image, level))


def encode(image: np.ndarray, level: int = 6) -> bytes:
    """(H, W[, C]) uint8 -> PNG bytes. Row 0 of the array is the top row of the image."""
    image = np.asarray(image)
    if image.dtype != np.uint8:
        raise ValueError(f"PNG pixels must be uint8, got {image.dtype}")
    if image.ndim == 2:
        image = image[:, :, None]
    height, width, channels = image.shape
    if channels not in COLOR_TYPES:
        raise ValueError(f"PNG needs 1 to 4 channels, got {channels}")
    rows = image.reshape(height, width * channels)
    # Sub filter: each byte minus the same channel of the pixel to its left (mod 256).
    filtered = rows.copy()
    filtered[:, channels:] -= rows[:, :-channels]
    raw = np.concatenate([np.ones((height, 1), np.uint8), filtered], axis=1).tobytes()
    header = struct.pack(">IIBBBBB", width, height, 8, COLOR_TYPES[channels], 0, 0, 0)
    return (
        SIGNATURE
        + _chunk(b"IHDR", header)
        + _chunk(b"IDAT", zlib.compress(raw, level))
        + _chunk(b"IEND", b"")
    )


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

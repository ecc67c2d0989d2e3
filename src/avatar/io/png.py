"""PNG reader and writer on numpy arrays (ISO/IEC 15948, W3C PNG 2nd edition), zlib only.

Writes 8-bit greyscale, grey+alpha, RGB or RGBA with the Sub filter on every row (one
vectorised subtraction; compresses smooth procedural textures well). Reads non-interlaced
8-bit files of those colour types and palette images, all five filters; None/Sub/Up rows
are vectorised, Average/Paeth rows fall back to a per-pixel loop.
"""

from __future__ import annotations

import os
import struct
import zlib

import numpy as np

from avatar.errors import FormatError

SIGNATURE = b"\x89PNG\r\n\x1a\n"
COLOR_TYPES = {1: 0, 2: 4, 3: 2, 4: 6}  # channels -> PNG colour type
CHANNELS = {0: 1, 4: 2, 2: 3, 6: 4, 3: 1}  # PNG colour type -> samples per pixel


def write(path: str | os.PathLike[str], image: np.ndarray, level: int = 6) -> None:
    """Write (H, W) or (H, W, C) uint8 pixels, C in 1..4, as a PNG file."""
    with open(path, "wb") as f:
        f.write(encode(image, level))


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


def read(path: str | os.PathLike[str]) -> np.ndarray:
    """Read a PNG file -> (H, W) uint8 for greyscale, else (H, W, C) uint8 (palette -> RGB/A)."""
    with open(path, "rb") as f:
        return decode(f.read(), path)


def decode(data: bytes, path: str | os.PathLike[str] | None = None) -> np.ndarray:
    """Decode PNG bytes; see ``read``."""
    if not data.startswith(SIGNATURE):
        raise FormatError(path, 0, "not a PNG file (bad signature)")
    chunks = _chunks(data, path)
    if "IHDR" not in chunks or "IDAT" not in chunks:
        raise FormatError(path, 0, "PNG without IHDR or IDAT chunk")
    width, height, depth, ctype, _, _, interlace = struct.unpack(">IIBBBBB", chunks["IHDR"][:13])
    if depth != 8 or interlace or ctype not in CHANNELS:
        raise FormatError(
            path,
            0,
            f"unsupported PNG (bit depth {depth}, colour type {ctype}, "
            f"interlace {interlace}); only 8-bit non-interlaced is read",
        )
    channels = CHANNELS[ctype]
    try:
        raw = np.frombuffer(zlib.decompress(chunks["IDAT"]), dtype=np.uint8)
        rows = raw.reshape(height, 1 + width * channels)
    except (zlib.error, ValueError) as exc:
        raise FormatError(path, 0, f"corrupt PNG image data ({exc})") from None
    pixels = _unfilter(rows, channels).reshape(height, width, channels)
    if ctype == 3:
        pixels = _expand_palette(pixels[:, :, 0], chunks, path)
    return pixels[:, :, 0] if pixels.shape[2] == 1 else pixels


def _chunks(data: bytes, path) -> dict[str, bytes]:
    """Chunk type -> payload; IDAT payloads concatenated."""
    out: dict[str, bytes] = {}
    pos = len(SIGNATURE)
    while pos + 8 <= len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind = data[pos + 4 : pos + 8].decode("latin-1")
        payload = data[pos + 8 : pos + 8 + length]
        if len(payload) != length:
            raise FormatError(path, 0, f"truncated PNG chunk {kind!r}")
        out[kind] = out.get(kind, b"") + payload if kind == "IDAT" else payload
        pos += 12 + length
        if kind == "IEND":
            break
    return out


def _unfilter(rows: np.ndarray, bpp: int) -> np.ndarray:
    """Undo PNG filtering; rows: (H, 1 + stride) uint8 -> (H, stride) uint8."""
    kinds, rows = rows[:, 0], rows[:, 1:]
    out = np.zeros(rows.shape, dtype=np.uint8)
    prior = np.zeros(rows.shape[1], dtype=np.uint8)
    for y, kind in enumerate(kinds):
        line = rows[y]
        if kind == 0:
            cur = line
        elif kind == 1:  # Sub: running sum per channel
            cur = np.cumsum(line.reshape(-1, bpp), axis=0, dtype=np.uint8).reshape(-1)
        elif kind == 2:  # Up
            cur = line + prior
        elif kind in (3, 4):
            cur = _unfilter_sequential(line, prior, bpp, kind)
        else:
            raise ValueError(f"bad PNG filter type {kind}")
        out[y] = cur
        prior = out[y]
    return out


def _unfilter_sequential(line: np.ndarray, prior: np.ndarray, bpp: int, kind: int) -> np.ndarray:
    """Average (3) and Paeth (4) filters, which depend on the pixel just decoded."""
    cur = [0] * len(line)
    up = prior.tolist()
    raw = line.tolist()
    for i, x in enumerate(raw):
        a = cur[i - bpp] if i >= bpp else 0
        b = up[i]
        if kind == 3:
            cur[i] = (x + ((a + b) >> 1)) & 255
            continue
        c = up[i - bpp] if i >= bpp else 0
        p = a + b - c
        pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
        pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
        cur[i] = (x + pred) & 255
    return np.array(cur, dtype=np.uint8)


def _expand_palette(index: np.ndarray, chunks: dict[str, bytes], path) -> np.ndarray:
    """(H, W) palette indices -> (H, W, 3|4) colours (alpha from tRNS when present)."""
    if "PLTE" not in chunks:
        raise FormatError(path, 0, "palette PNG without PLTE chunk")
    palette = np.frombuffer(chunks["PLTE"], dtype=np.uint8).reshape(-1, 3)
    if "tRNS" in chunks:
        alpha = np.full(len(palette), 255, dtype=np.uint8)
        trns = np.frombuffer(chunks["tRNS"], dtype=np.uint8)[: len(palette)]
        alpha[: len(trns)] = trns
        palette = np.concatenate([palette, alpha[:, None]], axis=1)
    return palette[index]

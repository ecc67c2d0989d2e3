"""Image files (PNG, JPEG and whatever else users' garments carry) -> numpy, via Pillow.

Pillow's C decoders read a 2048x2048 MakeHuman texture in tens of milliseconds, every PNG
filter, bit depth and interlacing, and progressive JPEGs. Results are uint8: (H, W) for
greyscale, (H, W, 3) RGB or (H, W, 4) RGBA (palettes and grey+alpha expanded); row 0 is
the top of the image. Avatar writes its own PNGs with ``avatar.io.png``.
"""

from __future__ import annotations

import io
import os

import numpy as np

from avatar.errors import FormatError


def read(path: str | os.PathLike[str]) -> np.ndarray:
    """Read an image file; FormatError naming the file if it is missing or unreadable."""
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError as exc:
        raise FormatError(path, 0, f"cannot read image ({exc.strerror})") from None
    return decode(data, path)


def decode(data: bytes, path: str | os.PathLike[str] | None = None) -> np.ndarray:
    """Decode image bytes; see the module docstring."""
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(io.BytesIO(data)) as image:
            image.load()
            return _pixels(image)
    except (UnidentifiedImageError, OSError, SyntaxError, ValueError) as exc:
        raise FormatError(path, 0, f"unreadable image ({exc})") from None


def _pixels(image) -> np.ndarray:
    """A loaded PIL image -> uint8 L, RGB or RGBA array."""
    mode = image.mode
    if mode in ("I;16", "I;16B", "I;16L", "I"):  # 16/32-bit grey: keep the top 8 bits
        grey = np.asarray(image, dtype=np.float64)
        top = 65535.0 if grey.max(initial=0) > 255 else 255.0
        return np.clip(np.rint(grey * 255.0 / top), 0, 255).astype(np.uint8)
    if mode in ("1", "L"):
        return np.asarray(image.convert("L"), dtype=np.uint8).copy()
    has_alpha = "A" in mode or "transparency" in image.info
    return np.asarray(image.convert("RGBA" if has_alpha else "RGB"), dtype=np.uint8).copy()

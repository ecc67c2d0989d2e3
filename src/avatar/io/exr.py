"""OpenEXR images (float32 channels) through the ``OpenEXR`` package (the ``dataset`` extra).

``read`` merges every part of a multi-part file (Blender 4.x+ writes each render pass as its
own part), channel name -> (H, W) float32, row 0 at the top. ``write`` stores named float32
channels, ZIP-compressed, atomically.
"""

from __future__ import annotations

import os

import numpy as np

from avatar.errors import AvatarError, FormatError
from avatar.io import atomic


def _openexr():
    try:
        import OpenEXR
    except ImportError:  # pragma: no cover - depends on the environment
        raise AvatarError("EXR files need the OpenEXR package: "
                          "pip install 'avatar[dataset]'") from None
    return OpenEXR


def read(path: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """Channel name -> (H, W) float32 of every part of an EXR file."""
    exr = _openexr()
    try:
        with exr.File(str(path), separate_channels=True) as f:
            return {name: np.asarray(c.pixels, dtype=np.float32)
                    for part in f.parts for name, c in part.channels.items()}  # fmt: skip
    except (RuntimeError, OSError) as exc:
        raise FormatError(path, 0, f"unreadable EXR ({exc})") from None


def write(path: str | os.PathLike[str], channels: dict[str, np.ndarray]) -> None:
    """Write (H, W) float32 channels (e.g. {"Z": depth} or {"X", "Y", "Z"}) atomically."""
    exr = _openexr()
    header = {"compression": exr.ZIP_COMPRESSION, "type": exr.scanlineimage}
    data = {name: np.ascontiguousarray(pixels, dtype=np.float32)
            for name, pixels in channels.items()}  # fmt: skip
    with atomic.replacing(path) as tmp, exr.File(header, data) as f:
        f.write(str(tmp))

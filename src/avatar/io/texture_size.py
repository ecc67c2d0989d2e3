"""Texture sizes of exported parts: each texture scaled to what its part needs, or to a cap.

A texture is never enlarged. By default (``size=None``) a part's textures are scaled down
to the power of two nearest above ``DENSITY * sqrt(surface area)`` texels (at least
``MIN_SIZE``): about 0.25 mm^2 of surface a texel, so a whole body keeps its 1024-2048 px
maps while an eyebrow (a few cm^2) gets 512 px, not the 1024 px normal map of its asset.
A given ``size`` (e.g. 512, 1024, 2048 for a game engine) caps that per-part side: a cap of
1024 leaves an eyebrow's maps at its 512 px, it does not make them 1024 px.
Materials shared by several parts stay shared (sized for the largest of them).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np
from PIL import Image

from avatar.material import Material
from avatar.mesh import Mesh
from avatar.part import MeshPart

DENSITY = 2048.0  # texels per metre of sqrt(surface area)
MIN_SIZE = 512  # px: never below this by default (close-ups of eyes, brows)
FIELDS = ("base_color_texture", "normal_texture", "roughness_texture")


def needed_size(mesh: Mesh) -> int:
    """The default texture side (px, a power of two >= MIN_SIZE) for a mesh's surface."""
    tris = mesh.triangles()
    v = np.asarray(mesh.vertices, dtype=np.float64)[tris]
    area = 0.5 * np.linalg.norm(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1).sum()
    side = DENSITY * float(np.sqrt(area))
    return max(MIN_SIZE, 1 << max(0, int(np.ceil(np.log2(max(side, 1.0))))))


def fit(image: np.ndarray, side: int) -> np.ndarray:
    """``image`` (H, W[, C]) uint8 scaled down (area-averaged) so its longer side is at most
    ``side``, keeping the aspect ratio; the same array when it already fits."""
    height, width = image.shape[:2]
    if max(height, width) <= side:
        return image
    scale = side / max(height, width)
    size = (max(1, round(width * scale)), max(1, round(height * scale)))
    picture = Image.fromarray(np.ascontiguousarray(image))
    return np.asarray(picture.resize(size, Image.Resampling.BOX))


def sized(parts: Sequence[MeshPart], size: int | None = None) -> list[MeshPart]:
    """``parts`` with their materials' textures sized per part (``needed_size``) and at most
    ``size`` px. Raises ValueError for a size under 1."""
    if size is not None and size < 1:
        raise ValueError(f"texture size must be a positive number of pixels, got {size}")
    sides: dict[int, int] = {}
    for part in parts:
        if part.material is not None:
            side = needed_size(part.mesh)
            side = side if size is None else min(side, size)
            sides[id(part.material)] = max(sides.get(id(part.material), 0), side)
    fitted: dict[int, Material] = {}
    out = []
    for part in parts:
        m = part.material
        if m is None:
            out.append(part)
            continue
        if id(m) not in fitted:
            changes: dict[str, Any] = {f: fit(getattr(m, f), sides[id(m)]) for f in FIELDS
                       if getattr(m, f) is not None}  # fmt: skip
            same = all(changes[f] is getattr(m, f) for f in changes)
            fitted[id(m)] = m if same else replace(m, **changes)
        out.append(part if fitted[id(m)] is m else replace(part, material=fitted[id(m)]))
    return out

"""The material record every exporter and the Blender bridge consume (glTF's PBR model).

Textures are plain images: uint8 arrays whose row 0 is the *top* of the picture, as in PNG
files and Blender images. A mesh's UV ``(u, v)`` (OBJ convention, v up) samples pixel
``(row, col) = ((1 - v) * H, u * W)``. Colour textures hold sRGB values; roughness and
normal maps hold linear data. Normal maps are tangent-space with +Y up (OpenGL/glTF/Blender).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

ALPHA_MODES = ("OPAQUE", "MASK", "BLEND")


@dataclass(frozen=True, eq=False)
class Material:
    """A metallic-roughness PBR material.

    name: material name (unique within a file; exporters suffix duplicates).
    base_color: linear RGBA factor, multiplied with the texture when there is one.
    base_color_texture: (H, W, 3|4) uint8 sRGB(A) image, or None.
    normal_texture: (H, W, 3) uint8 tangent-space normal map, or None.
    normal_scale: strength of the normal map (glTF ``normalTexture.scale``).
    roughness, metallic: factors in [0, 1].
    roughness_texture: (H, W) uint8 linear roughness (255 = 1), multiplied by ``roughness``.
    alpha_mode: "OPAQUE", "MASK" (cut out below ``alpha_cutoff``) or "BLEND".
    double_sided: render back faces too (hair cards, thin garments).
    extras: renderer hints that glTF has no field for (e.g. ``{"subsurface": 0.1}``); kept as
        glTF ``extras`` and read by the Blender bridge.
    """

    name: str
    base_color: tuple[float, float, float, float] = (0.8, 0.8, 0.8, 1.0)
    base_color_texture: np.ndarray | None = None
    normal_texture: np.ndarray | None = None
    normal_scale: float = 1.0
    roughness: float = 0.5
    metallic: float = 0.0
    roughness_texture: np.ndarray | None = None
    alpha_mode: str = "OPAQUE"
    alpha_cutoff: float = 0.5
    double_sided: bool = False
    extras: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.alpha_mode not in ALPHA_MODES:
            raise ValueError(f"alpha_mode must be one of {ALPHA_MODES}, got {self.alpha_mode!r}")
        if len(self.base_color) != 4:
            raise ValueError("base_color is an RGBA tuple of 4 floats")
        _check_image("base_color_texture", self.base_color_texture, (3, 4))
        _check_image("normal_texture", self.normal_texture, (3,))
        _check_image("roughness_texture", self.roughness_texture, (1,))

    def textures(self) -> dict[str, np.ndarray]:
        """The images this material uses, by field name (only those that are set)."""
        names = ("base_color_texture", "normal_texture", "roughness_texture")
        return {n: getattr(self, n) for n in names if getattr(self, n) is not None}


def _check_image(name: str, image: np.ndarray | None, channels: tuple[int, ...]) -> None:
    """Reject images that every consumer would have to convert or guess about."""
    if image is None:
        return
    if not isinstance(image, np.ndarray) or image.dtype != np.uint8:
        raise ValueError(f"{name} must be a uint8 numpy array")
    got = 1 if image.ndim == 2 else (image.shape[2] if image.ndim == 3 else -1)
    if got not in channels or min(image.shape[:2]) < 1:
        raise ValueError(
            f"{name} must be (H, W{', C' if channels != (1,) else ''}) with "
            f"C in {channels}, got shape {image.shape}"
        )

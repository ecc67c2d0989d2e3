"""Blender materials for a dataset stage: textures sized for the picture, kept across samples.

A dataset renders small pictures (256-1024 px) of people whose garments and skin carry 2K
maps. Made into Blender images at full size, each map cost ~1.2 s of a worker's time
(RGBA floats written, then packed as PNG) and 16 MB, for texels the camera never resolves:
a garment spans a few hundred pixels at most. Here each map is scaled down (area-averaged)
to the power of two at least twice the picture's longer side (512 px for 256x256, 2048 for
1024x1024, never enlarged), and the Blender materials stay cached between samples, the
least recently used dropped past ``keep`` (so memory stays bounded over a long run while
the same garments, colours and skins come back sample after sample). Labels do not depend
on any texture (the label pass overrides every material).
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import replace
from typing import Any

import bpy

from avatar.blender import materials as material_bridge
from avatar.io.texture_size import FIELDS, fit
from avatar.material import Material
from avatar.part import MeshPart

KEEP = 32  # Blender materials kept between samples (at 512 px, ~3 MB of images each)
MIN_SIDE = 256


def texture_side(width: int, height: int) -> int:
    """The longest texture side (px) worth staging for a ``width`` x ``height`` picture."""
    need = 2 * max(int(width), int(height), 1)
    return max(MIN_SIDE, 1 << (need - 1).bit_length())


def sized(material: Material, side: int) -> Material:
    """``material`` with each map scaled down to at most ``side`` px (the same record when
    every map already fits)."""
    changes: dict[str, Any] = {}
    for field in FIELDS:
        image = getattr(material, field)
        if image is not None:
            small = fit(image, side)
            if small is not image:
                changes[field] = small
    return replace(material, **changes) if changes else material


class StageMaterials:
    """Blender materials for parts' material records, made once per record and picture size.

    Keyed by the record's identity (the garment library hands out the same record for the
    same garment and colour); the record is held with its material, so its id is not reused
    while cached."""

    def __init__(self, keep: int = KEEP) -> None:
        self.keep = keep
        self.side = 0
        self._cache: OrderedDict[int, tuple[Material, bpy.types.Material]] = OrderedDict()
        self.made = 0  # Blender materials made so far (for tests and benchmarks)

    def for_picture(self, width: int, height: int) -> None:
        """Size textures for ``width`` x ``height`` pictures from now on (a new size drops
        the cache: its images are the wrong size)."""
        side = texture_side(width, height)
        if side != self.side:
            self.clear()
            self.side = side

    def get(self, part: MeshPart) -> bpy.types.Material:
        """The Blender material for ``part`` (made now, or the cached one)."""
        record = part.material
        key = id(record)
        if key in self._cache:
            self._cache.move_to_end(key)
            return self._cache[key][1]
        staged = None if record is None else sized(record, self.side or MIN_SIDE)
        made = material_bridge.material(staged, part.name)
        self.made += 1
        self._cache[key] = (record, made)
        return made

    def trim(self, used: set[str]) -> None:
        """Drop the least recently used materials past ``keep`` (never one in ``used``, the
        materials of the staged objects) and any image nothing uses any more."""
        while len(self._cache) > self.keep:
            key, (_, mat) = next(iter(self._cache.items()))
            if mat.name_full in used:
                break
            del self._cache[key]
            if mat.name_full not in self.names():  # equal records share one material
                _remove(mat)

    def clear(self) -> None:
        materials = {mat.name_full: mat for _, mat in self._cache.values()}
        self._cache.clear()
        for mat in materials.values():
            _remove(mat)

    def names(self) -> set[str]:
        return {mat.name_full for _, mat in self._cache.values()}


def _remove(mat: bpy.types.Material) -> None:
    """Remove ``mat`` and its images from Blender once no object uses them."""
    if mat.users > (1 if mat.use_fake_user else 0):
        return
    images = [n.image for n in mat.node_tree.nodes if getattr(n, "image", None)]
    bpy.data.materials.remove(mat)
    for image in images:
        if image.users == 0:
            bpy.data.images.remove(image)

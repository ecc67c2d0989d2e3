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

import weakref
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

    Keyed by what a record draws with: its name and factors, and its texture arrays by
    identity (the garment library hands out the same arrays for the same garment and
    colour, while a body's skin is new every sample). The arrays are held by weak reference
    only, so the cache keeps no full-size map alive; an entry whose arrays are gone can never
    be hit again and is dropped first."""

    def __init__(self, keep: int = KEEP) -> None:
        self.keep = keep
        self.side = 0
        self._cache: OrderedDict[tuple, tuple[tuple, bpy.types.Material]] = OrderedDict()
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
        key = _key(record)
        entry = self._cache.get(key)
        if entry is not None and _alive(entry[0], record):
            self._cache.move_to_end(key)
            return entry[1]
        staged = None if record is None else sized(record, self.side or MIN_SIDE)
        made = material_bridge.material(staged, part.name)  # an equal record's, if cached
        self.made += 1
        self._cache.pop(key, None)
        self._cache[key] = (_refs(record), made)
        return made

    def trim(self, used: set[str]) -> None:
        """Drop the entries whose arrays are gone, then the least recently used past ``keep``,
        and remove each dropped material, with its images, once no entry and no object in
        ``used`` (the staged objects' materials) uses it."""
        dead = {key for key, (refs, _) in self._cache.items() if not _alive(refs)}
        live = [key for key in self._cache if key not in dead]
        dropped = list(dead) + live[: max(0, len(live) - self.keep)]
        materials = [self._cache.pop(key)[1] for key in dropped]
        kept = self.names() | used
        for mat in {m.name_full: m for m in materials if m.name_full not in kept}.values():
            _remove(mat)

    def clear(self) -> None:
        materials = {mat.name_full: mat for _, mat in self._cache.values()}
        self._cache.clear()
        for mat in materials.values():
            _remove(mat)

    def names(self) -> set[str]:
        return {mat.name_full for _, mat in self._cache.values()}


def _key(record: Material | None) -> tuple:
    """What ``record`` draws with: its factors by value, its texture arrays by identity."""
    if record is None:
        return (None,)
    factors = replace(record, **{field: None for field in FIELDS})
    return (repr(factors), *(id(getattr(record, field)) for field in FIELDS))


def _refs(record: Material | None) -> tuple:
    """Weak references to ``record``'s texture arrays (None where it has none)."""
    if record is None:
        return ()
    return tuple(None if (a := getattr(record, f)) is None else weakref.ref(a) for f in FIELDS)


def _alive(refs: tuple, record: Material | None = None) -> bool:
    """Whether the arrays behind ``refs`` still exist (and are ``record``'s, when given: an
    id can be reused once its array is gone)."""
    for i, ref in enumerate(refs):
        array = None if ref is None else ref()
        if ref is not None and array is None:
            return False
        if record is not None and array is not getattr(record, FIELDS[i]):
            return False
    return True


def _remove(mat: bpy.types.Material) -> None:
    """Remove ``mat`` and its images from Blender once no object uses them."""
    if mat.users > (1 if mat.use_fake_user else 0):
        return
    images = [n.image for n in mat.node_tree.nodes if getattr(n, "image", None)]
    bpy.data.materials.remove(mat)
    for image in images:
        if image.users == 0:
            bpy.data.images.remove(image)

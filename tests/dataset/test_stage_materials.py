"""A dataset stage's materials: textures sized for the picture, kept between samples, the
least recently used dropped with their images (bpy)."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

from avatar.material import Material
from avatar.mesh import Mesh
from avatar.part import MeshPart

pytestmark = pytest.mark.skipif(importlib.util.find_spec("bpy") is None, reason="needs bpy")

QUAD = Mesh(np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], np.float32),
            np.array([[0, 1, 2, 3]], np.int32))  # fmt: skip


def _part(name: str, side: int = 2048, seed: int = 0) -> MeshPart:
    rng = np.random.default_rng(seed)
    colour = rng.integers(0, 256, (side, side, 3), dtype=np.uint8)
    rough = rng.integers(0, 256, (side, side), dtype=np.uint8)
    return MeshPart(name, QUAD, Material(name, base_color_texture=colour,
                                         roughness_texture=rough))  # fmt: skip


def _image_sides(mat) -> list[int]:
    return sorted(max(n.image.size) for n in mat.node_tree.nodes if getattr(n, "image", None))


def test_texture_side_is_twice_the_picture_as_a_power_of_two():
    from avatar.blender.stage_materials import texture_side

    assert texture_side(256, 256) == 512
    assert texture_side(320, 240) == 1024  # 640 -> the next power of two
    assert texture_side(1024, 768) == 2048
    assert texture_side(64, 48) == 256  # never below 256


def test_maps_are_staged_at_the_pictures_size_and_reused():
    from avatar.blender.stage_materials import StageMaterials

    stage = StageMaterials(keep=4)
    stage.for_picture(256, 256)
    part = _part("shirt")
    mat = stage.get(part)
    assert _image_sides(mat) == [512, 512]  # a 2K record staged at 512 px
    assert part.material.base_color_texture.shape[0] == 2048  # the record is untouched
    assert stage.get(part) is mat and stage.made == 1  # the next sample reuses it
    small = _part("brow", side=128, seed=1)
    assert _image_sides(stage.get(small)) == [128, 128]  # never enlarged
    stage.for_picture(1024, 1024)  # another picture size: made again at 2048
    assert _image_sides(stage.get(part)) == [2048, 2048]
    stage.clear()


def test_least_recently_used_materials_are_dropped_with_their_images():
    from avatar.blender.stage_materials import StageMaterials

    bpy = pytest.importorskip("bpy")
    stage = StageMaterials(keep=2)
    stage.for_picture(128, 128)
    parts = [_part(f"garment{i}", side=512, seed=i) for i in range(4)]
    images_before = len(bpy.data.images)
    made = [stage.get(p) for p in parts]
    names = [m.name_full for m in made]
    stage.trim(used={names[3]})
    assert stage.names() == set(names[2:])  # the two oldest gone...
    assert not any(n in bpy.data.materials for n in names[:2])
    assert len(bpy.data.images) == images_before + 2 * 2  # ...with their two maps each
    stage.get(parts[2])  # used again: now the most recent
    stage.get(parts[0])  # made again
    stage.trim(used=set())
    assert stage.names() == {names[2], stage.get(parts[0]).name_full}
    stage.clear()
    assert len(bpy.data.images) == images_before


def test_equal_records_share_a_material_that_outlives_either_entry():
    from dataclasses import replace

    from avatar.blender.stage_materials import StageMaterials

    stage = StageMaterials(keep=1)
    stage.for_picture(128, 128)
    first = _part("twin", side=256, seed=7)
    second = replace(first, material=replace(first.material))  # equal content, another record
    shared = stage.get(first)
    assert stage.get(second) is shared  # the bridge's digest finds the first one
    stage.trim(used=set())  # drops the first entry; the second still holds the material
    assert shared.name_full in stage.names() and len(shared.node_tree.nodes) > 0
    stage.clear()


def test_cache_stays_bounded_when_an_old_entry_shares_a_material_in_use():
    """Records equal in content but with their own arrays (a garment rebuilt for each body)
    share one Blender material; the oldest entry holding it must not stop the trimming
    (it did: 264 cached materials after 60 samples with keep = 32)."""
    import gc

    from avatar.blender.stage_materials import StageMaterials

    bpy = pytest.importorskip("bpy")
    stage = StageMaterials(keep=2)
    stage.for_picture(128, 128)
    base = _part("skin", side=256, seed=3)
    parts = [base]
    for i in range(6):
        m = base.material
        twin = Material("skin", base_color_texture=m.base_color_texture.copy(),
                        roughness_texture=m.roughness_texture.copy())  # fmt: skip
        copy = MeshPart("skin", QUAD, twin)
        shared = stage.get(copy)
        parts.append(copy)
        other = _part(f"garment{i}", side=256, seed=10 + i)
        parts.append(other)
        stage.get(other)
        stage.trim(used={shared.name_full, stage.get(other).name_full})
        assert len(stage._cache) <= 2, len(stage._cache)
        assert shared.name_full in bpy.data.materials  # in use: kept
    del parts, base, copy, other, twin, m  # every array the entries refer to
    gc.collect()
    stage.trim(used=set())  # every record is gone: nothing can be hit, nothing is kept
    assert stage.names() == set()
    stage.clear()


def test_the_cache_holds_no_texture_alive():
    import gc
    import weakref

    from avatar.blender.stage_materials import StageMaterials

    stage = StageMaterials(keep=8)
    stage.for_picture(128, 128)
    part = _part("shirt", side=512, seed=5)
    stage.get(part)
    texture = weakref.ref(part.material.base_color_texture)
    del part
    gc.collect()
    assert texture() is None
    stage.clear()

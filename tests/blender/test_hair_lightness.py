"""Long hair renders as light as short hair of the same colour under the same light along
the top of the head: the long locks' roots, all at the crown, stacked into a ridge of card
edges there that rendered as a dark band along the top (Cycles, the studio's lights)."""

from __future__ import annotations

import numpy as np
import pytest

SIZE = 120  # pixels: ~2.8 mm a pixel over the head
SIDE = (1.0, -0.3, 0.15)  # from the subject's right, a little in front and above


def _render(style: str, tmp_path) -> tuple[np.ndarray, np.ndarray]:
    """(H, W) CIE L* of the picture and (H, W) bool hair pixels (the hair's own render,
    every other object held out) of a woman wearing ``style`` in blond, seen from the side."""
    import bpy

    from avatar.blender import render, scene
    from avatar.blender.camera import add_camera
    from avatar.camera import CameraModel, look_at
    from avatar.human import Human, Recipe

    blond = {style: {"colour": "blond hair"}}
    recipe = Recipe(params={"gender": 0.0, "age": 0.45}, clothes=(style,), garment_options=blond)
    human = Human.from_recipe(recipe)
    scene.clear_scene()
    top = float(human.vertices[:13380, 2].max())
    scene.build_character(scene.Character("h", human.parts(), human.skeleton,
                                          location=(0.0, 0.0, 1.8 - top)))  # fmt: skip
    scene.add_lights()
    back = np.asarray(SIDE) / np.linalg.norm(SIDE)
    centre = np.array([0.0, 0.0, 1.68])
    add_camera(CameraModel(85.0, 36.0, 24.0, "HORIZONTAL", 0.0, 0.0, (SIZE, SIZE), 100,
                           (1.0, 1.0), look_at(centre + back * 0.8, centre)))  # fmt: skip
    picture = render.read_png(render.render(tmp_path / f"{style}.png", samples=16,
                                            resolution=SIZE))  # fmt: skip
    for obj in bpy.data.objects:
        if obj.type == "MESH" and obj.get("avatar_part") != style:
            obj.is_holdout = True
    mask = render.read_png(render.render(tmp_path / f"{style}_mask.png", samples=1,
                                         resolution=SIZE, transparent=True))  # fmt: skip
    srgb = picture[..., :3].astype(np.float64)
    linear = np.where(srgb <= 0.04045, srgb / 12.92, ((srgb + 0.055) / 1.055) ** 2.4)
    lightness = 116 * np.cbrt(linear @ [0.2126, 0.7152, 0.0722]) - 16
    return lightness, mask[..., 3] > 0.98


def _top_rim(lightness: np.ndarray, hair: np.ndarray, depth: int = 4) -> float:
    """Mean L* of the top ``depth`` hair pixels of every column: the hair along the top
    of the head's silhouette."""
    values = [lightness[top:top + depth, c][hair[top:top + depth, c]]
              for c, top in enumerate(hair.argmax(axis=0)) if hair[:, c].any()]  # fmt: skip
    return float(np.concatenate(values).mean())


@pytest.mark.slow
def test_long_hair_is_as_light_as_short_hair_along_the_top(empty_scene, tmp_path):
    short, short_hair = _render("hair-short", tmp_path)
    long_, long_hair = _render("hair-long", tmp_path)
    assert short_hair.sum() > 1000 and long_hair.sum() > 2 * short_hair.sum()
    ratio = _top_rim(long_, long_hair) / _top_rim(short, short_hair)
    assert ratio > 0.93, ratio  # 0.83 with the ridge of roots at the crown

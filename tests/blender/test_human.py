"""Integration with the real body model: Blender deforms a Human exactly as Avatar's LBS does.

Skipped when the MakeHuman assets are not installed.
"""

from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture(scope="module")
def human():
    from avatar.errors import AssetError

    try:
        from avatar.human import Human

        return Human({"gender": 0.2, "age": 0.4, "pca/belly": 1.0})
    except AssetError as exc:
        pytest.skip(f"MakeHuman assets not installed: {exc}")


def random_pose(skeleton, rng, frames=2, degrees=20.0):
    from avatar.rig.skeleton import Animation

    axis = rng.normal(size=(frames, len(skeleton.names), 3))
    axis /= np.linalg.norm(axis, axis=-1, keepdims=True)
    half = np.radians(rng.uniform(0, degrees, size=(frames, len(skeleton.names), 1))) / 2
    rotations = np.concatenate([np.cos(half), np.sin(half) * axis], axis=-1)
    translations = np.zeros((frames, len(skeleton.names), 3))
    translations[:, 0] = [0.1, -0.2, 0.05]
    return Animation(rotations, translations, 30.0, skeleton.names)


def test_blender_skinning_equals_avatar_lbs(empty_scene, human, rng):
    import bpy

    from avatar import export
    from avatar.blender import mesh, scene

    animation = random_pose(human.skeleton, rng)
    built = scene.build_character(export.character(human, animation))
    bpy.context.scene.frame_set(2)
    body = next(o for o in built.parts if o.name.startswith("body"))
    expected = human.posed(animation, slice(1, 2))[0][human.part_vertices("body")]
    np.testing.assert_allclose(mesh.read_vertices(body, evaluated=True), expected, atol=1e-4)


def test_render_character_png(empty_scene, human, tmp_path):
    from avatar import export
    from avatar.blender import render

    path = render.render_character_png(export.character(human), tmp_path / "human.png",
                                       engine="WORKBENCH", resolution=(128, 192))  # fmt: skip
    pixels = render.read_png(path)
    assert pixels.shape == (192, 128, 4) and pixels[..., :3].std() > 0.05

"""One picture of one human: what ``avatar create --render`` writes."""

from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path

import bpy

from avatar.blender import render, scene
from avatar.rig.skeleton import Animation


def render_human(
    human: object,
    path: str | os.PathLike[str],
    animation: Animation | None = None,
    engine: str = "CYCLES",
    samples: int = 32,
    resolution: tuple[int, int] = (640, 960),
) -> Path:
    """Render ``human`` (at the middle frame of ``animation``, if any) to a PNG."""
    if animation is not None:  # one picture: stage that frame only (its garments bake once)
        middle = slice(animation.frames // 2, animation.frames // 2 + 1)
        animation = replace(animation, rotations=animation.rotations[middle],
                            translations=animation.translations[middle])  # fmt: skip
    character = scene.character_from_human(human, animation=animation)
    direction = (0.35, -1.0, 0.15)
    built = render.stage_characters([character], resolution, direction=direction)[0]
    if animation is not None:
        bpy.context.scene.frame_set(bpy.context.scene.frame_start)
        scene.frame_camera(built.parts, direction=direction)  # the character has moved
    return render.render(path, engine=engine, samples=samples, resolution=resolution)

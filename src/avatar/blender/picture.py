"""One picture of one character: what ``avatar create --render`` writes."""

from __future__ import annotations

import os
from pathlib import Path

import bpy

from avatar.blender import render, scene


def render_character(
    character: scene.Character,
    path: str | os.PathLike[str],
    engine: str = "CYCLES",
    samples: int = 32,
    resolution: tuple[int, int] = (640, 960),
) -> Path:
    """Render a character (at the first frame of its animation, if any) to a PNG."""
    direction = (0.35, -1.0, 0.15)
    built = render.stage_characters([character], resolution, direction=direction)[0]
    if character.animation is not None:
        bpy.context.scene.frame_set(bpy.context.scene.frame_start)
        scene.frame_camera(built.parts, direction=direction)  # the character has moved
    return render.render(path, engine=engine, samples=samples, resolution=resolution)

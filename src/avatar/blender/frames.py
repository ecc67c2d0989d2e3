"""Render every frame of a staged character's animation to PNG files, from one fixed
camera framed on the largest pose of the clip (for videos of a character, e.g. the ground
truth of motion capture from video)."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import bpy
import numpy as np

from avatar.blender import render as render_bridge
from avatar.blender import scene as stage


def render_frames(
    character: stage.Character,
    folder: str | os.PathLike[str],
    resolution: tuple[int, int] = (320, 400),
    direction: Sequence[float] = (0.25, -1.0, 0.12),
    engine: str = "WORKBENCH",
    samples: int = 8,
    camera: np.ndarray | None = None,
    only: Sequence[int] | None = None,
) -> tuple[list[Path], np.ndarray]:
    """Stage ``character`` (floor, lights) and render each frame of its animation to
    ``folder``/00000.png, ... Returns (the paths, the camera's (4, 4) world matrix).

    direction: from the subject towards the camera (characters face -Y). camera: a (4, 4)
    world matrix to reuse (e.g. the input's, for a side-by-side), else framed on the box
    around every pose of the clip. only: render just these frames (0-based).
    """
    built = stage.build_character(character, stage.new_collection(character.name))
    scene = bpy.context.scene
    render_bridge.set_resolution(scene, resolution)
    frames = list(range(scene.frame_start, scene.frame_end + 1))
    if camera is None:
        box = _pose_box(built, frames[::5])
        camera_object = stage.frame_camera([box], direction=direction)
        bpy.data.objects.remove(box)
    else:
        camera_object = stage.frame_camera(built.parts, direction=direction)
        camera_object.matrix_world = camera.T.tolist()  # numpy rows -> Blender columns
    folder = Path(folder)
    paths = []
    for i, frame in enumerate(frames):
        if only is not None and i not in only:
            continue
        scene.frame_set(frame)
        paths.append(render_bridge.render(folder / f"{i:05d}.png", engine=engine,
                                          samples=samples, resolution=resolution))  # fmt: skip
    return paths, np.array(camera_object.matrix_world).reshape(4, 4)


def stage_empty(floor: bool = True) -> None:
    """Clear the scene and add lights (and a floor)."""
    stage.clear_scene()
    stage.add_lights()
    if floor:
        stage.add_floor()


def _pose_box(built: stage.CharacterObjects, frames: list[int]) -> bpy.types.Object:
    """A temporary box around the character over ``frames`` (removed after framing)."""
    scene = bpy.context.scene
    lows, highs = [], []
    for frame in frames:
        scene.frame_set(frame)
        lo, hi = stage.world_bounds(built.parts)
        lows.append(lo)
        highs.append(hi)
    return render_bridge._box_object(np.min(lows, axis=0), np.max(highs, axis=0))

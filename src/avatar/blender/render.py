"""Render still pictures of characters: one, a grid of several, or a strip over a clip.

Cycles runs on the CPU unless Blender reports a GPU. In the ``bpy`` module the Render Result
holds no pixels, so every render is written to a file and read back from there when needed.
"""

from __future__ import annotations

import logging
import math
import os
import tempfile
from collections.abc import Sequence
from pathlib import Path

import bpy
import numpy as np

from avatar.blender import scene as stage

log = logging.getLogger(__name__)

_GPU_BACKENDS = ("OPTIX", "CUDA", "HIP", "ONEAPI", "METAL")


def render(
    path: str | os.PathLike[str],
    engine: str = "CYCLES",
    samples: int = 32,
    resolution: int | tuple[int, int] = 512,
    transparent: bool = False,
    scene: bpy.types.Scene | None = None,
) -> Path:
    """Render the scene's camera view to a PNG and return its path.

    engine: "CYCLES" (path traced) or "WORKBENCH" (fast solid shading, for previews/tests).
    samples: Cycles samples per pixel. resolution: square size or (width, height) pixels.
    """
    scene = scene or bpy.context.scene
    configure(scene, engine, samples, resolution, transparent)
    path = Path(path).resolve()
    path.parent.mkdir(parents=True, exist_ok=True)
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True, scene=scene.name)
    return path


def configure(
    scene: bpy.types.Scene,
    engine: str = "CYCLES",
    samples: int = 32,
    resolution: int | tuple[int, int] = 512,
    transparent: bool = False,
) -> None:
    """Set engine, samples, resolution and 8-bit RGBA PNG output on ``scene``."""
    set_resolution(scene, resolution)
    settings = scene.render
    settings.film_transparent = transparent
    settings.image_settings.file_format = "PNG"
    settings.image_settings.color_mode = "RGBA"
    scene.view_settings.view_transform = "AgX" if engine == "CYCLES" else "Standard"
    if engine == "CYCLES":
        _configure_cycles(scene, samples)
    elif engine == "WORKBENCH":
        _configure_workbench(scene)
    else:
        settings.engine = engine_id(engine)


# EEVEE's engine id is BLENDER_EEVEE_NEXT in Blender 4.2-4.5 and BLENDER_EEVEE again from 5.0.
_EEVEE_IDS = ("BLENDER_EEVEE", "BLENDER_EEVEE_NEXT")


def engine_id(engine: str) -> str:
    """``engine`` as this Blender names it: either EEVEE id becomes the one it accepts."""
    if engine not in _EEVEE_IDS:
        return engine
    settings = bpy.types.RenderSettings.bl_rna.properties["engine"]
    known = {item.identifier for item in settings.enum_items}
    found = [e for e in (engine, *_EEVEE_IDS) if e in known]
    if found:
        return found[0]
    return "BLENDER_EEVEE_NEXT" if bpy.app.version < (5, 0) else "BLENDER_EEVEE"


def set_resolution(scene: bpy.types.Scene, resolution: int | tuple[int, int]) -> None:
    """Image size in pixels: a square size or (width, height)."""
    width, height = (resolution, resolution) if isinstance(resolution, int) else resolution
    scene.render.resolution_x, scene.render.resolution_y = int(width), int(height)
    scene.render.resolution_percentage = 100


def _configure_cycles(scene: bpy.types.Scene, samples: int) -> None:
    scene.render.engine = "CYCLES"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = samples >= 16  # the denoiser is a waste on tiny sample counts
    scene.cycles.max_bounces = 6
    scene.cycles.device = "GPU" if enable_gpu() else "CPU"


def _configure_workbench(scene: bpy.types.Scene) -> None:
    scene.render.engine = "BLENDER_WORKBENCH"
    shading = scene.display.shading
    shading.light = "STUDIO"
    shading.color_type = "MATERIAL"
    shading.show_shadows = True
    shading.show_cavity = False


def enable_gpu() -> bool:
    """Turn on the first GPU backend Cycles reports devices for; False when there is none."""
    addon = bpy.context.preferences.addons.get("cycles")
    if addon is None:
        return False
    prefs = addon.preferences
    for backend in _GPU_BACKENDS:
        try:
            prefs.compute_device_type = backend
        except TypeError:  # backend not compiled into this build
            continue
        prefs.refresh_devices()
        devices = [d for d in prefs.devices if d.type == backend]
        if devices:
            for device in prefs.devices:
                device.use = device.type == backend
            log.info("Cycles renders on %s: %s", backend, ", ".join(d.name for d in devices))
            return True
    prefs.compute_device_type = "NONE"
    return False


def stage_characters(
    characters: Sequence[stage.Character],
    resolution: int | tuple[int, int],
    spacing: float = 0.75,
    columns: int | None = None,
    direction: Sequence[float] = (0.25, -1.0, 0.12),
) -> list[stage.CharacterObjects]:
    """Clear the scene; place characters on a grid (rows go back in +Y); camera, lights, floor.

    resolution: the image size the camera is framed for. spacing: distance between
    neighbours in metres. columns: per row (default: all in one row).
    """
    stage.clear_scene()
    set_resolution(bpy.context.scene, resolution)
    columns = columns or len(characters)
    built = [
        stage.build_character(_placed(c, i, columns, spacing)) for i, c in enumerate(characters)
    ]
    stage.add_lights()
    stage.add_floor()
    stage.frame_camera([o for b in built for o in b.parts], direction=direction)
    return built


def _placed(character: stage.Character, i: int, columns: int, spacing: float) -> stage.Character:
    from dataclasses import replace

    row, column = divmod(i, columns)
    x = (column - (columns - 1) / 2) * spacing
    return replace(character, location=(x, row * spacing * 1.5, 0.0))


def render_grid(
    characters: Sequence[stage.Character],
    path: str | os.PathLike[str],
    columns: int | None = None,
    spacing: float = 0.75,
    resolution: int | tuple[int, int] | None = None,
    **render_kwargs: object,
) -> Path:
    """Render several characters side by side (e.g. for the README) to one PNG.

    resolution: default 384 px per column by 640 px per row.
    """
    columns = columns or len(characters)
    rows = math.ceil(len(characters) / columns)
    resolution = resolution or (384 * columns, 640 * rows)
    stage_characters(characters, resolution, spacing=spacing, columns=columns)
    return render(path, resolution=resolution, **render_kwargs)


def render_strip(
    character: stage.Character,
    path: str | os.PathLike[str],
    every: int = 10,
    panel: tuple[int, int] = (256, 384),
    **render_kwargs: object,
) -> Path:
    """Render every ``every``-th frame of the character's animation into one wide PNG.

    Each panel (width, height) is a render with the camera moved sideways to keep the
    character centred, at the same height and distance so feet and floor stay comparable.
    """
    built = stage_characters([character], panel)[0]
    scene = bpy.context.scene
    frames = list(range(scene.frame_start, scene.frame_end + 1, max(1, every)))
    camera, centre = _strip_camera(built, frames)
    pictures = []
    with tempfile.TemporaryDirectory(prefix="avatar-strip-") as tmp:
        for frame in frames:
            scene.frame_set(frame)
            lo, hi = stage.world_bounds(built.parts)
            centre = _slide_camera(camera, centre, (lo + hi) / 2)
            png = render(Path(tmp) / f"{frame:05d}.png", resolution=panel, **render_kwargs)
            pictures.append(read_png(png))
    return write_png(path, np.concatenate(pictures, axis=1))


def _strip_camera(built: stage.CharacterObjects, frames: list[int]) -> tuple:
    """Aim the camera at the character's largest pose over ``frames``; returns it and the
    (3,) point it is centred on."""
    scene = bpy.context.scene
    lows, highs = [], []
    for frame in frames:
        scene.frame_set(frame)
        lo, hi = stage.world_bounds(built.parts)
        lows.append(lo)
        highs.append(hi)
    lo, hi = np.min(lows, axis=0), np.max(highs, axis=0)
    # Frame a box of the largest single-pose footprint, not the whole path walked.
    size = np.max(np.array(highs) - np.array(lows), axis=0)
    centre = (lo + hi) / 2
    half = np.array([size[0] / 2, size[1] / 2, 0.0])
    box = _box_object(np.r_[centre[:2], lo[2]] - half, np.r_[centre[:2], hi[2]] + half)
    camera = stage.frame_camera([box])
    bpy.data.objects.remove(box)
    return camera, centre


def _slide_camera(camera: bpy.types.Object, old: np.ndarray, new: np.ndarray) -> np.ndarray:
    """Move the camera horizontally by new - old (x, y only); returns the new centre."""
    shift = np.array([new[0] - old[0], new[1] - old[1], 0.0])
    camera.location = np.array(camera.location) + shift
    return np.array([new[0], new[1], old[2]])


def _box_object(lo: np.ndarray, hi: np.ndarray) -> bpy.types.Object:
    from avatar.blender.mesh import new_mesh_object
    from avatar.mesh import Mesh

    corners = np.array(
        [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])],
        dtype=np.float32,
    )
    return new_mesh_object("bounds", Mesh(corners, np.array([[0, 1, 3, 2]], dtype=np.int32)))


def read_png(path: str | os.PathLike[str]) -> np.ndarray:
    """(H, W, 4) float32 pixels of an image file, row 0 at the top."""
    image = bpy.data.images.load(str(path), check_existing=False)
    try:
        width, height = image.size
        pixels = np.empty(width * height * 4, dtype=np.float32)
        image.pixels.foreach_get(pixels)
        return pixels.reshape(height, width, 4)[::-1]
    finally:
        bpy.data.images.remove(image)


def write_png(path: str | os.PathLike[str], pixels: np.ndarray) -> Path:
    """Write (H, W, 4) float 0..1 pixels (row 0 at the top) as an 8-bit RGBA PNG."""
    height, width = pixels.shape[:2]
    image = bpy.data.images.new("avatar-png", width, height, alpha=True)
    try:
        # The pixels are already display-referred (read from a PNG): no view transform again.
        image.colorspace_settings.name = "Non-Color"
        image.pixels.foreach_set(np.ascontiguousarray(pixels[::-1], dtype=np.float32).ravel())
        path = Path(path).resolve()
        path.parent.mkdir(parents=True, exist_ok=True)
        image.filepath_raw = str(path)
        image.file_format = "PNG"
        image.save()
        return path
    finally:
        bpy.data.images.remove(image)


def render_character_png(
    character: stage.Character,
    path: str | os.PathLike[str],
    engine: str = "CYCLES",
    samples: int = 32,
    resolution: int | tuple[int, int] = (512, 768),
) -> Path:
    """Render one character (``avatar.export.character`` makes one of a human)."""
    stage_characters([character], resolution)
    return render(path, engine=engine, samples=samples, resolution=resolution)

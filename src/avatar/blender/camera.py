"""Cameras: a Blender camera as ``avatar.camera.CameraModel`` (OpenCV ``K`` and
``world_to_camera``), and a camera placed from one."""

from __future__ import annotations

import bpy
import numpy as np
from mathutils import Matrix

from avatar.camera import CameraModel


def camera_model(obj: bpy.types.Object, scene: bpy.types.Scene | None = None) -> CameraModel:
    """The CameraModel of a perspective camera object as ``scene`` renders it."""
    scene = scene or bpy.context.scene
    cam, render = obj.data, scene.render
    if cam.type != "PERSP":
        raise ValueError(f"camera {obj.name!r} is {cam.type}; only perspective cameras")
    return CameraModel(
        lens=cam.lens, sensor_width=cam.sensor_width, sensor_height=cam.sensor_height,
        sensor_fit=cam.sensor_fit, shift_x=cam.shift_x, shift_y=cam.shift_y,
        resolution=(render.resolution_x, render.resolution_y),
        percentage=render.resolution_percentage,
        pixel_aspect=(render.pixel_aspect_x, render.pixel_aspect_y),
        camera_to_world=np.array(obj.matrix_world, dtype=np.float64),
    )  # fmt: skip


def add_camera(model: CameraModel, name: str = "Camera",
               scene: bpy.types.Scene | None = None) -> bpy.types.Object:  # fmt: skip
    """A new camera object set up as ``model`` (render size and pixel aspect too), made the
    scene's camera."""
    scene = scene or bpy.context.scene
    data = bpy.data.cameras.new(name)
    data.lens, data.sensor_width, data.sensor_height = model.lens, model.sensor_width, \
        model.sensor_height
    data.sensor_fit, data.shift_x, data.shift_y = model.sensor_fit, model.shift_x, model.shift_y
    data.clip_start, data.clip_end = 0.05, 200.0
    obj = bpy.data.objects.new(name, data)
    scene.collection.objects.link(obj)
    obj.matrix_world = Matrix([list(row) for row in np.asarray(model.camera_to_world)])
    render = scene.render
    render.resolution_x, render.resolution_y = model.resolution
    render.resolution_percentage = model.percentage
    render.pixel_aspect_x, render.pixel_aspect_y = model.pixel_aspect
    scene.camera = obj
    return obj

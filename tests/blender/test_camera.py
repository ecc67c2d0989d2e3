"""OpenCV intrinsics and extrinsics of Blender cameras (avatar.camera) against Blender's own
projection (bpy_extras.object_utils.world_to_camera_view), for every sensor fit, lens
shifts, non-square pixels and resolution percentages."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

CASES = list(itertools.product(
    ("AUTO", "HORIZONTAL", "VERTICAL"),
    ((640, 480), (480, 640)),
    ((0.0, 0.0), (0.1, -0.07)),
    ((1.0, 1.0), (1.0, 1.3), (1.4, 1.0)),
    (100, 50),
))  # fmt: skip


@pytest.fixture
def render_settings():
    """Put back the render size, percentage and pixel aspect the test changes (later tests
    of the same process frame their cameras with them)."""
    import bpy

    r = bpy.context.scene.render
    saved = (r.resolution_x, r.resolution_y, r.resolution_percentage, r.pixel_aspect_x,
             r.pixel_aspect_y)  # fmt: skip
    yield
    (r.resolution_x, r.resolution_y, r.resolution_percentage, r.pixel_aspect_x,
     r.pixel_aspect_y) = saved  # fmt: skip


@pytest.mark.parametrize(("fit", "resolution", "shift", "aspect", "percentage"), CASES)
def test_projection_matches_blender(empty_scene, render_settings, rng, fit, resolution, shift,
                                    aspect, percentage):  # fmt: skip
    import bpy
    from bpy_extras.object_utils import world_to_camera_view
    from mathutils import Vector

    from avatar import camera
    from avatar.blender.camera import add_camera, camera_model

    model = camera.CameraModel(
        lens=42.0, sensor_width=36.0, sensor_height=24.0, sensor_fit=fit, shift_x=shift[0],
        shift_y=shift[1], resolution=resolution, percentage=percentage, pixel_aspect=aspect,
        camera_to_world=camera.look_at([1.5, -4.0, 1.7], [0.1, 0.2, 0.9], roll=0.2),
    )  # fmt: skip
    scene = bpy.context.scene
    obj = add_camera(model, scene=scene)
    read = camera_model(obj, scene)
    np.testing.assert_allclose(read.camera_to_world, model.camera_to_world, atol=1e-6)
    K, w2c = camera.intrinsics(read), camera.world_to_camera(read)
    width, height = read.size
    points = rng.uniform([-0.6, -0.6, 0.2], [0.8, 0.9, 1.8], (50, 3))
    got = camera.project(points, K, w2c)
    for p, (u, v, z) in zip(points, got, strict=True):
        ndc = world_to_camera_view(scene, obj, Vector(p))
        assert u == pytest.approx(ndc.x * width - 0.5, abs=1e-3)
        assert v == pytest.approx((1.0 - ndc.y) * height - 0.5, abs=1e-3)
        assert z == pytest.approx(ndc.z, abs=1e-6)
    # unproject inverts project at pixel centres
    depth = np.full((height, width), np.inf)
    iu, iv = np.clip(np.round(got[:5, :2]).astype(int), 0, [width - 1, height - 1]).T
    depth[iv, iu] = got[:5, 2]
    back = camera.unproject(depth, K, w2c)[iv, iu]
    again = camera.project(back, K, w2c)
    np.testing.assert_allclose(again[:, :2], np.stack([iu, iv], 1), atol=1e-6)

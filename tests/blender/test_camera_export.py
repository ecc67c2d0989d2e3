"""Camera export: the JSON's K and world_to_camera (OpenCV axes) project world points where
Blender's own ``world_to_camera_view`` puts them, for sensor fits, lens shifts, pixel
aspects and resolution percentages; bad requests fail in one line and write nothing."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

CASES = list(itertools.product(
    ("AUTO", "HORIZONTAL", "VERTICAL"),
    ((0.0, 0.0), (0.12, -0.05)),
    ((1.0, 1.0), (1.0, 1.25)),
    (100, 35),
))  # fmt: skip


@pytest.fixture
def render_settings():
    import bpy

    r = bpy.context.scene.render
    saved = (r.resolution_x, r.resolution_y, r.resolution_percentage, r.pixel_aspect_x,
             r.pixel_aspect_y)  # fmt: skip
    yield
    (r.resolution_x, r.resolution_y, r.resolution_percentage, r.pixel_aspect_x,
     r.pixel_aspect_y) = saved  # fmt: skip


def _camera(fit, shift, aspect, percentage):
    import bpy
    from mathutils import Matrix

    from avatar import camera

    scene = bpy.context.scene
    data = bpy.data.cameras.new("Cam")
    data.lens, data.sensor_width, data.sensor_height = 35.0, 36.0, 24.0
    data.sensor_fit, data.shift_x, data.shift_y = fit, *shift
    obj = bpy.data.objects.new("Cam", data)
    scene.collection.objects.link(obj)
    obj.matrix_world = Matrix(camera.look_at([2.0, -5.0, 1.4], [0.2, 0.1, 0.9], roll=0.1))
    r = scene.render
    r.resolution_x, r.resolution_y, r.resolution_percentage = 720, 540, percentage
    r.pixel_aspect_x, r.pixel_aspect_y = aspect
    return obj


@pytest.mark.parametrize(("fit", "shift", "aspect", "percentage"), CASES)
def test_json_projects_like_blender(empty_scene, render_settings, rng, tmp_path, fit, shift,
                                    aspect, percentage):  # fmt: skip
    import bpy
    from bpy_extras.object_utils import world_to_camera_view
    from mathutils import Vector

    from avatar.blender import export

    scene = bpy.context.scene
    obj = _camera(fit, shift, aspect, percentage)
    scene.camera = obj
    path = export.export_camera(tmp_path / "cam")  # the scene's camera; .json added
    assert path.name == "cam.json"
    record = json.loads(path.read_text())
    K, w2c = np.array(record["K"]), np.array(record["world_to_camera"])
    width, height = record["width"], record["height"]
    assert (width, height) == (720 * percentage // 100, 540 * percentage // 100)
    np.testing.assert_allclose(np.array(record["R"]), w2c[:3, :3])
    np.testing.assert_allclose(w2c @ np.array(record["camera_to_world"]), np.eye(4), atol=1e-9)
    points = rng.uniform([-0.8, -0.5, 0.0], [0.8, 0.7, 1.9], (12, 3))
    cam = points @ w2c[:3, :3].T + w2c[:3, 3]
    assert np.all(cam[:, 2] > 0)  # OpenCV: z forward
    uv = (cam @ K.T)[:, :2] / cam[:, 2:]
    for p, (u, v) in zip(points, uv, strict=True):
        ndc = world_to_camera_view(scene, obj, Vector(p))
        assert u == pytest.approx(ndc.x * width - 0.5, abs=1e-3)
        assert v == pytest.approx((1.0 - ndc.y) * height - 0.5, abs=1e-3)


def test_bad_requests(empty_scene, tmp_path):
    import bpy

    from avatar.blender import export
    from avatar.errors import AvatarError

    bpy.context.scene.camera = None
    with pytest.raises(AvatarError, match="no camera"):
        export.export_camera(tmp_path / "a.json")
    obj = _camera("AUTO", (0.0, 0.0), (1.0, 1.0), 100)
    obj.data.type = "ORTHO"
    with pytest.raises(AvatarError, match="perspective"):
        export.export_camera(tmp_path / "a.json", obj)
    obj.data.type = "PERSP"
    (tmp_path / "file").write_text("x")
    for bad in (tmp_path / "file" / "a.json", "/proc/avatar-camera/a.json"):
        with pytest.raises(AvatarError) as raised:
            export.export_camera(bad, obj)
        assert "\n" not in str(raised.value)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]

"""Camera conventions of the dataset: intrinsics ``K`` and ``world_to_camera`` in OpenCV axes.

OpenCV axes: x right, y down, z forward (into the scene); pixel (u, v) = (0, 0) is the
*centre* of the top-left pixel, u grows right, v grows down. A world point X (metres, Avatar's
frame: Z up) projects as ``x = world_to_camera @ [X, 1]``, ``[u, v, 1] ~ K @ x[:3]``.

Blender's camera looks down its local -Z with +Y up; its image spans ``[0, W] x [0, H]`` with
pixel centres at ``i + 0.5``. ``intrinsics`` follows Blender's own rules (``sensor_fit``
AUTO/HORIZONTAL/VERTICAL, lens shift, non-square pixels, ``resolution_percentage``), checked
against ``bpy_extras.object_utils.world_to_camera_view`` in tests/blender/test_camera.py.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# Blender camera axes (x right, y up, z backward) -> OpenCV (x right, y down, z forward).
BLENDER_TO_OPENCV = np.diag([1.0, -1.0, -1.0, 1.0])


@dataclass(frozen=True)
class CameraModel:
    """Everything of a Blender perspective camera that decides where a point lands.

    lens, sensor_width, sensor_height: mm. sensor_fit: "AUTO", "HORIZONTAL" or "VERTICAL".
    shift_x, shift_y: lens shift in units of the larger image side (Blender's).
    resolution: (x, y) pixels before ``percentage``; pixel_aspect: (x, y).
    camera_to_world: (4, 4) the camera object's world matrix (Blender axes).
    """

    lens: float
    sensor_width: float
    sensor_height: float
    sensor_fit: str
    shift_x: float
    shift_y: float
    resolution: tuple[int, int]
    percentage: int
    pixel_aspect: tuple[float, float]
    camera_to_world: np.ndarray

    @property
    def size(self) -> tuple[int, int]:
        """(W, H) pixels of the rendered image (after ``percentage``, as Blender rounds)."""
        x, y = self.resolution
        return int(x * self.percentage / 100), int(y * self.percentage / 100)


def intrinsics(cam: CameraModel) -> np.ndarray:
    """(3, 3) float64 K in pixels, OpenCV convention (see module docstring)."""
    width, height = cam.size
    ax, ay = cam.pixel_aspect
    fit = cam.sensor_fit
    if fit == "AUTO":
        fit = "HORIZONTAL" if width * ax >= height * ay else "VERTICAL"
    sensor = cam.sensor_height if cam.sensor_fit == "VERTICAL" else cam.sensor_width
    aspect = ay / ax
    view = width if fit == "HORIZONTAL" else aspect * height  # pixels the sensor spans
    fx = cam.lens / sensor * view
    fy = fx / aspect
    cx = width / 2.0 - cam.shift_x * view - 0.5
    cy = height / 2.0 + cam.shift_y * view / aspect - 0.5
    return np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])


def world_to_camera(cam: CameraModel) -> np.ndarray:
    """(4, 4) float64 rigid transform from world (metres, Z up) to OpenCV camera axes."""
    return BLENDER_TO_OPENCV @ np.linalg.inv(np.asarray(cam.camera_to_world, dtype=np.float64))


def project(points: np.ndarray, K: np.ndarray, world_to_cam: np.ndarray) -> np.ndarray:
    """(N, 3) world points -> (N, 3) (u, v, z): pixels (OpenCV) and depth along the optical
    axis in metres (planar z, what the depth map stores)."""
    p = np.asarray(points, dtype=np.float64)
    cam = p @ world_to_cam[:3, :3].T + world_to_cam[:3, 3]
    z = cam[:, 2]
    uv = (cam @ K.T)[:, :2] / np.where(np.abs(z) > 1e-12, z, 1e-12)[:, None]
    return np.concatenate([uv, z[:, None]], axis=1)


def unproject(depth: np.ndarray, K: np.ndarray, world_to_cam: np.ndarray) -> np.ndarray:
    """(H, W) planar depth (metres; inf/0 where nothing) -> (H, W, 3) world points (NaN where
    nothing): the inverse of ``project`` at every pixel centre."""
    h, w = depth.shape
    v, u = np.mgrid[0:h, 0:w].astype(np.float64)
    z = np.where(np.isfinite(depth) & (depth > 0), depth, np.nan)
    x = (u - K[0, 2]) / K[0, 0] * z
    y = (v - K[1, 2]) / K[1, 1] * z
    cam = np.stack([x, y, z], axis=-1)
    to_world = np.linalg.inv(world_to_cam)
    return cam @ to_world[:3, :3].T + to_world[:3, 3]


def look_at(eye: np.ndarray, target: np.ndarray, roll: float = 0.0) -> np.ndarray:
    """(4, 4) a Blender camera's world matrix at ``eye`` looking at ``target`` with world Z
    up in the image (``roll`` radians about the view axis)."""
    eye, target = np.asarray(eye, dtype=np.float64), np.asarray(target, dtype=np.float64)
    back = eye - target
    back /= np.linalg.norm(back)  # Blender's camera looks down -Z: +Z points back
    right = np.cross([0.0, 0.0, 1.0], back)
    if np.linalg.norm(right) < 1e-9:  # looking straight up or down
        right = np.array([1.0, 0.0, 0.0])
    right /= np.linalg.norm(right)
    up = np.cross(back, right)
    c, s = np.cos(roll), np.sin(roll)
    right, up = c * right + s * up, -s * right + c * up
    out = np.eye(4)
    out[:3, 0], out[:3, 1], out[:3, 2], out[:3, 3] = right, up, back, eye
    return out

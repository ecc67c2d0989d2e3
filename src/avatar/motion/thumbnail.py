"""Small pictures of a body in a pose, drawn with numpy (no renderer needed): the pose
library's thumbnails.

    image = thumbnail.picture(human.body, human.pose("t-pose"), size=96)   # (96, 96, 4) uint8

The skin is posed by linear blend skinning and seen from the front (the camera on -Y
looking at the body, Z up), orthographic, framed on a fixed 2 m square so that poses
compare at one scale (a sitting body sits low, arms out reach the sides). Each face is
drawn at its corners, edge midpoints and centre into a z-buffer at twice the size, shaded
by its normal under a key light from the upper left, then averaged down (anti-aliased);
the background is transparent.
"""

from __future__ import annotations

import numpy as np

from avatar.body.shaped import PART_GROUPS, Body
from avatar.geometry.splat import splat
from avatar.rig import kinematics, skinning
from avatar.rig.skeleton import Animation

FRAME_M = 2.0  # metres of the world the picture spans, across and up
_COLOUR = np.array([0.80, 0.62, 0.52])  # a neutral skin tone
_LIGHT = np.array([-0.45, -0.75, 0.5]) / np.linalg.norm([-0.45, -0.75, 0.5])
_AMBIENT = 0.35
_SUPER = 2  # supersampling factor


def picture(body: Body, pose: Animation, size: int = 96, frame: int = 0) -> np.ndarray:
    """(size, size, 4) uint8 RGBA picture of ``body`` in ``pose`` (frame ``frame``).

    body: the shaped body on its rig (``Human.body``); pose: an Animation on that rig
    (``Human.pose(name)``, (1, J)). Row 0 is the top of the picture.
    """
    world = kinematics.forward(body.skeleton, pose.rotations[frame], pose.translations[frame])
    matrices = kinematics.skinning_matrices(body.skeleton, world)
    posed = skinning.linear_blend(body.vertices, body.weights, matrices).astype(np.float64)
    quads = _skin_faces(body)
    points, shade = _surface_points(posed, quads)
    return _draw(points, shade, size)


def _skin_faces(body: Body) -> np.ndarray:
    """(F, 4) the skin's quads (no eyes, teeth or helper geometry)."""
    base = body.model.base
    groups = [base.face_groups[g] for g in PART_GROUPS["body"]]
    return base.faces[np.concatenate(groups)]


def _surface_points(vertices: np.ndarray, quads: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(N, 3) points covering the quads (corners, edge midpoints, centres) and (N,) their
    face's brightness in [0, 1]."""
    corners = vertices[quads]  # (F, 4, 3)
    normal = np.cross(corners[:, 2] - corners[:, 0], corners[:, 3] - corners[:, 1])
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-12)
    light = np.clip(normal @ _LIGHT, 0.0, 1.0)
    brightness = _AMBIENT + (1.0 - _AMBIENT) * light
    mids = (corners + np.roll(corners, -1, axis=1)) / 2
    centre = corners.mean(axis=1, keepdims=True)
    quarter = (corners + centre) / 2  # halfway in from each corner: fills large faces
    points = np.concatenate([corners, mids, centre, quarter], axis=1)  # (F, 13, 3)
    shade = np.repeat(brightness, points.shape[1])
    return points.reshape(-1, 3), shade


def _draw(points: np.ndarray, shade: np.ndarray, size: int) -> np.ndarray:
    """Z-buffered splat of ``points`` seen from -Y into a (size, size, 4) uint8 picture."""
    big = size * _SUPER
    scale = big / FRAME_M
    centre_x = 0.5 * (points[:, 0].min() + points[:, 0].max())
    col = np.floor((points[:, 0] - centre_x) * scale + big / 2).astype(np.int64)
    row = np.floor(big - 1 - (points[:, 2] + 0.05) * scale).astype(np.int64)  # floor at bottom
    rgba = np.concatenate([shade[:, None] * _COLOUR, np.ones((len(shade), 1))], axis=1)
    out = splat(col, row, points[:, 1], rgba, size, _SUPER)  # nearer the camera: smaller y
    return np.round(out * 255).astype(np.uint8)

"""Per-person annotations of a rendered sample: 2D/3D joints, COCO-17 keypoints with COCO
visibility, boxes and masks, from the posed geometry and the label images. numpy only.

COCO visibility, decided by a depth test against the rendered depth: 0 outside the image (or
behind the camera; COCO writes x = y = 0 then), 1 occluded, 2 visible. A point is visible
when the first surface its pixel sees is no nearer than the point's own skin: rendered depth
>= z - (its depth under the skin) - ``TOLERANCE``. Another body part, garment or person in
front makes it occluded; the person's own clothes over it do not (annotators label a
shoulder under a shirt as visible).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from avatar.camera import project
from avatar.dataset.people import PosedPerson

TOLERANCE = 0.03  # m: the skin-depth test's slack (garments, rounding, a pixel's footprint)
GARMENT_SLACK = 0.04  # m: a person's own garments are this thick at most over the skin


def instance_id(person: int, item: int) -> int:
    """The object id of item ``item`` (0 = body and eyes, 1.. = garments in wearing order) of
    person ``person`` (0-based): person * 100 + item + 1, so 0 stays the background."""
    return person * 100 + item + 1


def person_of(instance: np.ndarray) -> np.ndarray:
    """(...) person index (0-based) of instance ids, -1 for the background."""
    return np.where(instance > 0, (instance.astype(np.int64) - 1) // 100, -1)


def annotate(people: Sequence[PosedPerson], instance: np.ndarray, depth: np.ndarray,
             K: np.ndarray, world_to_cam: np.ndarray) -> list[dict]:  # fmt: skip
    """One record per person: ``keypoints`` (17, 3) [u, v, visibility] (COCO order),
    ``joints_2d`` (J, 3) [u, v, z] and ``joints_3d`` (J, 3) world metres of the rig,
    ``joints_3d_camera`` (J, 3) in the camera frame, ``bbox`` [x, y, w, h] of its visible
    pixels (None when none), ``mask`` (H, W) bool (all its items), ``area``."""
    owner = person_of(instance)
    out = []
    for p, person in enumerate(people):
        mask = owner == p
        keypoints = _keypoints(person, depth, K, world_to_cam)
        joints = project(person.joints, K, world_to_cam)
        cam = person.joints @ world_to_cam[:3, :3].T + world_to_cam[:3, 3]
        out.append({
            "keypoints": keypoints, "joints_2d": joints, "joints_3d": person.joints,
            "joints_3d_camera": cam, "bbox": _bbox(mask), "mask": mask,
            "area": int(mask.sum()),
        })  # fmt: skip
    return out


def _keypoints(person: PosedPerson, depth: np.ndarray, K: np.ndarray,
               world_to_cam: np.ndarray) -> np.ndarray:  # fmt: skip
    h, w = depth.shape
    uvz = project(person.keypoints, K, world_to_cam)
    out = np.zeros((len(uvz), 3), np.float64)
    for k, (u, v, z) in enumerate(uvz):
        col, row = int(np.floor(u + 0.5)), int(np.floor(v + 0.5))  # pixel whose centre is nearest
        if z <= 0 or not (0 <= col < w and 0 <= row < h):
            continue  # outside the image: (0, 0, 0) as COCO writes it
        seen = depth[row, col]
        front = z - float(person.keypoint_depth[k]) - GARMENT_SLACK - TOLERANCE
        visible = np.isfinite(seen) and seen >= front
        out[k] = (u, v, 2 if visible else 1)
    return out


def _bbox(mask: np.ndarray) -> list[float] | None:
    """[x, y, width, height] in pixels (COCO: x, y of the top-left corner of the top-left
    pixel) of a mask's pixels, or None."""
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    if len(rows) == 0:
        return None
    return [float(cols[0]), float(rows[0]), float(cols[-1] - cols[0] + 1),
            float(rows[-1] - rows[0] + 1)]  # fmt: skip

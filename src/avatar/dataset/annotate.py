"""Per-person annotations of a rendered sample: 2D/3D joints, COCO-17 keypoints with COCO
visibility, boxes and masks, from the posed geometry and the label images. numpy only.

COCO visibility, decided by a depth test against the rendered depth: 0 outside the image (or
behind the camera; COCO writes x = y = 0 then), 1 occluded, 2 visible. A point is visible
when, at its pixel (or one next to it, for points on a silhouette), the first surface seen
(1) belongs to this person, (2) is the body part the point belongs to, or one it joins
(a knee: upper or lower leg; the part map labels clothes by the skin under them), and (3)
is no nearer than the point's own skin: rendered depth >= z - (its depth under the skin) -
``TOLERANCE``, with ``GARMENT_SLACK`` more where the surface is one of the person's own
garments (a loose skirt stands off the knee). Another person, or another of the person's
own parts (an arm across the hips), in front makes it occluded; the person's own clothes
over it do not (annotators label a knee under trousers as visible).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from avatar.camera import project
from avatar.dataset.people import COCO_KEYPOINTS, PARTS, PosedPerson

TOLERANCE = 0.03  # m: the skin-depth test's slack (rounding, a pixel's footprint)
GARMENT_SLACK = 0.25  # m: how far a person's own garment may stand off the skin (skirts)
_SIDE = {"left": "l", "right": "r"}


def _allowed_parts(name: str) -> set[int]:
    """Part ids (1-based, ``PARTS``) a keypoint's pixel may show for it to count as seen."""
    side, _, joint = name.partition("_")
    s = _SIDE.get(side, "")
    names = {
        "nose": {"head"}, "eye": {"head"}, "ear": {"head"},
        "shoulder": {"torso", "neck", f"upper_arm_{s}"},
        "elbow": {f"upper_arm_{s}", f"lower_arm_{s}"},
        "wrist": {f"lower_arm_{s}", f"hand_{s}"}, "hip": {"torso", f"upper_leg_{s}"},
        "knee": {f"upper_leg_{s}", f"lower_leg_{s}"}, "ankle": {f"lower_leg_{s}", f"foot_{s}"},
    }[joint or side]  # fmt: skip
    return {PARTS.index(n) + 1 for n in names}


def instance_id(person: int, item: int) -> int:
    """The object id of item ``item`` (0 = body and eyes, 1.. = garments in wearing order) of
    person ``person`` (0-based): person * 100 + item + 1, so 0 stays the background."""
    return person * 100 + item + 1


def person_of(instance: np.ndarray) -> np.ndarray:
    """(...) person index (0-based) of instance ids, -1 for the background."""
    return np.where(instance > 0, (instance.astype(np.int64) - 1) // 100, -1)


def annotate(people: Sequence[PosedPerson], instance: np.ndarray, depth: np.ndarray,
             parts: np.ndarray, K: np.ndarray, world_to_cam: np.ndarray) -> list[dict]:  # fmt: skip
    """One record per person: ``keypoints`` (17, 3) [u, v, visibility] (COCO order),
    ``joints_2d`` (J, 3) [u, v, z] and ``joints_3d`` (J, 3) world metres of the rig,
    ``joints_3d_camera`` (J, 3) in the camera frame, ``bbox`` [x, y, w, h] of its visible
    pixels (None when none), ``mask`` (H, W) bool (all its items), ``area``."""
    owner = person_of(instance)
    out = []
    for p, person in enumerate(people):
        mask = owner == p
        keypoints = _keypoints(p, person, instance, depth, parts, K, world_to_cam)
        joints = project(person.joints, K, world_to_cam)
        cam = person.joints @ world_to_cam[:3, :3].T + world_to_cam[:3, 3]
        out.append({
            "keypoints": keypoints, "joints_2d": joints, "joints_3d": person.joints,
            "joints_3d_camera": cam, "bbox": _bbox(mask), "mask": mask,
            "area": int(mask.sum()),
        })  # fmt: skip
    return out


def _keypoints(p: int, person: PosedPerson, instance: np.ndarray, depth: np.ndarray,
               parts: np.ndarray, K: np.ndarray,
               world_to_cam: np.ndarray) -> np.ndarray:  # fmt: skip
    h, w = depth.shape
    uvz = project(person.keypoints, K, world_to_cam)
    out = np.zeros((len(uvz), 3), np.float64)
    for k, (u, v, z) in enumerate(uvz):
        col, row = int(np.floor(u + 0.5)), int(np.floor(v + 0.5))  # pixel whose centre is nearest
        if z <= 0 or not (0 <= col < w and 0 <= row < h):
            continue  # outside the image: (0, 0, 0) as COCO writes it
        window = (slice(max(row - 1, 0), row + 2), slice(max(col - 1, 0), col + 2))
        ident = instance[window].astype(np.int64)
        mine = person_of(instance[window]) == p
        garment = mine & ((ident - 1) % 100 > 0)
        front = z - float(person.keypoint_depth[k]) - TOLERANCE - np.where(garment,
                                                                           GARMENT_SLACK, 0.0)
        allowed = np.isin(parts[window], list(_allowed_parts(COCO_KEYPOINTS[k])))
        seen = mine & allowed & np.isfinite(depth[window]) & (depth[window] >= front)
        out[k] = (u, v, 2 if seen.any() else 1)
    return out


def _bbox(mask: np.ndarray) -> list[float] | None:
    """[x, y, width, height] in pixels (COCO: x, y of the top-left corner of the top-left
    pixel) of a mask's pixels, or None."""
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    if len(rows) == 0:
        return None
    return [float(cols[0]), float(rows[0]), float(cols[-1] - cols[0] + 1),
            float(rows[-1] - rows[0] + 1)]  # fmt: skip

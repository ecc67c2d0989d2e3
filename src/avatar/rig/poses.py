"""Static poses: MPFB's T-pose files and poses as bone-name -> rotation maps."""

from __future__ import annotations

import numpy as np

from avatar.errors import unknown_name
from avatar.rig import quaternion
from avatar.rig.skeleton import Animation, Skeleton

# MPFB stores pose-bone Euler angles in Blender's default rotation mode.
EULER_ORDER = "XYZ"


def rest_pose(skeleton: Skeleton) -> Animation:
    """A one-frame animation holding the rest pose (identity rotations)."""
    j = len(skeleton.names)
    rot = np.zeros((1, j, 4))
    rot[..., 0] = 1.0
    return Animation(rot, np.zeros((1, j, 3)), 24.0, skeleton.names)


def from_euler_map(
    skeleton: Skeleton,
    rotations: dict[str, list[float]],
    translations: dict[str, list[float]] | None = None,
) -> Animation:
    """A one-frame pose from {bone: Euler XYZ radians} (bones not in the rig are skipped)."""
    pose = rest_pose(skeleton)
    rot, trans = pose.rotations.copy(), pose.translations.copy()
    index = {n: i for i, n in enumerate(skeleton.names)}
    for bone, euler in rotations.items():
        if bone in index:
            rot[0, index[bone]] = quaternion.from_euler(np.asarray(euler), EULER_ORDER)
    for bone, t in (translations or {}).items():
        if bone in index:
            trans[0, index[bone]] = t
    return Animation(rot, trans, pose.fps, skeleton.names)


def named_pose(skeleton: Skeleton, rig: str, name: str, poses: dict[str, dict]) -> Animation:
    """A named pose of the asset library ("rest", "a-pose" or "t-pose") for ``rig``."""
    if name in ("rest", "a-pose"):  # MakeHuman rigs rest in an A-pose
        return rest_pose(skeleton)
    library = poses.get(rig) or poses.get("default", {})
    if name not in library:
        raise unknown_name("pose", name, ["rest", "a-pose", *library])
    data = library[name]
    return from_euler_map(skeleton, data["bone_rotations"], data.get("bone_translations"))

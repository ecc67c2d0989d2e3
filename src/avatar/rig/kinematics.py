"""Forward kinematics: pose-bone rotations -> world bone rotations/heads and skinning matrices.

The hierarchy is walked level by level (all bones of one depth at once). ``world_pose``
keeps world rotations as quaternions (a (T, J, 4) product is a few array operations, much
cheaper than stacks of tiny matrix products); ``forward`` gives Blender's 4x4 matrices.
"""

from __future__ import annotations

import numpy as np

from avatar.rig import quaternion
from avatar.rig.skeleton import Skeleton


def levels(parents: np.ndarray, which: np.ndarray | None = None) -> list[np.ndarray]:
    """Bone indices grouped by depth (roots first), each group (n,) int.

    which: (J,) bool, keep only these bones (their parents are either kept too, in an
    earlier group, or are expected to be evaluated already).
    """
    depth = np.zeros(len(parents), dtype=int)
    for j, p in enumerate(parents):  # parents precede children
        depth[j] = 0 if p < 0 else depth[p] + 1
    keep = np.ones(len(parents), dtype=bool) if which is None else which
    return [g for d in range(int(depth.max(initial=0)) + 1)
            if len(g := np.flatnonzero(keep & (depth == d)))]  # fmt: skip


def rest_quaternions(skeleton: Skeleton) -> tuple[np.ndarray, np.ndarray]:
    """(J, 4) rest rotations and (J, 4) rotations relative to the parent's rest frame."""
    rest = quaternion.from_matrix(skeleton.rest[:, :3, :3])
    return rest, quaternion.from_matrix(skeleton.local_rest()[:, :3, :3])


def world_pose(
    skeleton: Skeleton, rotations: np.ndarray, translations: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """World bone rotations and heads for a pose (Blender's pose-bone evaluation).

    rotations: (..., J, 4) quaternions in each bone's rest frame (normalised here).
    translations: (..., J, 3) pose locations in each bone's rest frame, or None.
    Returns (..., J, 4) world rotations (bone frame -> world) and (..., J, 3) heads (metres).
    """
    local_rest = skeleton.local_rest()
    step_rest = local_rest[:, :3, 3]  # head in the parent's frame
    turn_rest = quaternion.from_matrix(local_rest[:, :3, :3])
    rotations = rotations / np.linalg.norm(rotations, axis=-1, keepdims=True)
    local = quaternion.multiply(turn_rest, rotations)
    step = np.broadcast_to(step_rest, rotations.shape[:-1] + (3,))
    if translations is not None:
        moved = np.flatnonzero(np.any(translations != 0, axis=tuple(range(translations.ndim - 2))
                                      + (-1,)))  # fmt: skip
        if len(moved):
            step = step.copy()
            step[..., moved, :] += quaternion.rotate(turn_rest[moved], translations[..., moved, :])
    rot = np.empty(rotations.shape)
    pos = np.empty(rotations.shape[:-1] + (3,))
    parents = skeleton.parents
    for group in levels(parents):
        p = parents[group]
        if p[0] < 0:  # roots (depth 0)
            rot[..., group, :], pos[..., group, :] = local[..., group, :], step[..., group, :]
            continue
        parent_rot = rot[..., p, :]
        rot[..., group, :] = quaternion.multiply(parent_rot, local[..., group, :])
        pos[..., group, :] = pos[..., p, :] + quaternion.rotate(parent_rot, step[..., group, :])
    return rot, pos


def pose_matrices(rotations: np.ndarray, translations: np.ndarray | None = None) -> np.ndarray:
    """(..., J, 4) quaternions and (..., J, 3) locations -> (..., J, 4, 4) basis matrices."""
    out = np.zeros(rotations.shape[:-1] + (4, 4))
    out[..., :3, :3] = quaternion.to_matrix(rotations)
    if translations is not None:
        out[..., :3, 3] = translations
    out[..., 3, 3] = 1.0
    return out


def forward(
    skeleton: Skeleton, rotations: np.ndarray, translations: np.ndarray | None = None
) -> np.ndarray:
    """World bone matrices for a pose, exactly as Blender evaluates pose bones.

    world[j] = world[parent] @ local_rest[j] @ basis[j], basis = T(location) R(rotation).

    rotations: (..., J, 4) quaternions in each bone's rest frame.
    translations: (..., J, 3) pose locations in each bone's rest frame, or None.
    Returns (..., J, 4, 4) float64 bone-to-world matrices (metres).
    """
    local = skeleton.local_rest() @ pose_matrices(rotations, translations)
    world = np.empty_like(local)
    parents = skeleton.parents
    for group in levels(parents):
        p = parents[group]
        if p[0] < 0:
            world[..., group, :, :] = local[..., group, :, :]
        else:
            world[..., group, :, :] = world[..., p, :, :] @ local[..., group, :, :]
    return world


def skinning_matrices(skeleton: Skeleton, world: np.ndarray) -> np.ndarray:
    """(..., J, 4, 4) matrices taking rest-pose vertices to posed ones: world @ inv(rest)."""
    return world @ np.linalg.inv(skeleton.rest)

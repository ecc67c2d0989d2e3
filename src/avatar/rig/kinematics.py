"""Forward kinematics: pose-bone rotations -> world bone matrices and skinning matrices."""

from __future__ import annotations

import numpy as np

from avatar.rig import quaternion
from avatar.rig.skeleton import Skeleton


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
    basis = pose_matrices(rotations, translations)
    local = skeleton.local_rest() @ basis
    world = np.empty_like(local)
    for j, p in enumerate(skeleton.parents):
        world[..., j, :, :] = local[..., j, :, :] if p < 0 else world[..., p, :, :] @ local[..., j, :, :]
    return world


def skinning_matrices(skeleton: Skeleton, world: np.ndarray) -> np.ndarray:
    """(..., J, 4, 4) matrices taking rest-pose vertices to posed ones: world @ inv(rest)."""
    return world @ np.linalg.inv(skeleton.rest)

"""Forward kinematics: pose-bone rotations -> world bone rotations/heads and skinning matrices.

The hierarchy is walked level by level (all bones of one depth at once). ``world_pose``
keeps world rotations as quaternions (a (T, J, 4) product is a few array operations, much
cheaper than stacks of tiny matrix products); ``forward`` gives Blender's 4x4 matrices.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

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
    return rest, _local_rest(skeleton, rest)[0]


def _local_rest(skeleton: Skeleton, rest: np.ndarray | None = None):
    """(J, 4) rest rotations relative to the parent's and (J, 3) heads in the parent's
    rest frame (rigid rest frames: the inverse is the conjugate, no LAPACK call)."""
    if rest is None:
        rest = quaternion.from_matrix(skeleton.rest[:, :3, :3])
    parents = skeleton.parents
    has = parents >= 0
    local = rest.copy()
    step = skeleton.heads.copy()
    inverse = quaternion.conjugate(rest[parents[has]])
    local[has] = quaternion.multiply(inverse, rest[has])
    step[has] = quaternion.rotate(inverse, skeleton.heads[has] - skeleton.heads[parents[has]])
    return local, step


def world_pose(
    skeleton: Skeleton,
    rotations: np.ndarray,
    translations: np.ndarray | None = None,
    *,
    bones_first: bool = False,
    dtype: npt.DTypeLike = np.float64,
) -> tuple[np.ndarray, np.ndarray]:
    """World bone rotations and heads for a pose (Blender's pose-bone evaluation).

    rotations: (..., J, 4) unit quaternions in each bone's rest frame.
    translations: (..., J, 3) pose locations in each bone's rest frame, or None.
    bones_first: return the bone axis first, (J, ..., 4) and (J, ..., 3): the layout in
        which per-bone gathers over many frames are contiguous (what motion work wants).
    dtype: of the rotations (float32 halves memory traffic on long clips; rotations then
        carry errors of about 1e-5 degrees). Heads are float64 whatever it is: they add up
        along the hierarchy and may be far from the origin.
    Returns (..., J, 4) world rotations (bone frame -> world) and (..., J, 3) heads (metres).
    """
    rest_rot, rest_step = _local_rest(skeleton)
    rest_rot = rest_rot.astype(dtype)
    count = len(skeleton.names)
    batch = rotations.shape[:-2]
    rot_in = np.moveaxis(rotations, -2, 0).astype(dtype).reshape(count, -1, 4)  # (J, F, 4)
    local = rot_in @ quaternion.left_matrix(rest_rot)  # rest * rotation, per bone
    moved: dict[int, np.ndarray] = {}  # bone -> (F, 3) head in the parent's frame
    if translations is not None:
        trans = np.moveaxis(translations, -2, 0).reshape(count, -1, 3)
        for j in range(count):
            if np.any(trans[j]):
                moved[j] = rest_step[j] + quaternion.rotate(rest_rot[j], trans[j])
    rot = np.empty(local.shape, dtype)
    pos = np.empty(local.shape[:-1] + (3,))
    parents = skeleton.parents
    for group in levels(parents):
        step = rest_step[group, None]  # (n, 1, 3): the same every frame unless translated
        if any(int(j) in moved for j in group):
            step = np.repeat(step, local.shape[1], axis=1)
            for i, j in enumerate(group):
                step[i] = moved.get(int(j), step[i])
        p = parents[group]
        if p[0] < 0:  # roots (depth 0)
            rot[group], pos[group] = local[group], step
        else:
            parent_rot = rot[p]
            rot[group] = quaternion.multiply(parent_rot, local[group])
            pos[group] = pos[p] + quaternion.rotate(parent_rot, step)
    rot, pos = rot.reshape((count,) + batch + (4,)), pos.reshape((count,) + batch + (3,))
    if bones_first:
        return rot, pos
    return np.moveaxis(rot, 0, -2), np.moveaxis(pos, 0, -2)


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

"""Static poses: MPFB's pose files, poses as bone-name -> rotation maps, and re-expressing
an animation over a different rest pose (``rebase``).

Geometric poses for any rig (T-pose, A-pose) and the pose library are in
``avatar.motion.poselib``; they need bone roles.
"""

from __future__ import annotations

import numpy as np

from avatar.rig import kinematics, quaternion
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


def inverse(pose: Animation) -> Animation:
    """The pose that undoes ``pose`` bone by bone: basis T(t) R(q) -> R(q)^-1 T(-t).

    With ``rebase``: ``rebase(*rebase(skeleton, anim, pose), inverse(pose))`` gives back
    ``skeleton`` and ``anim``. pose: one frame (1, J) or as many frames as needed.
    """
    back = quaternion.conjugate(pose.rotations)
    moved = -quaternion.rotate(back, pose.translations)
    return Animation(back, moved, pose.fps, pose.bone_names)


def rebase(skeleton: Skeleton, animation: Animation, pose: Animation) -> tuple[Skeleton, Animation]:
    """The same motion over a new rest pose: ``pose`` (its first frame) becomes the rest.

    skeleton: (J bones) the rig; animation: (T, J) motion on it; pose: (1, J) the new rest
    (e.g. ``poselib.built_in(skeleton, "t-pose")``).
    Returns the skeleton whose rest matrices and tails are the posed ones, and the motion
    re-expressed on it: every bone's world matrix in every frame is unchanged. Per bone,
    with the pose's basis P = T(p_t) R(p_q): new local rest = old local rest @ P and new
    basis = P^-1 @ old basis, i.e. rotation p_q^-1 q and location p_q^-1 (t - p_t).
    """
    p_q, p_t = pose.rotations[0], pose.translations[0]
    world = kinematics.forward(skeleton, p_q[None], p_t[None])[0]
    tails_local = np.einsum("jab,jb->ja", np.linalg.inv(skeleton.rest)[:, :3, :3],
                            skeleton.tails - skeleton.heads)  # fmt: skip
    tails = world[:, :3, 3] + np.einsum("jab,jb->ja", world[:, :3, :3], tails_local)
    rested = Skeleton(skeleton.names, skeleton.parents, world, tails, dict(skeleton.extra))
    back = quaternion.conjugate(p_q)
    rotations = quaternion.multiply(back, animation.rotations)
    translations = quaternion.rotate(back, animation.translations - p_t)
    return rested, Animation(rotations, translations, animation.fps, animation.bone_names)

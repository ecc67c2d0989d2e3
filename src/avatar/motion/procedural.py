"""Built-in procedural motions, so a character can move with no motion-capture file.

A walk cycle written as joint angles about world axes (sagittal swing of hips, knees,
ankles, shoulders and elbows, pelvis yaw and bob), converted into each bone's rest frame.
The arms first come down from the rig's rest (MakeHuman's A-pose) to hang at the sides;
the elbow's hinge turns with them, so the forearm swings forward, not across the body.
Given the shaped body (``Body``), each arm hangs as close to the side as its skin stays
clear of the torso, with room for clothes on both (heavier bodies hold their arms further
out, as people do).
It drives MakeHuman's default-family rigs (default, default_no_toes, game_engine*) by name;
other rigs receive it through retargeting.
"""

from __future__ import annotations

import numpy as np

from avatar.body.model import BODY_VERTICES
from avatar.body.shaped import Body
from avatar.errors import AvatarError
from avatar.geometry import collision
from avatar.rig import kinematics, quaternion, skinning
from avatar.rig.skeleton import Animation, Skeleton

X, Z = np.array([1.0, 0, 0]), np.array([0, 0, 1.0])

# bone -> (world axis, amplitude deg, phase rad, offset deg, swing of the right side)
WALK = {
    "upperleg01": (X, -24.0, 0.0, 0.0),
    "lowerleg01": (X, 28.0, -1.2, 30.0),
    "foot": (X, 12.0, -0.6, 0.0),
    "upperarm01": (X, 18.0, np.pi, 0.0),
    "lowerarm01": (X, -10.0, np.pi, -12.0),
}
ARM_HANG = 15.0  # deg out from straight down, where the walk's arms hang at the closest
ARM_ROOM = 0.012  # m of air a hanging arm keeps from the torso (a garment on each side)
ARM_BONES = ("upperarm", "lowerarm")  # not the hand: fingers lie within ARM_ROOM of each other
ALIASES = {"upperleg01": ("upperleg01", "thigh"), "lowerleg01": ("lowerleg01", "calf"),
           "foot": ("foot",), "upperarm01": ("upperarm01", "upperarm"),
           "lowerarm01": ("lowerarm01", "lowerarm")}  # fmt: skip


def walk(
    skeleton: Skeleton,
    seconds: float = 2.0,
    fps: float = 30.0,
    cadence: float = 1.0,
    body: Body | None = None,
) -> Animation:
    """A walk of ``seconds`` along -Y at ``cadence`` strides (two steps) per second.

    skeleton: the rig to drive.
    body: the shaped body on that rig (``Human.body``): the arms then hang clear of its own
        torso; without it they hang ARM_HANG degrees out.
    Stride length scales with leg length, so every body walks at its own natural speed.
    """
    t = np.arange(int(round(seconds * fps))) / fps
    phase = 2 * np.pi * cadence * t
    j = len(skeleton.names)
    rot = np.zeros((len(t), j, 4))
    rot[..., 0] = 1.0
    trans = np.zeros((len(t), j, 3))
    for side, sign in ((".L", 0.0), (".R", np.pi)):
        out = ARM_HANG if body is None else _clear_hang(body, side)
        hang = _arm_hang(skeleton, side, out)
        for key, (axis, amp, shift, offset) in WALK.items():
            bone = _find(skeleton, key, side)
            if bone is None:
                continue
            angle = np.radians(offset + amp * np.sin(phase + shift + sign))
            if key == "lowerleg01":  # knees only bend one way
                angle = np.radians(offset * 0.2) + np.maximum(angle - np.radians(offset * 0.8), 0)
            if key == "lowerarm01":  # the hinge as it was before the arm came down
                axis = quaternion.to_matrix(hang).T @ axis
            q = quaternion.from_axis_angle(axis, angle)
            if key == "upperarm01":
                q = quaternion.multiply(q, hang)
            rot[:, bone] = _local(skeleton, bone, q)
    root = int(np.flatnonzero(skeleton.parents < 0)[0])
    legs = _leg_length(skeleton)
    world = np.zeros((len(t), 3))
    world[:, 1] = -1.1 * legs * cadence * t  # a stride (two steps) ~ 1.1 leg lengths
    world[:, 2] = 0.015 * legs * np.cos(2 * phase)
    trans[:, root] = world @ skeleton.rest[root, :3, :3]  # world offset -> root's rest frame
    rot[:, root] = _local(
        skeleton, root, quaternion.from_axis_angle(Z, np.radians(4) * np.sin(phase))
    )
    return Animation(rot, trans, fps, skeleton.names)


def _arm_hang(skeleton: Skeleton, side: str, degrees: float) -> np.ndarray:
    """(4,) the world rotation taking the upper arm from its rest to hanging ``degrees``
    out from straight down (identity without an arm)."""
    shoulder, elbow = _find(skeleton, "upperarm01", side), _find(skeleton, "lowerarm01", side)
    if shoulder is None or elbow is None:
        return np.array([1.0, 0.0, 0.0, 0.0])
    rest = skeleton.heads[elbow] - skeleton.heads[shoulder]
    out = np.sign(rest[0]) * np.sin(np.radians(degrees))
    hang = np.array([out, 0.0, -np.cos(np.radians(degrees))])
    return quaternion.between(rest / np.linalg.norm(rest), hang)


def _clear_hang(body: Body, side: str) -> float:
    """Degrees out from straight down (ARM_HANG..45, in 3-degree steps) at which the arm's
    skin, grown by ARM_ROOM, is first outside the body, posed by linear blend skinning."""
    skeleton, weights = body.skeleton, body.weights
    skin = BODY_VERTICES
    arm = [i for i, n in enumerate(skeleton.names) if n.endswith(side) and n.startswith(ARM_BONES)]
    share = np.isin(weights.indices[:skin], arm) * weights.weights[:skin]
    points = np.flatnonzero(share.sum(axis=1) > 0.95)  # the arm itself, not the shoulder
    shoulder = _find(skeleton, "upperarm01", side)
    if shoulder is None or len(points) == 0:
        return ARM_HANG
    surface = collision.skin_surface(body.faces)
    rot = np.zeros((1, len(skeleton.names), 4))
    rot[..., 0] = 1.0
    for degrees in np.arange(ARM_HANG, 45.0, 3.0):
        rot[0, shoulder] = _local(skeleton, shoulder, _arm_hang(skeleton, side, degrees))
        mats = kinematics.skinning_matrices(skeleton, kinematics.forward(skeleton, rot))[0]
        x = skinning.linear_blend(body.vertices, weights, mats)[:skin]
        grown = x[points] + ARM_ROOM * surface.normals(x)[points]
        if not np.any(collision.winding_number(grown, x, surface.triangles) > 0):
            return float(degrees)
    return 45.0


def _find(skeleton: Skeleton, key: str, side: str) -> int | None:
    for stem in ALIASES[key]:
        for name in (stem + side, stem + "_" + side[1:].lower(), stem + side.lower()):
            if name in skeleton.names:
                return skeleton.names.index(name)
    return None


def _local(skeleton: Skeleton, bone: int, q_world: np.ndarray) -> np.ndarray:
    """A rotation about a world axis through the bone's head, in the bone's rest frame."""
    q_rest = quaternion.from_matrix(skeleton.rest[bone, :3, :3])
    return quaternion.multiply(quaternion.conjugate(q_rest), quaternion.multiply(q_world, q_rest))


def _leg_length(skeleton: Skeleton) -> float:
    thigh = _find(skeleton, "upperleg01", ".L")
    if thigh is None:
        raise AvatarError("the procedural walk needs a MakeHuman-style rig (upperleg01.L, ...)")
    return float(skeleton.heads[thigh, 2] - 0.0)


MOTIONS = {"walk": walk}

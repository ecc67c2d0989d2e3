"""Foot contacts: detect them on the source clip, keep them planted on the target.

A foot joint (ankle or toe) is in contact while it is nearly still (speed below 15% of leg
length per second) for at least 50 ms; floors at any height (steps, boxes) count. While the
toe is down the toe is pinned (heel-off pivots about it), else the ankle. The target's leg
is bent by analytic two-bone IK so the pinned joint stays at its mean position over the
contact (on the floor when it was within a few cm of it), blending in and out over 0.1 s.
The foot keeps its retargeted world orientation.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from avatar.motion import geometry
from avatar.motion.bonemap import BoneMap
from avatar.rig import quaternion
from avatar.rig.skeleton import Skeleton

FOOT_ROLES = ("foot.L", "toe.L", "foot.R", "toe.R")
_SPEED = 0.15  # leg lengths per second
_NEAR_FLOOR = 0.06  # leg lengths: a contact this close to the floor is put on it
_MIN_CONTACT_S = 0.05
_BLEND_S = 0.1
_STRAIGHT = np.sin(np.radians(0.1))  # knee bends below this have no plane of their own
_BACK = np.array([0.0, 1.0, 0.0])  # Avatar characters face -Y: knees bend toward +Y


@dataclass(frozen=True)
class FootContacts:
    """Per side ("L", "R"): which role is pinned each frame ("toe", "foot" or "")."""

    pinned: dict[str, np.ndarray]  # side -> (T,) str array

    def frames(self, side: str) -> np.ndarray:
        return self.pinned[side] != ""


def foot_level(pos: np.ndarray, bmap: BoneMap, roles: tuple[str, ...] = FOOT_ROLES) -> float:
    """Height of the lowest foot joint (of ``roles``) when down: the 5th percentile over
    frames of (T, J, 3) heads ``pos``, metres."""
    idx = [bmap.bones[r] for r in roles if r in bmap.bones]
    if not idx:
        return float(np.percentile(pos[..., 2].min(axis=1), 5))
    return float(np.percentile(pos[:, idx, 2].min(axis=1), 5))


def detect(pos: np.ndarray, bmap: BoneMap, fps: float, leg: float) -> FootContacts:
    """Contacts from source joint paths (T, J, 3); ``leg`` is the source leg length (m)."""
    pinned = {}
    for side in ("L", "R"):
        state = np.full(len(pos), "", dtype="<U4")
        for role in ("foot", "toe"):  # toe last: it wins when both are down
            j = bmap.bones.get(f"{role}.{side}")
            if j is not None:
                still = _still(pos[:, j], fps, leg)
                state[still] = role
        pinned[side] = state
    return FootContacts(pinned)


def _still(path: np.ndarray, fps: float, leg: float) -> np.ndarray:
    """(T,) bool: the joint moves slower than the threshold, in runs long enough."""
    if len(path) < 2:
        return np.zeros(len(path), dtype=bool)
    step = np.linalg.norm(np.diff(path, axis=0), axis=-1) * fps
    speed = np.concatenate([[step[0]], np.maximum(step[:-1], step[1:]), [step[-1]]])
    still = speed < _SPEED * leg
    return _drop_short(still, max(2, int(round(_MIN_CONTACT_S * fps))))


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """[start, stop) of each run of True."""
    edges = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True))


def _drop_short(mask: np.ndarray, length: int) -> np.ndarray:
    out = mask.copy()
    for a, b in _runs(mask):
        if b - a < length:
            out[a:b] = False
    return out


def plant(feet: FootContacts, tmap: BoneMap, target: Skeleton, world: np.ndarray,
          root: np.ndarray, fps: float) -> np.ndarray:  # fmt: skip
    """Bend the target's legs so pinned joints stay put.

    world: (J, T, 4) target world rotations, bone axis first (bones not evaluated: NaN in
    frame 0), changed in place and returned; root: (T, 3) hips heads.
    """
    hips = tmap.bones["hips"]
    legs = [tmap.bones[f"{r}.{s}"] for r in ("thigh", "shin", "foot", "toe") for s in "LR"
            if f"{r}.{s}" in tmap.bones]  # fmt: skip
    pos = geometry.positions(target, world, {hips: root}, geometry.ancestors(target, legs))
    for side in ("L", "R"):
        roles = [f"{r}.{side}" for r in ("thigh", "shin", "foot")]
        if any(r not in tmap.bones for r in roles):
            continue
        goal = _ankle_goals(feet.pinned[side], pos, tmap, side, target, fps)
        if goal is not None:
            thigh, shin, foot = (tmap.bones[r] for r in roles)
            _two_bone_ik(world, pos, target, thigh, shin, foot, goal)
    return world


def _ankle_goals(pinned, pos, tmap: BoneMap, side: str, target: Skeleton, fps: float):
    """(T, 3) where the ankle should be, blended around contacts; pos (J, T, 3)."""
    ankle = tmap.bones[f"foot.{side}"]
    offset = np.zeros((len(pinned), 3))
    weight = np.zeros(len(pinned))
    near_floor = _NEAR_FLOOR * _leg(target, tmap, side)
    for role in ("foot", "toe"):
        j = tmap.bones.get(f"{role}.{side}")
        if j is None:
            continue
        down = pinned == role
        runs = np.array(_runs(down), dtype=int).reshape(-1, 2)
        if not len(runs):
            continue
        # each run's mean position, from running sums (all runs at once)
        total = np.concatenate([np.zeros((1, 3)), np.cumsum(pos[j], axis=0, dtype=np.float64)])
        pin = (total[runs[:, 1]] - total[runs[:, 0]]) / (runs[:, 1] - runs[:, 0])[:, None]
        rest_z = target.heads[j, 2]
        pin[:, 2] = np.where(pin[:, 2] - rest_z < near_floor, rest_z, pin[:, 2])  # on the floor
        offset[down] = np.repeat(pin, runs[:, 1] - runs[:, 0], axis=0) - pos[j, down]
        weight[down] = 1.0
    if not weight.any():
        return None
    offset, weight = _blend(offset, weight, max(1, int(round(_BLEND_S * fps))))
    return pos[ankle] + offset * weight[:, None]


def _blend(offset: np.ndarray, weight: np.ndarray, n: int):
    """Carry each contact's boundary offset into the free frames around it, fading out
    over ``n`` frames (the nearest contact wins; on a tie, the one before)."""
    frames = np.arange(len(weight))
    on = weight > 0
    before = np.maximum.accumulate(np.where(on, frames, -1))  # last contact frame so far
    after = np.minimum.accumulate(np.where(on, frames, len(weight))[::-1])[::-1]
    d_before = np.where(before >= 0, frames - before, len(weight) + n)
    d_after = np.where(after < len(weight), after - frames, len(weight) + n)
    use_before = d_before <= d_after
    gap = np.where(use_before, d_before, d_after)
    near = ~on & (gap <= n)
    out_o, out_w = offset.copy(), weight.copy()
    out_w[near] = 1.0 - gap[near] / (n + 1)
    out_o[near] = offset[np.where(use_before, before, after)[near]]
    return out_o, out_w


def _leg(target: Skeleton, tmap: BoneMap, side: str) -> float:
    h = target.heads[[tmap.bones[f"{r}.{side}"] for r in ("thigh", "shin", "foot")]]
    return float(np.linalg.norm(np.diff(h, axis=0), axis=1).sum())


def _two_bone_ik(world, pos, target: Skeleton, thigh: int, shin: int, foot: int, goal) -> None:
    """Rotate thigh and shin chains (in place) so the ankle reaches ``goal`` (T, 3);
    world (J, T, 4), pos (J, T, 3)."""
    h, k, a = pos[thigh], pos[shin], pos[foot]
    l1 = np.linalg.norm(k - h, axis=-1)
    l2 = np.linalg.norm(a - k, axis=-1)
    hinge = np.cross(a - k, h - k)
    # A (nearly) straight leg has no bending plane of its own (the cross product is
    # rounding noise): bend it about the knee's hinge, the rest knee axis (knees bend
    # toward +Y) carried by the thigh.
    weak = np.linalg.norm(hinge, axis=-1) < _STRAIGHT * l1 * l2
    rest_knee = geometry.unit(np.cross(target.heads[shin] - target.heads[thigh], _BACK))
    knee = quaternion.rotate(world[thigh], target.rest[thigh, :3, :3].T @ rest_knee)
    hinge = geometry.unit(np.where(weak[:, None], knee, hinge))
    reach = np.clip(np.linalg.norm(goal - h, axis=-1), np.abs(l1 - l2) + 1e-6, l1 + l2 - 1e-6)
    cur = np.radians(geometry.angle(h - k, a - k))
    want = np.arccos(np.clip((l1**2 + l2**2 - reach**2) / (2 * l1 * l2), -1, 1))
    bend = quaternion.from_axis_angle(hinge, cur - want)
    a_new = k + quaternion.rotate(bend, a - k)
    turn = quaternion.between(a_new - h, goal - h)
    upper = geometry.path(target, thigh, shin)[:-1]
    lower = geometry.path(target, shin, foot)[:-1]
    world[upper] = quaternion.multiply(turn, world[upper])
    world[lower] = quaternion.multiply(quaternion.multiply(turn, bend), world[lower])


# Sole points of a foot, from its joints alone (the retargeter has no mesh): behind the
# ankle by this fraction of the ankle's height (MakeHuman's heel: 5 cm behind a 7 cm high
# ankle), and to each side of the ball by this fraction of the ankle-to-ball distance.
_HEEL_BACK = 0.6
_HALF_WIDTH = 0.3


def floor_height(target: Skeleton, tmap: BoneMap) -> float:
    """The floor the target's rest pose stands on: z = 0 when its feet are above it by less
    than a foot's height (every Avatar rig), else its lowest foot joint."""
    feet = [tmap.bones[r] for r in FOOT_ROLES if r in tmap.bones]
    if not feet:
        return 0.0
    low = float(np.concatenate([target.heads[feet, 2], target.tails[feet, 2]]).min())
    return 0.0 if 0.0 <= low < 0.15 else low


def soles(target: Skeleton, tmap: BoneMap) -> tuple[np.ndarray, np.ndarray]:
    """Points on the floor under the target's feet in its rest pose: heel, ball and its
    two sides (carried by the foot bone) and under every toe's tip (by that toe's last
    bone). Returns (P,) bone indices and (P, 3) rest positions (metres)."""
    floor = floor_height(target, tmap)
    bones, points = [], []
    for side in ("L", "R"):
        foot, toe = tmap.bones.get(f"foot.{side}"), tmap.bones.get(f"toe.{side}")
        if foot is None:
            continue
        ankle = target.heads[foot]
        ball = target.heads[toe] if toe is not None else target.tails[foot]
        ahead = (ball - ankle) * (1.0, 1.0, 0.0)
        reach = float(np.linalg.norm(ahead))
        if reach < 1e-6:
            continue
        ahead /= reach
        across = np.cross(ahead, (0.0, 0.0, 1.0)) * _HALF_WIDTH * reach
        heel = ankle - ahead * _HEEL_BACK * max(ankle[2] - floor, 0.0)
        tips = _leaves(target, foot)
        for j, p in [(foot, heel), (foot, ball), (foot, ball + across), (foot, ball - across),
                     *((t, target.tails[t]) for t in tips)]:  # fmt: skip
            bones.append(j)
            points.append((p[0], p[1], floor))
    return np.array(bones, dtype=int), np.array(points, dtype=float).reshape(-1, 3)


def _leaves(skeleton: Skeleton, bone: int) -> list[int]:
    """The bones at the ends of the branches below ``bone`` (itself when it has none)."""
    below = np.zeros(len(skeleton.names), dtype=bool)
    below[bone] = True
    for j, p in enumerate(skeleton.parents):  # parents precede children
        if p >= 0 and below[p]:
            below[j] = True
    has_child = np.zeros_like(below)
    has_child[skeleton.parents[below & (skeleton.parents >= 0)]] = True
    return [int(j) for j in np.flatnonzero(below & ~has_child)]


def lift(target: Skeleton, tmap: BoneMap, world: np.ndarray, root: np.ndarray) -> np.ndarray:
    """(T,) how far (metres, >= 0) each frame must rise so that no sole point (``soles``)
    is under the floor; world (J, T, 4) target world rotations (bones not evaluated: NaN
    in frame 0; they keep their rest pose relative to their parent), root (T, 3) hips heads."""
    bones, points = soles(target, tmap)
    if not len(bones):
        return np.zeros(len(root))
    for k, j in enumerate(bones):  # a point on a bone that only follows its parent
        while np.isnan(world[j, 0, 0]) and target.parents[j] >= 0:
            j = target.parents[j]
        bones[k] = j
    known = ~np.isnan(world[bones, 0, 0])  # a root left unevaluated carries nothing
    bones, points = bones[known], points[known]
    if not len(bones):
        return np.zeros(len(root))
    carriers, which = np.unique(bones, return_inverse=True)
    hips = tmap.bones["hips"]
    pos = geometry.positions(target, world, {hips: root}, geometry.ancestors(target, carriers))
    rest = quaternion.from_matrix(target.rest[carriers, :3, :3])
    w, x, y, z = np.moveaxis(
        quaternion.multiply(world[carriers], quaternion.conjugate(rest)[:, None]), -1, 0
    )
    # Only heights matter: the third row of each carrier's turn (as a matrix), (C, T, 3).
    up = np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=-1)
    lowest = np.full(len(root), np.inf)
    for c in range(len(carriers)):
        offsets = points[which == c] - target.heads[carriers[c]]  # (P_c, 3)
        heights = pos[carriers[c], :, 2, None] + up[c] @ offsets.T  # (T, P_c)
        lowest = np.minimum(lowest, heights.min(axis=1))
    return np.maximum(floor_height(target, tmap) - lowest, 0.0)

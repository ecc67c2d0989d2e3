"""Foot contacts: detect them on the source clip, keep them planted on the target.

A foot joint (ankle or toe) is in contact while it is nearly still (speed below 15% of leg
length per second) for at least 50 ms; floors at any height (steps, boxes) count. While the
toe is down the toe is pinned (heel-off pivots about it), else the ankle. The target's leg
is bent by analytic two-bone IK so the pinned joint stays at its mean position over the
contact, blending in and out over 0.1 s; a contact within a few cm of the floor is put on
it: the foot's lowest sole point (``soles``: heel, ball, toe tips, from the rig alone) at
the floor's height, frame by frame. The foot keeps its retargeted world orientation.
``lift`` then raises any frame that still has a sole point under the floor.
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
_EASE_S = 0.05  # a floor lift eases in and out over twice this
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
    on_soles = {side: _carried(target, world, *soles(target, tmap, (side,))) for side in "LR"}
    carriers = [j for bones, _ in on_soles.values() for j in bones]
    pos = geometry.positions(target, world, {hips: root},
                             geometry.ancestors(target, [*legs, *carriers]))  # fmt: skip
    for side in ("L", "R"):
        roles = [f"{r}.{side}" for r in ("thigh", "shin", "foot")]
        if any(r not in tmap.bones for r in roles):
            continue
        sole = _lowest(target, world, pos, *on_soles[side])
        other = feet.frames("R" if side == "L" else "L")
        goal = _ankle_goals(feet.pinned[side], other, pos, sole, tmap, side, target, fps)
        if goal is not None:
            thigh, shin, foot = (tmap.bones[r] for r in roles)
            _two_bone_ik(world, pos, target, thigh, shin, foot, goal)
    return world


def _ankle_goals(pinned, other, pos, sole, tmap: BoneMap, side: str, target: Skeleton,
                 fps: float):  # fmt: skip
    """(T, 3) where the ankle should be, blended around contacts; pos (J, T, 3), sole (T,)
    the foot's lowest sole point's height (``soles``) as retargeted, other (T,) bool: the
    other foot is in contact.

    A pinned joint stays at its mean position over the contact; near the floor, its
    height is instead whatever puts the lowest sole point on the floor that frame: the
    source's foot may meet the floor at another angle than the target's rest foot (CMU's
    flat foot has its toe joint 1 cm under the ankle, MakeHuman's 4 cm), so the joint's
    rest height would sink a heel or lift a toe. A free foot whose sole would be under the
    floor while the other is planted is raised by as much (eased in and out over 0.1 s);
    with no foot planted, ``lift`` raises the body instead (a nearly straight leg bends
    several degrees to shorten by millimetres).
    """
    ankle = tmap.bones[f"foot.{side}"]
    offset = np.zeros((len(pinned), 3))
    weight = np.zeros(len(pinned))
    near_floor = _NEAR_FLOOR * _leg(target, tmap, side)
    floor = floor_height(target, tmap)
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
        on_floor = np.repeat(pin[:, 2] - target.heads[j, 2] < near_floor, runs[:, 1] - runs[:, 0])
        offset[down] = np.repeat(pin, runs[:, 1] - runs[:, 0], axis=0) - pos[j, down]
        on_floor &= np.isfinite(sole[down])  # (a foot without sole points: the mean)
        offset[down, 2] = np.where(on_floor, floor - sole[down], offset[down, 2])
        weight[down] = 1.0
    if weight.any():
        offset, weight = _blend(offset, weight, max(1, int(round(_BLEND_S * fps))))
    shift = offset * weight[:, None]
    # A free foot whose sole would go under the floor (a toe tip pointed down further
    # than the source's) is raised by its own leg, not by lifting the whole body off the
    # planted one.
    under = np.maximum(floor - (sole + shift[:, 2]), 0.0) * (other & (weight == 0))
    if not under.any() and not weight.any():
        return None
    shift[:, 2] += _envelope(under, max(1, int(round(_EASE_S * fps))))
    return pos[ankle] + shift


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
_TIP_FLESH = 0.5  # of a toe tip's height: MakeHuman's skin there is 0.7 cm up, tails 1.4 cm


def floor_height(target: Skeleton, tmap: BoneMap) -> float:
    """The floor the target's rest pose stands on: z = 0 when its feet are above it by less
    than a foot's height (every Avatar rig), else its lowest foot joint."""
    feet = [tmap.bones[r] for r in FOOT_ROLES if r in tmap.bones]
    if not feet:
        return 0.0
    low = float(np.concatenate([target.heads[feet, 2], target.tails[feet, 2]]).min())
    return 0.0 if 0.0 <= low < 0.15 else low


def soles(target: Skeleton, tmap: BoneMap,
          sides: tuple[str, ...] = ("L", "R")) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Points under the target's feet in its rest pose: on the floor under the heel, the
    ball and its two sides (carried by the foot bone), and half way down from every toe's
    tip (carried by that toe's last bone). Returns (P,) bone indices and (P, 3) rest
    positions (metres)."""
    floor = floor_height(target, tmap)
    bones, points = [], []
    for side in sides:
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
        for j, p in [(foot, heel), (foot, ball), (foot, ball + across), (foot, ball - across)]:
            bones.append(j)
            points.append((p[0], p[1], floor))
        for j in _leaves(target, foot):  # toe tips curl up: the flesh is half way down
            tail = target.tails[j]
            bones.append(j)
            points.append((tail[0], tail[1], floor + max(tail[2] - floor, 0.0) * _TIP_FLESH))
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


def lift(target: Skeleton, tmap: BoneMap, world: np.ndarray, root: np.ndarray,
         fps: float) -> np.ndarray:  # fmt: skip
    """(T,) how far (metres, >= 0) each frame must rise so that no sole point (``soles``)
    is under the floor, eased in and out over 0.1 s; world (J, T, 4) target world rotations
    (bones not evaluated: NaN in frame 0), root (T, 3) hips heads."""
    hips = tmap.bones["hips"]
    bones, points = _carried(target, world, *soles(target, tmap))
    pos = geometry.positions(target, world, {hips: root}, geometry.ancestors(target, bones))
    need = floor_height(target, tmap) - _lowest(target, world, pos, bones, points)
    return _envelope(np.maximum(need, 0.0), max(1, int(round(_EASE_S * fps))))


def _envelope(x: np.ndarray, width: int) -> np.ndarray:
    """A smooth curve never below ``x`` (T,): the largest value within ``width`` frames,
    averaged over ``width`` frames (a lift that comes and goes in one frame would pop)."""
    if len(x) < 2 or width < 2:
        return x
    pad = np.pad(x, width, mode="edge")
    peak = np.lib.stride_tricks.sliding_window_view(pad, 2 * width + 1).max(axis=1)
    kernel = np.ones(2 * width + 1) / (2 * width + 1)
    return np.convolve(np.pad(peak, width, mode="edge"), kernel, mode="valid")


def _carried(target: Skeleton, world: np.ndarray, bones: np.ndarray,
             points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Sole points (P, 3) on ``bones`` (P,) re-assigned to the bones that move them: a
    bone not evaluated (world NaN in frame 0) keeps its rest pose relative to its parent,
    so its points go with the nearest evaluated ancestor; points with none are dropped."""
    bones = bones.copy()
    for k, j in enumerate(bones):
        while np.isnan(world[j, 0, 0]) and target.parents[j] >= 0:
            j = target.parents[j]
        bones[k] = j
    known = ~np.isnan(world[bones, 0, 0])
    return bones[known], points[known]


def _lowest(target: Skeleton, world: np.ndarray, pos: np.ndarray, bones: np.ndarray,
            points: np.ndarray) -> np.ndarray:  # fmt: skip
    """(T,) height of the lowest of ``points`` (P, 3) (rest positions) carried by evaluated
    ``bones`` (P,) (``_carried``); world (J, T, 4) rotations, pos (J, T, 3) heads.
    +inf: no points."""
    lowest = np.full(world.shape[1], np.inf)
    if not len(bones):
        return lowest
    carriers, which = np.unique(bones, return_inverse=True)
    rest = quaternion.from_matrix(target.rest[carriers, :3, :3])
    w, x, y, z = np.moveaxis(
        quaternion.multiply(world[carriers], quaternion.conjugate(rest)[:, None]), -1, 0
    )
    # Only heights matter: the third row of each carrier's turn (as a matrix), (C, T, 3).
    up = np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=-1)
    for c in range(len(carriers)):
        offsets = points[which == c] - target.heads[carriers[c]]  # (P_c, 3)
        heights = pos[carriers[c], :, 2, None] + up[c] @ offsets.T  # (T, P_c)
        lowest = np.minimum(lowest, heights.min(axis=1))
    return lowest

"""Bone roles from the hierarchy and geometry alone, for skeletons whose names mean nothing.

Steps (``infer``):
1. feet: the lowest leaf (on average over the given poses) and the lowest leaf far from it
   along the tree; the hips are where the legs meet the way up to the head;
2. hands: the two leaves farthest along the tree from the legs' meeting point that are far
   from each other; the chest is where the arms meet; the neck is the chest's other long
   branch, and the head is where that chain ends or splits (the face);
3. each limb is cut into segments by the anatomical proportions of a human (thigh : shin :
   foot : toe and clavicle : upper arm : forearm : hand), measured as lengths along the
   chain, which no pose changes; joints at one place take the role from the first of them;
   fingers are the chains below the hand (the thumb's base sits apart from the knuckles);
4. left and right: the character's left is ``up x facing``, facing being where the toes
   point (Avatar's -Y when a skeleton has no toes).

Only lengths along the tree and a few signs are read from the poses, so any rest (T, A,
arms down, or Reallusion's folded offsets) works when ``heads`` are posed frames; an
upright rest is read first. ``upright_roles`` also finds the up axis of a file in unknown
axes (the BVH reader's fallback when names say nothing).
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import numpy as np

from avatar.rig.skeleton import Skeleton

_LEG = (0.42, 0.42, 0.16)  # thigh, shin, foot (ankle to toe tip)
_BALL = 0.72  # ankle to ball of the foot, share of ankle to toe tip
_ARM = (0.2, 0.3, 0.28, 0.22)  # clavicle, upper arm, forearm, hand (wrist to fingertip)
_FACING = np.array([0.0, -1.0, 0.0])  # Avatar's characters face -Y
_MAX_POSES = 48


@dataclass(frozen=True)
class _Tree:
    """Pose-independent view of a skeleton: children, length along the tree from the root."""

    parents: np.ndarray
    children: list[list[int]]
    dist: np.ndarray  # (J,) length along the tree from the root to each head (metres)
    ancestors: list[list[int]]  # each joint's chain up to the root, itself first
    tips: np.ndarray  # (J,) bone length beyond a leaf's head

    def lca(self, a: int, b: int) -> int:
        mine = set(self.ancestors[a])
        return next(j for j in self.ancestors[b] if j in mine)

    def between(self, a: int, b: int) -> float:
        return float(self.dist[a] + self.dist[b] - 2 * self.dist[self.lca(a, b)])

    def path(self, top: int, bottom: int) -> list[int]:
        """Joints below ``top`` down to ``bottom`` (``top`` excluded)."""
        chain = self.ancestors[bottom]
        return chain[: chain.index(top)][::-1]

    def reach(self, j: int) -> float:
        """Longest length from j's head down to a leaf's tip."""
        best = self.tips[j]
        for c in self.children[j]:
            best = max(best, self.dist[c] - self.dist[j] + self.reach(c))
        return float(best)

    def leaves(self, below: int | None = None) -> list[int]:
        out = [j for j, kids in enumerate(self.children) if not kids]
        return out if below is None else [j for j in out if below in self.ancestors[j]]


def _tree(skeleton: Skeleton) -> _Tree:
    return _tree_of(skeleton.parents, skeleton.heads, skeleton.lengths)


def _tree_of(parents: np.ndarray, heads: np.ndarray, tips: np.ndarray) -> _Tree:
    children: list[list[int]] = [[] for _ in parents]
    dist = np.zeros(len(parents))
    ancestors: list[list[int]] = []
    for j, p in enumerate(parents):
        if p >= 0:
            children[p].append(j)
            dist[j] = dist[p] + np.linalg.norm(heads[j] - heads[p])
            ancestors.append([j, *ancestors[p]])
        else:
            ancestors.append([j])
    return _Tree(parents, children, dist, ancestors, tips)


def upright_roles(
    parents: np.ndarray, offsets: np.ndarray, poses: np.ndarray | None = None
) -> dict[str, int] | None:
    """Bone roles of a humanoid in any axes, for files whose joint names mean nothing
    (``io.bvh`` finds the up axis and the unit from the head and feet).

    parents: (J,); offsets: (J, 3) rest offsets from each parent (any unit, any axes);
    poses: (T, J, 3) joint positions of some frames in the same axes, or None.
    Each signed axis is tried as up, on the rest pose and on the poses; the roles are those
    of the reading in which feet, hips, chest and head rise by the widest margin. None
    when no reading finds two legs, two arms and a head.
    """
    heads = np.asarray(offsets, dtype=float).copy()
    for j, p in enumerate(parents):
        if p >= 0:
            heads[j] += heads[p]
    tree = _tree_of(np.asarray(parents), heads, np.zeros(len(parents)))
    views = [heads[None]] if poses is None else [heads[None], np.asarray(poses, dtype=float)]
    best, out = 0.0, None
    for view in views:
        for axis in range(3):
            others = [a for a in range(3) if a != axis]
            for sign in (1.0, -1.0):
                turned = view[..., [*others, axis]] * [1.0, 1.0, sign]
                roles = _roles(tree, turned)
                names = ("head", "chest", "hips", "foot.L", "foot.R")
                if not all(r in roles for r in names):
                    continue
                z = np.median(turned[:, [roles[r] for r in names], 2], axis=0)
                margin = min(z[0] - z[1], z[1] - z[2], z[2] - max(z[3], z[4]))
                if margin > best:
                    best, out = margin, roles
    return out


def infer(skeleton: Skeleton, heads: np.ndarray | None = None) -> dict[str, int]:
    """Canonical body roles of a skeleton from its hierarchy and geometry.

    skeleton: any humanoid skeleton (metres, Z-up as Avatar loads it).
    heads: (J, 3) or (T, J, 3) world heads of poses to read heights and sides from when
        the rest pose is not an upright human (Reallusion's folded offsets); an upright
        rest is always preferred, being the most neutral pose there is.
    Returns {canonical role: joint index} for the roles found: ``bonemap.CORE`` (hips,
    spine, chest, neck, head, and clavicle..hand, thigh..toe per side) and fingers
    (thumb1..pinky3); {} when the skeleton has no two legs.
    """
    tree = _tree(skeleton)
    roles = _roles(tree, skeleton.heads[None])
    if heads is None or _upright(roles, skeleton.heads):
        return roles
    pose = np.asarray(heads, dtype=float)
    pose = pose[None] if pose.ndim == 2 else pose
    pose = pose[np.linspace(0, len(pose) - 1, min(len(pose), _MAX_POSES)).astype(int)]
    return _roles(tree, pose)


def _upright(roles: dict[str, int], heads: np.ndarray) -> bool:
    """Head above chest above hips above knees above feet, left and right."""
    z = heads[:, 2]
    chains = [("head", "chest", "hips")]
    chains += [(f"thigh.{s}", f"shin.{s}", f"foot.{s}") for s in "LR"]
    for chain in chains:
        if not all(r in roles for r in chain):
            return False
        if not np.all(np.diff(z[[roles[r] for r in chain]]) < 0):
            return False
    return True


def _roles(tree: _Tree, pose: np.ndarray) -> dict[str, int]:
    """``infer`` in the given poses (T, J, 3)."""
    feet = _feet(tree, pose)
    if feet is None:
        return {}
    legs = [tree.path(tree.lca(*feet), f) for f in feet]
    hands = _hands(tree, tree.lca(*feet), legs)
    roles: dict[str, int] = {"hips": tree.lca(*feet)}
    if hands is not None:
        roles.update(_trunk(tree, feet, hands))
    sides = [_leg(tree, pose, legs[0], legs[1]), _leg(tree, pose, legs[1], legs[0])]
    if _is_left(pose, sides, roles) < 0:
        sides.reverse()
    for side, leg in zip("LR", sides, strict=True):
        roles.update({f"{k}.{side}": v for k, v in leg.items()})
    if hands is None or "chest" not in roles:
        return roles
    arms = [_arm(tree, tree.path(roles["chest"], h)) for h in hands]
    if _same_side(pose, sides, arms) < 0:
        arms.reverse()
    for side, arm in zip("LR", arms, strict=True):
        roles.update({f"{k}.{side}": v for k, v in arm.items()})
        if "hand" in arm:
            roles.update({f"{k}.{side}": v for k, v in _fingers(tree, pose, arm["hand"]).items()})
    return roles


def _fingers(tree: _Tree, pose: np.ndarray, hand: int) -> dict[str, int]:
    """thumb1..pinky3 below a hand: each finger is a chain to a fingertip; its last three
    joints are the phalanges (metacarpals before them are left out). The thumb's base sits
    apart from the row of knuckles (with two fingers only: the shorter one); the others
    are named by their distance from the thumb across the palm (index, middle, ring,
    pinky; a finger alone is the middle one)."""
    chains: dict[int, list[int]] = {}
    for tip in tree.leaves(below=hand):
        path = tree.path(hand, tip)
        if path:
            joints = _points(tree, path)[0][-3:]
            chains.setdefault(joints[0], joints)
    if not chains:
        return {}
    reach = {f: tree.dist[c[-1]] - tree.dist[hand] + tree.tips[c[-1]] for f, c in chains.items()}
    chains = {f: c for f, c in chains.items() if reach[f] > 0.3 * max(reach.values())}
    apart = {f: np.mean([np.linalg.norm(pose[:, f] - pose[:, g], axis=-1).mean()
                         for g in chains if g != f] or [0.0]) for f in chains}  # fmt: skip
    names = {}
    if len(chains) == 1:
        names[next(iter(chains))] = "middle"
    else:
        thumb = (
            max(chains, key=lambda f: apart[f])
            if len(chains) > 2
            else min(chains, key=lambda f: reach[f])
        )
        names[thumb] = "thumb"
        gap = {
            f: float(np.linalg.norm(pose[:, f] - pose[:, thumb], axis=-1).mean()) for f in chains
        }
        others = sorted((f for f in chains if f != thumb), key=lambda f: gap[f])
        order = ("middle",) if len(others) == 1 else ("index", "middle", "ring", "pinky")
        names.update(zip(others, order, strict=False))
    return {f"{names[f]}{i}": j for f, c in chains.items() if f in names
            for i, j in enumerate(c, 1)}  # fmt: skip


def _same_side(pose: np.ndarray, legs: list[dict[str, int]], arms: list[dict[str, int]]) -> float:
    """> 0 when ``arms[0]`` is on the side of ``legs[0]``."""
    a, b = legs[0].get("thigh"), legs[1].get("thigh")
    c, d = arms[0].get("upperarm"), arms[1].get("upperarm")
    if None in (a, b, c, d):
        return 1.0
    return float(np.sum((pose[:, a] - pose[:, b]) * (pose[:, c] - pose[:, d])))


def _feet(tree: _Tree, pose: np.ndarray) -> tuple[int, int] | None:
    """The two foot tips: the lowest leaf, and the lowest leaf far from it along the tree."""
    leaves = tree.leaves()
    height = pose[:, leaves, 2].mean(axis=0)
    order = [leaves[i] for i in np.argsort(height)]
    first = order[0]
    far = max(tree.between(first, j) for j in leaves)
    for j in order[1:]:
        if tree.between(first, j) > 0.5 * far:
            return first, j
    return None


def _hands(tree: _Tree, pelvis: int, legs: list[list[int]]) -> tuple[int, int] | None:
    """The two hand tips: the leaves outside the legs farthest from where the legs meet,
    far apart from each other along the tree."""
    leg_roots = {leg[0] for leg in legs if leg}
    upper = [j for j in tree.leaves() if not leg_roots & set(tree.ancestors[j])]
    if len(upper) < 2:
        return None
    upper.sort(key=lambda j: -tree.between(pelvis, j))
    first = upper[0]
    for j in upper[1:]:
        if tree.between(first, j) > 0.5 * tree.between(first, pelvis):
            return first, j
    return None


def _trunk(tree: _Tree, feet: tuple[int, int], hands: tuple[int, int]) -> dict[str, int]:
    """hips (where legs and spine meet), spine, chest (where the arms meet), neck, head."""
    chest = tree.lca(*hands)
    hips = tree.lca(tree.lca(*feet), chest)
    roles = {"hips": hips, "chest": chest}
    spine = tree.path(hips, chest)
    if len(spine) >= 2:
        roles["spine"] = spine[0]
    arm_roots = {tree.path(chest, h)[0] for h in hands}
    others = [c for c in tree.children[chest] if c not in arm_roots]
    if not others:
        return roles
    neck = max(others, key=lambda c: tree.dist[c] - tree.dist[chest] + tree.reach(c))
    roles["neck"] = neck
    j = neck
    while len(tree.children[j]) == 1:
        j = tree.children[j][0]
    head = _first_here(tree, j, stop=neck)
    if head != neck:
        roles["head"] = head
    return roles


def _first_here(tree: _Tree, j: int, stop: int) -> int:
    """The topmost joint (not above ``stop``) at the same place as ``j``."""
    while j != stop and tree.dist[j] - tree.dist[tree.parents[j]] < 1e-4:
        j = int(tree.parents[j])
    return j


def _points(tree: _Tree, chain: list[int]) -> tuple[list[int], np.ndarray]:
    """Distinct places along a chain: the first joint at each, and lengths from the first
    place, the last entry being the chain's tip (end of its leaf)."""
    joints, arcs = [chain[0]], [0.0]
    for j in chain[1:]:
        if tree.dist[j] - tree.dist[joints[-1]] > 1e-4:
            joints.append(j)
            arcs.append(float(tree.dist[j] - tree.dist[chain[0]]))
    arcs.append(arcs[-1] + float(tree.tips[chain[-1]]))
    return joints, np.asarray(arcs)


def _cut(arcs: np.ndarray, first: int, cuts: int, shares: tuple[float, ...]) -> tuple[int, ...]:
    """Indices (ascending, > ``first``, below the tip) of ``cuts`` places whose segment
    lengths best match ``shares`` of the whole; () when there are too few places."""
    places = range(first + 1, len(arcs) - 1)
    best, out = np.inf, ()  # type: tuple[float, tuple[int, ...]]
    total = arcs[-1] - arcs[first]
    for pick in combinations(places, cuts):
        edges = arcs[[first, *pick, len(arcs) - 1]]
        cost = float(np.sum((np.diff(edges) / max(total, 1e-9) - shares) ** 2))
        if cost < best:
            best, out = cost, pick
    return out


def _leg(tree: _Tree, pose: np.ndarray, leg: list[int], other: list[int]) -> dict[str, int]:
    """thigh, shin, foot, toe along a leg chain (from below the legs' meeting point)."""
    start = _parting(pose, leg, other)
    joints, arcs = _points(tree, leg[start:])
    if len(joints) < 3:
        return {}
    knee, ankle = _cut(arcs, 0, 2, _LEG)
    out = {"thigh": joints[0], "shin": joints[knee], "foot": joints[ankle]}
    toe = _big_toe(tree, pose, joints[ankle], pose[:, leg[start]] - pose[:, other[start]])
    if toe is not None:
        out["toe"] = toe
    return out


def _big_toe(tree: _Tree, pose: np.ndarray, foot: int, outward: np.ndarray) -> int | None:
    """The ball of the foot: on the chain of the foot's most medial long child (the big
    toe among several), the joint about 3/4 of the way to the tip; None without toes."""
    j = foot
    while len(tree.children[j]) == 1 and tree.dist[tree.children[j][0]] - tree.dist[j] < 1e-4:
        j = tree.children[j][0]  # joints at the ankle itself
    kids = tree.children[j]
    if not kids:
        return None
    reach = {c: tree.dist[c] - tree.dist[j] + tree.reach(c) for c in kids}
    longest = max(reach.values())
    near = [c for c in kids if reach[c] >= 0.5 * longest]
    side = {c: float(np.mean(np.sum((pose[:, c] - pose[:, j]) * outward, axis=-1))) for c in near}
    inner = min(side.values())
    ties = [c for c in near if side[c] - inner < 1e-3]
    chain = [j, max(ties, key=lambda c: reach[c])]
    while tree.children[chain[-1]]:
        chain.append(max(tree.children[chain[-1]], key=lambda c: tree.dist[c] + tree.reach(c)))
    joints, arcs = _points(tree, chain)  # the ball of the foot: ~3/4 from ankle to tip
    return joints[1 + int(np.argmin(np.abs(arcs[1:-1] / max(arcs[-1], 1e-9) - _BALL)))]


def _parting(pose: np.ndarray, leg: list[int], other: list[int]) -> int:
    """Index along ``leg`` of the first joint apart from its twin on the other leg (the
    hip joint; the bones before it run from the pelvis's centre)."""
    size = np.linalg.norm(pose[:, leg[-1]] - pose[:, leg[0]], axis=-1).mean()
    for i, (a, b) in enumerate(zip(leg, other, strict=False)):
        if np.linalg.norm(pose[:, a] - pose[:, b], axis=-1).mean() > 0.05 * size:
            return i
    return 0


def _arm(tree: _Tree, arm: list[int]) -> dict[str, int]:
    """clavicle, upperarm, forearm, hand along an arm chain (from below the chest)."""
    joints, arcs = _points(tree, arm)
    if len(joints) < 4:
        return {}
    shoulder, elbow, wrist = _cut(arcs, 0, 3, _ARM)
    return {"clavicle": joints[0], "upperarm": joints[shoulder], "forearm": joints[elbow],
            "hand": joints[wrist]}  # fmt: skip


def _is_left(pose: np.ndarray, sides: list[dict[str, int]], roles: dict[str, int]) -> float:
    """> 0 when ``sides[0]`` is the character's left leg: (first - second) . (up x facing),
    summed over poses; facing is where the toes point (-Y without toes)."""
    a, b = sides[0].get("thigh"), sides[1].get("thigh")
    if a is None or b is None:
        return 1.0
    top = roles.get("neck", roles.get("chest", roles["hips"]))
    up = pose[:, top] - pose[:, roles["hips"]]
    if top == roles["hips"]:
        up = np.broadcast_to([0.0, 0.0, 1.0], up.shape)
    facing = np.zeros_like(up)
    for leg in sides:
        if "toe" in leg:
            facing += pose[:, leg["toe"]] - pose[:, leg["foot"]]
    if not np.any(facing):
        facing = np.broadcast_to(_FACING, up.shape)
    left = np.cross(up, facing)
    return float(np.sum((pose[:, a] - pose[:, b]) * left))

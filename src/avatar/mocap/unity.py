"""Unity HumanBodyBones on Avatar rigs, and Unity's frame <-> Avatar's.

Axes. Unity is left-handed, Y up, a character facing +Z with its right hand towards +X.
Avatar is right-handed, Z up, the character facing -Y with its left hand towards +X. So a
Unity vector (x, y, z) is Avatar's (-x, -z, y) (``M = [[-1,0,0],[0,0,-1],[0,1,0]]``,
det -1: the handedness flips). A rotation R_u becomes M R_u M^T; as quaternions, Unity's
(x, y, z, w) is Avatar's (w, x, z, -y): the axis maps as a pseudovector (-M a) and the
angle keeps its value. ``tests/mocap/test_vmc.py`` checks both against the matrices.

What VMC sends. Each ``/VMC/Ext/Bone/Pos`` carries a HumanBodyBones bone's
``localPosition`` and ``localRotation`` on a normalised humanoid: in the T-pose every bone's
frame is the model's frame (all local rotations identity), so a bone's world rotation,
the product of its ancestors' local rotations, is its turn away from the T-pose (``D``).
``/VMC/Ext/Root/Pos`` places the model (position, rotation) in the world.

On an Avatar rig (``UnityRig``): each mapped bone's world rotation is ``D T`` with ``T``
the bone's world rotation in the rig's own T-pose (``motion.poselib``'s t-pose: arms out
straight); bones in between on the spine and neck share the turn of their mapped
neighbours; other bones keep their T-pose relation to their parent. The hips go where
the sender's hips are, scaled by the rig's leg length over the sender's (from its bone
positions). The sender does the reverse with the same T-pose, so Avatar -> VMC -> Avatar
is exact (float32 on the wire).
"""

from __future__ import annotations

import functools
import json
from collections.abc import Sequence
from dataclasses import dataclass
from importlib import resources

import numpy as np

from avatar.motion import bonemap, geometry, poselib
from avatar.rig import quaternion
from avatar.rig.kinematics import rest_quaternions, world_pose
from avatar.rig.skeleton import Skeleton

Vector = Sequence[float] | np.ndarray  # a 3- or 4-vector: floats as received, or an array

M = np.array([[-1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
"""Unity vector -> Avatar vector (``M @ v``); its inverse is its transpose."""


@functools.cache
def human_bones() -> tuple[tuple[str, str | None, str | None], ...]:
    """(name, Unity parent, canonical role) for the 55 HumanBodyBones, parents first."""
    text = (resources.files("avatar") / "data" / "mocap" / "unity_humanoid.json").read_text("utf-8")
    return tuple((b[0], b[1], b[2]) for b in json.loads(text)["bones"])


def to_avatar_vector(v: Vector) -> np.ndarray:
    """(..., 3) Unity positions -> Avatar's."""
    v = np.asarray(v, dtype=np.float64)
    return np.stack([-v[..., 0], -v[..., 2], v[..., 1]], axis=-1)


def to_unity_vector(v: Vector) -> np.ndarray:
    """(..., 3) Avatar positions -> Unity's."""
    v = np.asarray(v, dtype=np.float64)
    return np.stack([-v[..., 0], v[..., 2], -v[..., 1]], axis=-1)


def to_avatar_quaternion(q: np.ndarray) -> np.ndarray:
    """(..., 4) Unity quaternions (x, y, z, w) -> Avatar's (w, x, y, z)."""
    q = np.asarray(q, dtype=np.float64)
    return np.stack([q[..., 3], q[..., 0], q[..., 2], -q[..., 1]], axis=-1)


def to_unity_quaternion(q: np.ndarray) -> np.ndarray:
    """(..., 4) Avatar quaternions (w, x, y, z) -> Unity's (x, y, z, w)."""
    q = np.asarray(q, dtype=np.float64)
    return np.stack([q[..., 1], -q[..., 3], q[..., 2], q[..., 0]], axis=-1)


@dataclass(frozen=True)
class UnityPose:
    """One humanoid pose as VMC carries it (Unity's axes).

    root: (position (3,), rotation (4,) xyzw) of the model.
    bones: HumanBodyBones name -> (localPosition (3,), localRotation (4,) xyzw).
    Each a 3- or 4-sequence of floats (tuples as received, arrays as ``to_unity`` makes).
    """

    root: tuple[Vector, Vector]
    bones: dict[str, tuple[Vector, Vector]]


class UnityRig:
    """HumanBodyBones on one Avatar rig: ``to_unity`` (send) and ``from_unity`` (receive)."""

    def __init__(self, skeleton: Skeleton, bmap: bonemap.BoneMap | None = None):
        self.skeleton = skeleton
        bmap = bonemap.detect(skeleton) if bmap is None else bmap
        self.names = [b[0] for b in human_bones()]
        self.unity_parent = [self.names.index(p) if p else -1 for _, p, _ in human_bones()]
        self.bone_of = self._map(skeleton, bmap)  # Unity index -> rig bone (-1: none)
        self._index = {name: u for u, name in enumerate(self.names)}
        self._levels = _levels(self.unity_parent)
        # Unity's humanoid T-pose has the legs straight down; poselib's t-pose keeps the
        # rest's leg splay (CMU's legs stand 20 degrees apart, Avatar's 5.7), which would
        # turn every streamed leg by the difference.
        tpose = poselib.arms_out(skeleton, 0.0, bmap, legs_down=True)
        t_rot, t_heads = world_pose(skeleton, tpose.rotations[0], tpose.translations[0])
        self.t_rot, self.t_heads = t_rot, t_heads
        self.rest_rot, self.local_rest = rest_quaternions(skeleton)
        self.hips = bmap.bones["hips"]
        self.source, self.shares = self._sources(skeleton, bmap)
        above, j = [], int(skeleton.parents[self.hips])
        while j >= 0:
            above.append(j)
            j = int(skeleton.parents[j])
        self.above_hips = np.array(above, dtype=int)  # bones that stay at rest
        self.leg = _leg(t_heads, bmap)
        # What a frame's conversion needs, prepared once (both directions work on all bones
        # at once: a handful of numpy calls a tree level, not a product per bone).
        self._identity_xyzw = np.tile([0.0, 0.0, 0.0, 1.0], (len(self.names), 1))
        if self.shares:
            share = np.array([sh[:3] for sh in self.shares], dtype=int)
            self._share_bone, self._share_lo, self._share_hi = share.T
            self._share_f = np.array([sh[3] for sh in self.shares])
        parents = skeleton.parents
        self._has_parent = np.flatnonzero(parents >= 0)
        self._parent_of = parents[self._has_parent]
        self._local_rest_c = self.local_rest[self._has_parent]
        self._t_rot_inverse = _conjugate(self.t_rot)
        mapped = np.flatnonzero(self.bone_of >= 0)
        self._mapped, self._mapped_bones = mapped, self.bone_of[mapped]
        # Per Unity bone: the nearest mapped bone at or above it (-1: none, identity turn).
        nearest = np.full(len(self.names), -1)
        for u, p in enumerate(self.unity_parent):  # parents precede children
            nearest[u] = u if self.bone_of[u] >= 0 else (nearest[p] if p >= 0 else -1)
        self._nearest = nearest
        sent_parent = np.array([self.unity_parent[u] for u in mapped])
        self._sent_parent = sent_parent
        self._sent_names = [self.names[u] for u in mapped]
        self._sent_root = [i for i, u in enumerate(mapped) if self.unity_parent[u] < 0]
        positions = np.zeros((len(mapped), 3))
        for i, m in enumerate(mapped.tolist()):  # T-pose offsets from the mapped bone above
            if self.unity_parent[m] >= 0:
                over = self._mapped_above(m)
                ref = self.t_heads[self.bone_of[over]] if over >= 0 else np.zeros(3)
                positions[i] = to_unity_vector(self.t_heads[self.bone_of[m]] - ref)
        self._sent_positions = positions

    def _map(self, skeleton: Skeleton, bmap: bonemap.BoneMap) -> np.ndarray:
        out = np.full(len(self.names), -1)
        for u, (_, _, role) in enumerate(human_bones()):
            if role and role in bmap.bones:
                out[u] = bmap.bones[role]
        chest = bmap.bones.get("chest")
        if chest is not None and "spine" in bmap.bones:
            chain = geometry.path(skeleton, bmap.bones["spine"], chest)
            out[self.names.index("Chest")] = chain[len(chain) // 2] if len(chain) >= 3 else chest
            if len(chain) >= 3:
                out[self.names.index("UpperChest")] = chest
            if len(chain) >= 2:
                out[self.names.index("Spine")] = chain[0]
        return out

    def _sources(self, skeleton: Skeleton, bmap: bonemap.BoneMap):
        """Per rig bone, the Unity bone whose turn it takes (mapped, or its parent's), and
        the in-between spine/neck bones: (bone, lower Unity, upper Unity, fraction)."""
        count = len(skeleton.names)
        source = np.full(count, self.names.index("Hips"))
        mapped = {int(b): u for u, b in enumerate(self.bone_of) if b >= 0}
        for j in range(count):
            p = skeleton.parents[j]
            source[j] = mapped.get(j, source[p] if p >= 0 else source[j])
        shares = []
        for top in ("head",):
            if top not in bmap.bones or "hips" not in bmap.bones:
                continue
            path = geometry.path(skeleton, bmap.bones["hips"], bmap.bones[top])
            marks = [i for i, j in enumerate(path) if j in mapped]
            for lo, hi in zip(marks, marks[1:], strict=False):
                for i in range(lo + 1, hi):
                    shares.append((path[i], mapped[path[lo]], mapped[path[hi]],
                                   (i - lo) / (hi - lo)))  # fmt: skip
        return source, shares

    # -- receive ---------------------------------------------------------------------------

    def from_unity(self, pose: UnityPose) -> tuple[np.ndarray, np.ndarray]:
        """A VMC pose -> (J, 4) pose-bone rotations and (J, 3) locations on this rig."""
        local = self._identity_xyzw.copy()
        bones = pose.bones
        if bones:
            index = self._index
            local[[index[name] for name in bones]] = [q for _, q in bones.values()]
        local = local[:, _TO_AVATAR] * _TO_AVATAR_SIGN  # to_avatar_quaternion
        root = np.asarray(pose.root[1], dtype=np.float64)
        root_q = root[_TO_AVATAR] * _TO_AVATAR_SIGN
        turn = np.empty_like(local)  # D per Unity bone, Avatar's axes
        for level, parents in self._levels:  # a tree level at a time: ~8 products, not 55
            turn[level] = _multiply(turn[parents] if parents is not None else root_q[None],
                                    local[level])  # fmt: skip
        d = turn[self.source]
        if self.shares:
            d[self._share_bone] = quaternion.slerp(turn[self._share_lo], turn[self._share_hi],
                                                   self._share_f)  # fmt: skip
        world = _multiply(d, self.t_rot)
        world[self.above_hips] = self.t_rot[self.above_hips]
        rotations = self._locals(world)
        translations = np.zeros((len(self.skeleton.names), 3))
        hips = bones.get("Hips")
        if hips is not None:
            at = to_avatar_vector(pose.root[0]) + quaternion.rotate(
                root_q, to_avatar_vector(hips[0])
            )
            at = at * self._scale(pose)
            translations[self.hips] = quaternion.rotate(
                quaternion.conjugate(self.rest_rot[self.hips]), at - self.skeleton.heads[self.hips]
            )
        return rotations, translations

    def _locals(self, world: np.ndarray) -> np.ndarray:
        base = self.local_rest.copy()
        base[self._has_parent] = _multiply(world[self._parent_of], self._local_rest_c)
        out = _multiply(_conjugate(base), world)
        return out * np.where(out[:, :1] < 0, -1.0, 1.0)

    def _scale(self, pose: UnityPose) -> float:
        parts = [pose.bones.get(n) for n in ("LeftLowerLeg", "LeftFoot")]
        if any(p is None for p in parts):
            return 1.0
        leg = sum(float(np.linalg.norm(p[0])) for p in parts if p is not None)
        return self.leg / leg if leg > 1e-3 else 1.0

    # -- send ------------------------------------------------------------------------------

    def to_unity(self, rotations: np.ndarray, translations: np.ndarray) -> UnityPose:
        """(J, 4) pose-bone rotations and (J, 3) locations on this rig -> a VMC pose."""
        world, heads = world_pose(self.skeleton, rotations[None], translations[None])
        world, heads = world[0], heads[0]
        # Each Unity bone's turn from the T-pose: its mapped bone's, or the nearest mapped
        # one's above it (identity above all of them).
        mapped_turn = _multiply(world[self._mapped_bones], self._t_rot_inverse[self._mapped_bones])
        turn = np.tile([1.0, 0.0, 0.0, 0.0], (len(self.names), 1))
        nearest = self._nearest
        has = nearest >= 0
        where = np.searchsorted(self._mapped, nearest[has])
        turn[has] = mapped_turn[where]
        parent_turn = np.where((self._sent_parent >= 0)[:, None], turn[self._sent_parent],
                               [1.0, 0.0, 0.0, 0.0])  # fmt: skip
        local = _multiply(_conjugate(parent_turn), mapped_turn)
        quats = to_unity_quaternion(local)
        positions = self._sent_positions.copy()
        for i in self._sent_root:
            positions[i] = to_unity_vector(heads[self._mapped_bones[i]])
        bones = dict(zip(self._sent_names, zip(positions, quats, strict=True), strict=True))
        return UnityPose((np.zeros(3), np.array([0.0, 0.0, 0.0, 1.0])), bones)

    def _mapped_above(self, u: int) -> int:
        p = self.unity_parent[u]
        while p >= 0 and self.bone_of[p] < 0:
            p = self.unity_parent[p]
        return p


# Unity (x, y, z, w) -> Avatar (w, x, y, z) as a gather and a sign: (w, x, z, -y).
_TO_AVATAR = np.array([3, 0, 2, 1])
_TO_AVATAR_SIGN = np.array([1.0, 1.0, 1.0, -1.0])
# The Hamilton product as one contraction: out[k] = sum_ij a[i] b[j] _HAMILTON[i, j, k].
_HAMILTON = np.zeros((4, 4, 4))
for _k, _terms in enumerate((
        ((0, 0, 1), (1, 1, -1), (2, 2, -1), (3, 3, -1)),
        ((0, 1, 1), (1, 0, 1), (2, 3, 1), (3, 2, -1)),
        ((0, 2, 1), (1, 3, -1), (2, 0, 1), (3, 1, 1)),
        ((0, 3, 1), (1, 2, 1), (2, 1, -1), (3, 0, 1)))):  # fmt: skip
    for _i, _j, _sign in _terms:
        _HAMILTON[_i, _j, _k] = _sign
_HAMILTON_FLAT = _HAMILTON.reshape(16, 4)


def _multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton products of (n, 4) quaternions ((1, 4) broadcasts): ``quaternion.multiply``
    in two numpy calls (for a few dozen rows its per-component form is 36 calls)."""
    n = max(len(a), len(b))
    return np.dot((a[:, :, None] * b[:, None, :]).reshape(n, 16), _HAMILTON_FLAT)


def _conjugate(q: np.ndarray) -> np.ndarray:
    return q * _CONJUGATE


_CONJUGATE = np.array([1.0, -1.0, -1.0, -1.0])


def _levels(parents: list[int]) -> list[tuple[np.ndarray, np.ndarray | None]]:
    """The tree's levels, roots first: (bones (n,), their parents (n,) or None for roots)."""
    depth = np.zeros(len(parents), dtype=int)
    for u, p in enumerate(parents):  # parents precede children
        depth[u] = 0 if p < 0 else depth[p] + 1
    out: list[tuple[np.ndarray, np.ndarray | None]] = []
    for d in range(int(depth.max()) + 1):
        level = np.flatnonzero(depth == d)
        out.append((level, None if d == 0 else np.asarray(parents)[level]))
    return out


def _leg(heads: np.ndarray, bmap: bonemap.BoneMap) -> float:
    b = bmap.bones
    if not all(r in b for r in ("thigh.L", "shin.L", "foot.L")):
        return 1.0
    return float(np.linalg.norm(heads[b["shin.L"]] - heads[b["thigh.L"]])
                 + np.linalg.norm(heads[b["foot.L"]] - heads[b["shin.L"]]))  # fmt: skip

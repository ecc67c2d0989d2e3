"""Bone pairs between a source and a target skeleton, and the segments they measure."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from avatar.motion import bonemap
from avatar.motion.bonemap import BoneMap
from avatar.rig import quaternion
from avatar.rig.skeleton import Skeleton

TRUNK = ("hips", "spine", "chest", "neck", "head")
_MIN_SEGMENT = 1e-3  # metres; shorter segments (CMU's zero offsets) are followed further


@dataclass(frozen=True)
class Pair:
    """One source bone driving one target bone.

    role: canonical name, or "=name" for bones matched by identical names.
    source, target: bone indices. source_end, target_end: index of the bone whose head ends
    the measured segment, or -1 for the bone's own tail.
    """

    role: str
    source: int
    target: int
    source_end: int
    target_end: int

    @property
    def kind(self) -> str:
        base = self.role.split(".")[0].rstrip("123")
        return "trunk" if base in TRUNK else base


def _end_role(source: Skeleton, smap: BoneMap, target: Skeleton, tmap: BoneMap, role: str):
    """The canonical bone whose head ends ``role``'s segment on both sides: the next one
    mapped on both, skipping any that starts where ``role`` starts on either side (CMU's
    zero offsets); None means each bone's own tail."""
    nxt, skipped = bonemap.NEXT.get(role), None
    while nxt is not None and nxt in smap.bones and nxt in tmap.bones:
        gaps = [np.linalg.norm(sk.heads[m.bones[nxt]] - sk.heads[m.bones[role]])
                for sk, m in ((source, smap), (target, tmap))]  # fmt: skip
        if min(gaps) > _MIN_SEGMENT:
            return nxt
        skipped, nxt = nxt, bonemap.NEXT.get(nxt)
    return None if skipped is None else ("tail", skipped)


def _end_index(bmap: BoneMap, end) -> int:
    """Encode an end role: head of bone b -> b; tail of bone b -> -2 - b; own tail -> -1."""
    if end is None:
        return -1
    if isinstance(end, tuple):
        return -2 - bmap.bones[end[1]]
    return bmap.bones[end]


def _landmark(source: Skeleton, s: int, target: Skeleton, t: int) -> tuple[int, int] | None:
    """(source child, target child): the same-named child joints of bones ``s`` and ``t``
    farthest from their joint on the target (at least ``_MIN_SEGMENT`` away on both), or
    None. A child joint is a point of the anatomy both skeletons place; a bone's own tail
    is not (a BVH file has no tails: readers invent one from an End Site or the mean of
    the children, which for a head with a face is a point inside the skull)."""
    kids_s = {bonemap.normalise(source.names[c]): c for c in np.flatnonzero(source.parents == s)}
    best, far = None, _MIN_SEGMENT
    for c in np.flatnonzero(target.parents == t):
        o = kids_s.get(bonemap.normalise(target.names[c]))
        if o is None:
            continue
        gaps = (np.linalg.norm(source.heads[o] - source.heads[s]),
                np.linalg.norm(target.heads[c] - target.heads[t]))  # fmt: skip
        if min(gaps) > _MIN_SEGMENT and gaps[1] > far:
            best, far = (int(o), int(c)), float(gaps[1])
    return best


def make_pairs(
    source: Skeleton, smap: BoneMap, target: Skeleton, tmap: BoneMap, match_names: bool = True
) -> list[Pair]:
    """Canonical pairs (roles mapped on both sides), then same-named leftovers.

    A segment that would end at the bones' own tails (the head, the last bone of a
    chain, same-named extras) ends instead at a same-named child joint where both
    skeletons have one (``_landmark``: the face's joints for the head).
    """
    pairs = []
    for role in bonemap.NEXT:
        if role in smap.bones and role in tmap.bones:
            end = _end_role(source, smap, target, tmap, role)
            s_end, t_end = _end_index(smap, end), _end_index(tmap, end)
            mark = _landmark(source, smap.bones[role], target, tmap.bones[role])
            if end is None and mark is not None:
                s_end, t_end = mark
            pairs.append(Pair(role, smap.bones[role], tmap.bones[role], s_end, t_end))
    if match_names:
        used_s = {p.source for p in pairs}
        used_t = {p.target for p in pairs}
        index = {bonemap.normalise(n): j for j, n in enumerate(source.names)}
        for t, name in enumerate(target.names):
            s = index.get(bonemap.normalise(name))
            if s is not None and s not in used_s and t not in used_t:
                s_end, t_end = _landmark(source, s, target, t) or (-1, -1)
                pairs.append(Pair("=" + name, s, t, s_end, t_end))
    return pairs


def segments(skeleton: Skeleton, rot: np.ndarray, pos: np.ndarray, bones, ends) -> np.ndarray:
    """(n, T, 3) world segment vectors of ``bones`` (n,) ending at ``ends`` (n,) (encoded as
    ``Pair.target_end``: a bone's head, -1 its own tail, -2 - b the tail of bone b).

    rot: (J, T, 4) world bone rotations (quaternions); pos: (J, T, 3) world heads (bone
    axis first, as the retargeter keeps them).
    """
    bones, ends = np.asarray(bones, dtype=int), np.asarray(ends, dtype=int)
    other = np.where(ends == -1, bones, -2 - ends)
    out = pos[np.where(ends >= 0, ends, other)] - pos[bones]
    tail = np.flatnonzero(ends < 0)
    if len(tail):
        o = other[tail]
        local = np.einsum("jba,jb->ja", skeleton.rest[o, :3, :3],
                          skeleton.tails[o] - skeleton.heads[o])  # fmt: skip
        out[tail] += quaternion.rotate(rot[o], local[:, None])
    return out


def segment_world(skeleton: Skeleton, rot: np.ndarray, pos: np.ndarray, bone: int, end: int):
    """(T, 3) world segment vector of one bone; rot (T, J, 4) and pos (T, J, 3) frame
    first (see ``segments``)."""
    if end >= 0:
        return pos[:, end] - pos[:, bone]
    other = bone if end == -1 else -2 - end
    local = skeleton.rest[other, :3, :3].T @ (skeleton.tails[other] - skeleton.heads[other])
    return pos[:, other] - pos[:, bone] + quaternion.rotate(rot[:, other], local)


def segment_rest(skeleton: Skeleton, bone: int, end: int) -> np.ndarray:
    """(3,) the segment in the bone's own rest frame."""
    far = skeleton.heads[end] if end >= 0 else skeleton.tails[bone if end == -1 else -2 - end]
    return skeleton.rest[bone, :3, :3].T @ (far - skeleton.heads[bone])

"""Per-bone rest alignment between a source clip and a target skeleton.

For each pair the offset ``A`` (3x3, target bone frame -> source bone frame) is chosen so the
target bone's segment runs along the source's and its twist matches an anatomical
reference seen the same way on both sides: the pelvis/shoulder line for the trunk, the knee
and elbow hinge axes (estimated from the clip's own bending, so any rest pose works: T, A,
arms down or Reallusion's folded rest) for limbs, the body's forward axis for clavicles.
Bones without such a reference (fingers, same-named extras) keep their rest twist relative
to their parent (shortest-arc alignment of the source's rest).
"""

from __future__ import annotations

import numpy as np

from avatar.motion import geometry
from avatar.motion.pairs import Pair, segment_rest, segments
from avatar.rig import quaternion
from avatar.rig.kinematics import rest_quaternions
from avatar.rig.skeleton import Skeleton

_BACK = np.array([0.0, 1.0, 0.0])  # Avatar characters face -Y: knees bend toward +Y
_UP = np.array([0.0, 0.0, 1.0])
_MIN_BEND = np.sin(np.radians(15.0))
STATS_FRAMES = 500  # a median over this many frames is as good as over all, and cheaper


class _Side:
    """Source (T frames) or target (rest, one frame) view of a skeleton, bone axis first:
    world rotations (J, T, 4), heads (J, T, 3) and, for the source, the pairs' segments."""

    def __init__(self, skeleton: Skeleton, rot: np.ndarray, pos: np.ndarray, segs=None):
        self.skeleton, self.rot, self.pos, self.segs = skeleton, rot, pos, segs

    def seg(self, pair: Pair, source: bool) -> np.ndarray:
        """(T, 3) the pair's segment on this side."""
        if source and self.segs is not None:
            return self.segs[pair.role]
        bone, end = (pair.source, pair.source_end) if source else (pair.target, pair.target_end)
        return segments(self.skeleton, self.rot, self.pos, [bone], [end])[0]


def offsets(pairs: list[Pair], source: Skeleton, src_rot: np.ndarray, src_pos: np.ndarray,
            target: Skeleton, src_seg: np.ndarray | None = None) -> np.ndarray:  # fmt: skip
    """(P, 4) alignment quaternion A per pair: target world = source world * A.

    src_rot: (Js, T, 4) source world rotations; src_pos: (Js, T, 3) heads (bone axis
    first); src_seg: (P, T, 3) the pairs' source segments (``pairs.segments``), computed
    when None. The statistics (medians over frames) use at most about ``STATS_FRAMES``
    frames spread evenly over the clip.
    """
    every = slice(None, None, -(-src_rot.shape[1] // STATS_FRAMES))
    src_rot, src_pos = src_rot[:, every], src_pos[:, every]
    if src_seg is None:
        src_seg = segments(source, src_rot, src_pos, [p.source for p in pairs],
                           [p.source_end for p in pairs])  # fmt: skip
    else:
        src_seg = src_seg[:, every]
    src = _Side(source, src_rot, src_pos, {p.role: src_seg[k] for k, p in enumerate(pairs)})
    tgt = _Side(target, rest_quaternions(target)[0][:, None], target.heads[:, None])
    refs = _references({p.role: p for p in pairs}, src, tgt)
    out = np.full((len(pairs), 3, 3), np.nan)
    rows = [(k, ref) for k, p in enumerate(pairs)
            if (ref := refs.get(_reference_name(p))) is not None]  # fmt: skip
    if rows:
        ks = [k for k, _ in rows]
        bones = [pairs[k].source for k in ks]
        world = np.concatenate([src_seg[ks], np.stack([r[0] for _, r in rows])])
        local = _local_median(src_rot[bones + bones], world)  # one median for all pairs
        rt = target.rest[[pairs[k].target for k in ks], :3, :3]
        e_t = np.stack([segment_rest(target, pairs[k].target, pairs[k].target_end) for k in ks])
        s_t = np.einsum("kba,kb->ka", rt, np.stack([r[1] for _, r in rows]))
        frame_t = geometry.frame(e_t, s_t)
        out[ks] = geometry.frame(local[: len(ks)], local[len(ks) :]) @ np.swapaxes(frame_t, -1, -2)
    _choose(out, pairs, source, target)
    return quaternion.from_matrix(out)


def _reference_name(pair: Pair) -> str | None:
    side = pair.role.rsplit(".", 1)[-1] if "." in pair.role else ""
    kind = pair.kind
    if pair.role in ("hips", "spine"):
        return "pelvis"
    if kind == "trunk":
        return "shoulders"
    if kind in ("thigh", "shin", "foot", "toe"):
        return f"knee.{side}"
    if kind in ("upperarm", "forearm"):
        return f"elbow.{side}"
    if kind == "clavicle":
        return "forward"
    return None


def _references(by_role: dict[str, Pair], src: _Side, tgt: _Side) -> dict:
    """name -> ((T, 3) source world vectors, (3,) target world vector)."""
    refs: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    pelvis = _line(by_role, src, tgt, "thigh")
    if pelvis is None:
        return refs
    refs["pelvis"] = pelvis
    refs["shoulders"] = _line(by_role, src, tgt, "upperarm") or pelvis
    fwd_s = np.cross(pelvis[0], _UP)
    refs["forward"] = (fwd_s, np.cross(pelvis[1], _UP))
    for side in ("L", "R"):
        refs[f"knee.{side}"] = _hinge(by_role, src, tgt, f"thigh.{side}", f"shin.{side}",
                                      _BACK, pelvis)  # fmt: skip
        refs[f"elbow.{side}"] = _hinge(by_role, src, tgt, f"upperarm.{side}",
                                       f"forearm.{side}", -_BACK, refs["forward"])  # fmt: skip
    return refs


def _line(by_role, src: _Side, tgt: _Side, role: str):
    """Right-to-left line between the heads of a bone pair (pelvis or shoulder width)."""
    left, right = by_role.get(f"{role}.L"), by_role.get(f"{role}.R")
    if left is None or right is None:
        return None
    s = src.pos[left.source] - src.pos[right.source]
    t = tgt.pos[left.target, 0] - tgt.pos[right.target, 0]
    return s, t


def _hinge(by_role, src: _Side, tgt: _Side, upper: str, lower: str, bend: np.ndarray, fallback):
    """A hinge axis (knee, elbow): from the clip's bent frames in the upper bone's frame,
    and for the target from its rest direction and the way the joint bends (``bend``)."""
    up, low = by_role.get(upper), by_role.get(lower)
    if up is None or low is None:
        return fallback
    cross = np.cross(geometry.unit(src.seg(up, True)), geometry.unit(src.seg(low, True)))
    bent = np.linalg.norm(cross, axis=-1) > _MIN_BEND
    if bent.sum() < 1:
        return fallback
    rot = src.rot[up.source]
    local = _local_median(rot[bent], cross[bent])
    world_s = quaternion.rotate(rot, local)
    world_t = geometry.unit(np.cross(tgt.seg(up, False)[0], bend))
    return world_s, world_t


def _local_median(rot: np.ndarray, world: np.ndarray) -> np.ndarray:
    """(..., 3) median over frames of world vectors (..., T, 3) seen in bone frames
    (..., T, 4)."""
    local = geometry.unit(quaternion.rotate(rot, world, inverse=True))
    return geometry.unit(np.median(local, axis=-2))


def _choose(out: np.ndarray, pairs: list[Pair], source: Skeleton, target: Skeleton):
    """Walk the source in its reference pose (the pose matching the target's rest): each
    paired bone turns by the shortest arc from its parent-relative rest onto the target's
    segment (rest alignment). Where that agrees with the anatomical alignment within
    ``REST_TRUST`` degrees (compatible rests: same skeleton, T vs A arms), keep it, so a
    skeleton retargets onto itself exactly; otherwise (folded or twisted rests) take the
    anatomical one. Pairs without an anatomical reference always use rest alignment."""
    local = source.local_rest()[:, :3, :3]
    of_source = {p.source: k for k, p in enumerate(pairs)}
    ref = np.empty((len(source.names), 3, 3))
    for j, parent in enumerate(source.parents):
        base = local[j] if parent < 0 else ref[parent] @ local[j]
        k = of_source.get(j)
        if k is None:
            ref[j] = base
            continue
        p, rt = pairs[k], target.rest[pairs[k].target, :3, :3]
        if p.role.startswith("="):
            # A same-named bone is the same bone of one rig family: it keeps its rest
            # relation to its parent. Its segment says nothing more (own tails are
            # invented by BVH readers; child joints differ with the body's shape).
            g = base
        else:
            e_s = segment_rest(source, p.source, p.source_end)
            want = rt @ segment_rest(target, p.target, p.target_end)
            g = _swing(base @ e_s, want) @ base
        rest_aligned = g.T @ rt
        if np.isnan(out[k, 0, 0]) or _degrees(rest_aligned, out[k]) < REST_TRUST:
            out[k] = rest_aligned
        ref[j] = rt @ out[k].T


REST_TRUST = 45.0


def _swing(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``geometry.swing`` for one pair of 3-vectors, with a handful of small operations
    (it runs once per pair, in a sequential walk): R = I + [v] + [v]^2 / (1 + c)."""
    a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
    c = float(a @ b)
    if c < -1.0 + 1e-9:
        return geometry.swing(a, b)
    x, y, z = a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]
    k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + k + (k @ k) / (1.0 + c)


def _degrees(a: np.ndarray, b: np.ndarray) -> float:
    """Angle of the rotation between two 3x3 rotations, degrees."""
    c = (np.trace(a.T @ b) - 1.0) / 2.0
    return float(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))))

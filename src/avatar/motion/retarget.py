"""Retarget an animation from one skeleton onto another (any convention, rest pose, size).

Steps (``retarget``):
1. select frames and resample to the wanted fps (source side, before anything else);
2. source forward kinematics: world bone rotations and heads per frame;
3. bone maps on both sides -> pairs of bones (canonical roles + identical names);
4. per-pair rest alignment ``A`` (``calibrate``): target world = source world * A;
5. transfer: mapped bones take the source's world rotation, turned per frame onto the
   source segment's direction; unmapped bones follow their parent; spine and neck chains
   of different lengths share the bend;
6. root path: the pelvis (between the hip joints) follows the source's, scaled by leg
   length, with ankle level on the floor mapped onto ankle level; the hips hang from it;
7. feet: contacts detected on the source stay planted on the target (two-bone leg IK),
   and frames that would put a sole under the floor rise onto it (``contacts.lift``);
8. world rotations -> pose-bone rotations/locations; quality metrics for the report;
9. with the target's ``body``: the motion settled on its skin (``floor.settle``), the final polish.

Per-frame arrays are quaternions and 3-vectors with the bone axis first, (J, T, 4) and
(J, T, 3), in float32 (see docs/benchmarks.md "Motion" for why); only bones that carry
driven bones or segment ends are evaluated.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from avatar.body.shaped import Body
from avatar.motion import (
    bonemap,
    calibrate,
    contacts,
    deformation,
    floor,
    geometry,
    metrics,
    timing,
)
from avatar.motion.pairs import Pair, make_pairs, segment_rest, segments
from avatar.rig import quaternion
from avatar.rig.kinematics import levels, rest_quaternions, world_pose
from avatar.rig.skeleton import Animation, Skeleton


@dataclass(frozen=True)
class RetargetReport:
    """What a retarget did and how well: mapping, scale, contacts, quality."""

    source_convention: str
    target_convention: str
    mapped: tuple[tuple[str, str, str], ...]  # (role, source bone, target bone)
    unmapped_target: tuple[str, ...]  # target bones that only follow their parent
    unused_source: tuple[str, ...]
    scale: float
    frames: int
    fps: float
    quality: metrics.Quality | None = None
    notes: tuple[str, ...] = field(default_factory=tuple)
    floor: floor.FloorReport | None = None  # onto a Human: its skin on the floor, settled

    def summary(self) -> str:
        """A few human-readable lines for logs and the CLI."""
        lines = [
            f"{self.source_convention} -> {self.target_convention}: {len(self.mapped)} bones "
            f"mapped, scale {self.scale:.3f}, {self.frames} frames at {self.fps:g} fps"
        ]
        if self.quality is not None:
            lines.append(self.quality.summary())
        if self.floor is not None:
            lines.append(self.floor.summary())
        lines.extend(self.notes)
        return "\n".join(lines)


# Per-frame work runs in float32: half the memory traffic of float64, rotation errors about
# 1e-4 degrees; set-up and the returned pose-bone values are float64.
_WORK_TYPE = np.float32


def _fixed(q: np.ndarray) -> np.ndarray:
    """(..., 4, 4) matrices M with x * q == x @ M for fixed rotations q (..., 4): a product
    of many quaternions by one is a matrix product (``quaternion.right_matrix``)."""
    return quaternion.right_matrix(q).astype(_WORK_TYPE)


@dataclass(frozen=True)
class _Source:
    """The clip in the world. Arrays here and in the steps below keep the bone axis first,
    (J, T, ...): per-bone gathers over all frames are then contiguous copies."""

    skeleton: Skeleton
    rot: np.ndarray  # (J, T, 4) world bone rotations (quaternions)
    pos: np.ndarray  # (J, T, 3) world heads

    def frames_first(self) -> _Source:
        """The same arrays viewed (T, J, ...), as the metrics take them."""
        return _Source(self.skeleton, self.rot.swapaxes(0, 1), self.pos.swapaxes(0, 1))


def retarget(
    source_skeleton: Skeleton,
    source_animation: Animation,
    target_skeleton: Skeleton,
    *,
    body: Body | None = None,
    source_map: bonemap.Convention = "auto",
    target_map: bonemap.Convention = "auto",
    frames: slice | None = None,
    fps: float | None = None,
    in_place: bool = False,
    fix_feet: bool = True,
    match_names: bool = True,
    measure: bool = True,
) -> tuple[Animation, RetargetReport]:
    """Transfer ``source_animation`` onto ``target_skeleton``.

    source_skeleton/source_animation: the clip (e.g. from ``avatar.motion.load_bvh``).
    target_skeleton: any rig (``Human(...).skeleton``), metres, Z-up, facing -Y, its rest
        pose standing on the floor (z = 0 for Avatar rigs).
    body: the shaped body on ``target_skeleton`` (``Human.body``), or None: the result is
        then settled on its skin (``floor.settle_body``: planted feet touch the floor, no
        vertex under it; ``RetargetReport.floor`` says how it meets it).
    source_map/target_map: convention name, bone map JSON path, {canonical: [names]}
        table (``bonemap.detect``), or "auto".
    frames: source frames to keep (slice, applied before resampling); fps: output rate.
    in_place: remove horizontal root motion. fix_feet: keep contacts planted, soles on the
        floor and out of it (leg IK, ``contacts.plant`` and ``contacts.lift``).
    match_names: also drive target bones whose names equal a source bone's.
    measure: compute ``RetargetReport.quality`` (cheap; off for the fastest batch runs).
    Returns the target ``Animation`` (T, J_target) and a ``RetargetReport``.
    """
    anim = timing.resample(timing.select(source_animation, frames), fps)
    src = _Source(source_skeleton, *world_pose(source_skeleton, anim.rotations, anim.translations,
                                               bones_first=True, dtype=_WORK_TYPE))  # fmt: skip
    smap = bonemap.detect(source_skeleton, source_map, src.pos.swapaxes(0, 1))
    tmap = bonemap.detect(target_skeleton, target_map)
    pairs = make_pairs(source_skeleton, smap, target_skeleton, tmap, match_names)
    src_seg = segments(source_skeleton, src.rot, src.pos, [p.source for p in pairs],
                       [p.source_end for p in pairs]).astype(_WORK_TYPE)  # fmt: skip
    align = calibrate.offsets(pairs, source_skeleton, src.rot, src.pos, target_skeleton, src_seg)
    world, rigid = _transfer(pairs, align, src, src_seg, target_skeleton)
    scale = _leg_length(target_skeleton, tmap) / _leg_length(source_skeleton, smap)
    hips = tmap.bones["hips"]
    root = _root_path(src, smap, tmap, target_skeleton, world, scale, in_place)
    feet = None
    if fix_feet or measure:
        leg = _leg_length(source_skeleton, smap)
        feet = contacts.detect(src.pos.swapaxes(0, 1), smap, anim.fps, leg)
    if feet is not None and fix_feet:
        world = contacts.plant(feet, tmap, target_skeleton, world, root, anim.fps)
        root[:, 2] += contacts.lift(target_skeleton, tmap, world, root, anim.fps)
    out = _to_local(target_skeleton, world, rigid, hips, root, anim.fps)
    quality = None
    if measure:
        ends = [p.target for p in pairs] + [_far(p) for p in pairs]
        pos = geometry.positions(target_skeleton, world, {hips: root},
                                 geometry.ancestors(target_skeleton, ends))  # fmt: skip
        framewise = (world.swapaxes(0, 1), pos.swapaxes(0, 1))  # metrics take (T, J, ...)
        quality = metrics.measure(pairs, src.frames_first(), target_skeleton, *framewise, tmap,
                                  feet, anim.fps)  # fmt: skip
    report = _report(pairs, smap, tmap, source_skeleton, target_skeleton, scale, out, quality)
    return (out, report) if body is None else _settle(body, out, report)


def _settle(body: Body, animation: Animation, report: RetargetReport):
    """The animation settled on the body's skin (planted feet on the floor, no vertex
    under it: ``floor.settle_body``) and the report with how it meets the floor now and,
    when measured, how it stretches the skin."""
    ground = floor.measure_body(body, animation)
    animation, shift = floor.settle_body(body, animation, report=ground)
    return animation, with_stretch(replace(report, floor=ground.shifted(shift)), body, animation)


def with_stretch(report: RetargetReport, body: Body, animation: Animation) -> RetargetReport:
    """``report`` with its quality's skin stretch of ``animation`` on ``body``
    (``deformation.measure``: per bone, the face, the eyes; bones over their limit are
    ``Quality.deformed``). Unchanged when the quality was not measured."""
    if report.quality is None:
        return report
    stretch = deformation.measure(body, animation)
    return replace(report, quality=report.quality.with_stretch(stretch))


def _transfer(pairs: list[Pair], align: np.ndarray, src: _Source, src_seg: np.ndarray,
              target: Skeleton) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """(Jt, T, 4) target world bone rotations (quaternions) and (Jt,) bool, the evaluated
    bones that keep their rest pose relative to their parent. Rows of bones not evaluated
    are left undefined (no memory touched) and marked NaN in frame 0."""
    world = np.empty((len(target.names), src.rot.shape[1], 4), _WORK_TYPE)
    world[:, 0, 0] = np.nan
    # source world * A, as one matrix product per pair (A is fixed)
    world[[p.target for p in pairs]] = src.rot[[p.source for p in pairs]] @ _fixed(align)
    # Bones that only follow their parent keep an identity pose rotation whatever happens
    # above them, so only those that carry driven bones or segment ends are evaluated.
    needed = geometry.ancestors(target, [p.target for p in pairs] + [_far(p) for p in pairs])
    free = np.isnan(world[:, 0, 0])
    rest, local = rest_quaternions(target)
    _inherit(world, target, local, free & needed)
    free &= ~_share_chains(world, pairs, target, rest)
    _aim(world, _aims(pairs, src, src_seg, target, free & needed, local))
    _inherit(world, target, local, free & needed)  # side branches follow the turned bones
    return world, free & needed


def _far(p: Pair) -> int:
    """The target bone whose head or tail ends a pair's segment (-1: none)."""
    return p.target_end if p.target_end >= -1 else -2 - p.target_end


def _inherit(world: np.ndarray, target: Skeleton, local: np.ndarray, which: np.ndarray) -> None:
    """Bones in ``which`` keep their rest pose relative to their parent (``local``: (J, 4)
    rest rotations relative to the parent), a level of the hierarchy at a time."""
    for group in levels(target.parents, which):
        p = target.parents[group]
        if p[0] < 0:
            world[group] = local[group, None]
        else:
            world[group] = world[p] @ _fixed(local[group])


@dataclass(frozen=True)
class _Aim:
    """Turn ``bones`` (about the first one's head) so that the sum of their world-rotated
    ``vectors`` (the segment they span) points along ``want`` (T, 3)."""

    bones: list[int]
    vectors: np.ndarray  # (len(bones), 3) in each bone's frame
    want: np.ndarray


def _aims(pairs: list[Pair], src: _Source, src_seg: np.ndarray, target: Skeleton,
          rigid: np.ndarray, local: np.ndarray) -> list[_Aim]:  # fmt: skip
    """Segment aims in the order they apply: trunk chains (start bone and in-between bones,
    far end along the source's start-to-end line; exact, the far end depends only on the
    chain's own rotations), then limb segments (a bone and any bones up to the segment's
    end) onto the source segment's direction, parents first."""
    off = geometry.offsets(target)
    by_role = {p.role: p for p in pairs}
    out = []
    for start, end in bonemap.CHAINS:
        a, b = by_role.get(start), by_role.get(end)
        if a is None or b is None:
            continue
        chain = geometry.path(target, a.target, b.target)
        if len(chain) >= 2:
            want = src.pos[b.source] - src.pos[a.source]
            aim = _Aim(chain[:-1], off[chain[1:]], want.astype(_WORK_TYPE))
            out.append(_rigid_folded(aim, rigid, local))
    limbs = [k for k in sorted(range(len(pairs)), key=lambda k: pairs[k].target)
             if pairs[k].kind != "trunk" and not pairs[k].role.startswith("=")]  # fmt: skip
    aimed = {pairs[k].target for k in limbs}  # same-named extras keep their twist
    for k in limbs:
        p = pairs[k]
        if p.target_end >= -1:  # up to the end bone's head, or along the bone itself
            path = (
                [p.target] if p.target_end == -1 else geometry.path(target, p.target, p.target_end)
            )
        else:  # the tail of a bone starting at this one's joint on one skeleton
            path = geometry.path(target, p.target, -2 - p.target_end)
        # A segment that runs over the next aimed bone (which starts at this one's joint on
        # one skeleton: CMU's finger base at the wrist) is aimed only up to that bone's
        # head, the same way; that bone follows its own pair (on the source both run along
        # one line), so both parts, and so the whole segment, follow the source.
        if not path:
            continue
        cut = next((i for i, j in enumerate(path[1:], 1) if j in aimed), None)
        if cut is not None:
            bones, vectors = path[:cut], off[path[1 : cut + 1]]
        elif p.target_end == -1 or p.target_end < -1:
            bones = path
            tail = segment_rest(target, path[-1], -1)[None]
            vectors = np.concatenate([off[path[1:]], tail])
        else:
            bones, vectors = path[:-1], off[path[1:]]
        if bones and np.linalg.norm(vectors.sum(axis=0)) > 1e-6:
            out.append(_rigid_folded(_Aim(bones, vectors, src_seg[k]), rigid, local))
    return out


def _rigid_folded(aim: _Aim, rigid: np.ndarray, local: np.ndarray) -> _Aim:
    """The same aim over fewer bones: a bone that keeps its rest pose relative to its parent
    (``rigid``; re-derived from the parent after the aims) adds its vector, turned by its
    rest rotation ``local`` (J, 4), to its parent's."""
    bones, vectors, carry = [], [], np.zeros(3)
    for j, v in zip(aim.bones[::-1], aim.vectors[::-1], strict=True):
        carry = carry + v
        if rigid[j] and j != aim.bones[0]:
            carry = quaternion.rotate(local[j], carry)
        else:
            bones.append(j)
            vectors.append(carry)
            carry = np.zeros(3)
    return _Aim(bones[::-1], np.array(vectors[::-1], _WORK_TYPE), aim.want)


def _aim(world: np.ndarray, aims: list[_Aim]) -> None:
    """Apply the aims in order, all those of one wave at once: an aim joins the first wave
    after every earlier aim that turns one of its bones (disjoint aims commute)."""
    waves: list[list[_Aim]] = []
    last: dict[int, int] = {}  # bone -> wave that last turns it
    for aim in aims:
        w = 1 + max((last.get(j, -1) for j in aim.bones), default=-1)
        if w == len(waves):
            waves.append([])
        waves[w].append(aim)
        last.update(dict.fromkeys(aim.bones, w))
    for wave in waves:
        bones = np.concatenate([a.bones for a in wave])
        sizes = [len(a.bones) for a in wave]
        turned = world[bones]
        terms = quaternion.rotate(turned, np.concatenate([a.vectors for a in wave])[:, None])
        have = np.add.reduceat(terms, np.cumsum([0] + sizes[:-1]), axis=0)
        turn = quaternion.between(have, np.stack([a.want for a in wave]))
        world[bones] = quaternion.multiply(np.repeat(turn, sizes, axis=0), turned)


def _share_chains(world: np.ndarray, pairs: list[Pair], target: Skeleton,
                  rest: np.ndarray) -> np.ndarray:  # fmt: skip
    """Undriven bones strictly between two mapped trunk bones (spine..chest, neck..head)
    turn by a blend of their ends' turns, weighted by position along the chain.
    rest: (J, 4) rest rotations. Returns (J,) bool: the bones set here."""
    driven = {p.role: p.target for p in pairs}
    targets = {p.target for p in pairs}
    done = np.zeros(len(target.names), dtype=bool)
    for start, end in bonemap.CHAINS:
        if start not in driven or end not in driven:
            continue
        chain = geometry.path(target, driven[start], driven[end])
        if len(chain) < 3:
            continue
        heads = target.heads[chain]
        cum = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(heads, axis=0), axis=1))])
        u = cum / max(cum[-1], 1e-9)
        inner = [i for i in range(1, len(chain) - 1) if chain[i] not in targets]
        if not inner:
            continue
        ends = [world[chain[i]] @ _fixed(quaternion.conjugate(rest[chain[i]]))
                for i in (0, -1)]  # fmt: skip
        weights = np.broadcast_to(u[inner, None], (len(inner), world.shape[1]))
        turn = quaternion.slerp(ends[0][None], ends[1][None], weights)
        bones = [chain[i] for i in inner]
        world[bones] = turn @ _fixed(rest[bones])
        done[bones] = True
    return done


def _leg_length(skeleton: Skeleton, bmap: bonemap.BoneMap) -> float:
    """Mean hip-to-ankle length along thigh and shin (metres); body height / 2 fallback."""
    total = []
    for side in ("L", "R"):
        roles = [f"{r}.{side}" for r in ("thigh", "shin", "foot")]
        if all(r in bmap.bones for r in roles):
            h = skeleton.heads[[bmap.bones[r] for r in roles]]
            total.append(np.linalg.norm(h[1] - h[0]) + np.linalg.norm(h[2] - h[1]))
    if total:
        return float(np.mean(total))
    return float(np.ptp(skeleton.heads[:, 2])) / 2 or 1.0


def _root_path(src: _Source, smap: bonemap.BoneMap, tmap: bonemap.BoneMap, target: Skeleton,
               world: np.ndarray, scale: float, in_place: bool) -> np.ndarray:  # fmt: skip
    """(T, 3) target hips heads: the source's pelvis scaled by leg length, its height above
    the source's ankles on the floor mapped to the target's above its rest ankles; the hips
    then placed from the target's pelvis, turned by the target's world rotations (J, T, 4).

    The pelvis is the midpoint of the hip (thigh) joints, not the hips joint: that sits
    level with them on MakeHuman rigs but 2-10 cm above them on CMU and Reallusion ones.
    Ankles, not the lowest foot joint: the legs scale from hip joint to ankle, and the
    ankle is at the same place on every rig (a toe joint is at the ball or the tip), so a
    frame standing on flat feet stands the target's ankles at their rest height, its soles
    on the floor they stand on in the rest pose.
    """
    pelvis = _pelvis(src.pos, smap) * scale
    ankles_s = contacts.foot_level(src.pos.swapaxes(0, 1), smap, ("foot.L", "foot.R"))
    ankles_t = [tmap.bones[r] for r in ("foot.L", "foot.R") if r in tmap.bones]
    rest_t = float(target.heads[ankles_t, 2].mean()) if ankles_t else 0.0
    pelvis[:, 2] += rest_t - scale * ankles_s
    hips = tmap.bones["hips"]
    legs = [tmap.bones[r] for r in ("thigh.L", "thigh.R") if r in tmap.bones]
    out = pelvis
    if legs and all(geometry.path(target, hips, j) for j in legs):  # thighs hang from hips
        zero = np.zeros((world.shape[1], 3))
        pos = geometry.positions(target, world, {hips: zero}, geometry.ancestors(target, legs))
        out = pelvis - _pelvis(pos, tmap)  # the target's pelvis relative to its hips head
    if in_place:
        out[:, :2] = target.heads[hips, :2]
    return out


def _pelvis(pos: np.ndarray, bmap: bonemap.BoneMap) -> np.ndarray:
    """(T, 3) float64 midpoint of the hip joints (thigh heads) from heads (J, T, 3); the
    hips head when a thigh is not mapped."""
    legs = [bmap.bones[r] for r in ("thigh.L", "thigh.R") if r in bmap.bones]
    if len(legs) < 2:
        return pos[bmap.bones["hips"]].astype(np.float64)
    return (pos[legs[0]].astype(np.float64) + pos[legs[1]]) / 2


def _to_local(target: Skeleton, world: np.ndarray, rigid: np.ndarray, hips: int,
              root: np.ndarray, fps: float):  # fmt: skip
    """World rotations (J, T, 4) and hips heads (T, 3) -> Blender pose-bone values.

    Bones left unevaluated (NaN: they only follow their parent) and ``rigid`` ones (J,)
    (evaluated, but in their rest pose relative to the parent) get the identity.
    """
    j, t = world.shape[:2]
    posed = ~np.isnan(world[:, 0, 0])
    parents = target.parents
    free = ~posed | rigid | ((parents >= 0) & ~posed[np.maximum(parents, 0)])
    bones = np.flatnonzero(~free)
    rest, local_rest = rest_quaternions(target)
    p = parents[bones]
    parent_world = world[np.maximum(p, 0)]
    parent_world[p < 0] = (1.0, 0.0, 0.0, 0.0)
    base = parent_world @ _fixed(local_rest[bones])  # each bone's frame before its pose
    local = quaternion.multiply(quaternion.conjugate(base), world[bones])
    local = local.astype(np.float64)
    local /= np.copysign(np.sqrt(np.einsum("...i,...i->...", local, local)), local[..., 0])[
        ..., None
    ]  # unit (float32 work rounds the norm at 1e-7) with w >= 0
    rotations = np.tile(np.array([1.0, 0.0, 0.0, 0.0]), (t, j, 1))  # identity everywhere
    # Bone-major -> frame-major, moving whole quaternions (32-byte items): ~3x faster than
    # numpy's strided copy of single floats.
    whole = np.dtype((np.void, 32))
    rotations.view(whole)[..., 0][:, bones] = local.view(whole)[..., 0].T
    translations = np.zeros((t, j, 3))
    ph = parents[hips]
    if ph < 0:
        head0, frame0 = target.heads[hips], rest[hips]
    else:
        pos = geometry.positions(target, world, {}, geometry.ancestors(target, [ph]))
        head0 = pos[ph] + quaternion.rotate(world[ph], geometry.offsets(target)[hips])
        frame0 = quaternion.multiply(world[ph], local_rest[hips])
    translations[:, hips] = quaternion.rotate(quaternion.conjugate(frame0), root - head0)
    return Animation(rotations, translations, float(fps), target.names)


def _report(pairs, smap, tmap, source, target, scale, out: Animation, quality) -> RetargetReport:
    used_s = {p.source for p in pairs}
    used_t = {p.target for p in pairs}
    notes = []
    for side, bmap, skeleton in (("source", smap, source), ("target", tmap, target)):
        if bmap.inferred:
            found = ", ".join(f"{r}={skeleton.names[bmap.bones[r]]}" for r in bmap.inferred)
            notes.append(f"{side} mapped by topology (names unknown): {found}")
        if bmap.missing:
            notes.append(f"{side} lacks {', '.join(bmap.missing)}")
    unused = [n for j, n in enumerate(source.names) if j not in used_s]
    if unused:
        shown = ", ".join(unused[:8]) + (", ..." if len(unused) > 8 else "")
        notes.append(f"{len(unused)} source bones not mapped: {shown}")
    return RetargetReport(
        source_convention=smap.convention,
        target_convention=tmap.convention,
        mapped=tuple((p.role, source.names[p.source], target.names[p.target]) for p in pairs),
        unmapped_target=tuple(n for j, n in enumerate(target.names) if j not in used_t),
        unused_source=tuple(unused),
        scale=float(scale),
        frames=out.frames,
        fps=out.fps,
        quality=quality,
        notes=tuple(notes),
    )

"""Retarget an animation from one skeleton onto another (any convention, rest pose, size).

Steps (``retarget``):
1. select frames and resample to the wanted fps (source side, before anything else);
2. source forward kinematics: world bone rotations and heads per frame;
3. bone maps on both sides -> pairs of bones (canonical roles + identical names);
4. per-pair rest alignment ``A`` (``calibrate``): target world = source world @ A;
5. transfer: mapped bones take the source's world rotation, turned per frame onto the
   source segment's direction; unmapped bones follow their parent; spine and neck chains
   of different lengths share the bend;
6. root path: the hips follow the source's, scaled by leg length, standing on the floor;
7. feet: contacts detected on the source stay planted on the target (two-bone leg IK);
8. world rotations -> pose-bone rotations/locations; quality metrics for the report.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from avatar.motion import bonemap, calibrate, contacts, geometry, metrics, timing
from avatar.motion.pairs import Pair, make_pairs, segment_rest, segment_world
from avatar.rig import quaternion
from avatar.rig.kinematics import forward
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

    def summary(self) -> str:
        """A few human-readable lines for logs and the CLI."""
        lines = [
            f"{self.source_convention} -> {self.target_convention}: {len(self.mapped)} bones "
            f"mapped, scale {self.scale:.3f}, {self.frames} frames at {self.fps:g} fps"
        ]
        if self.quality is not None:
            lines.append(self.quality.summary())
        lines.extend(self.notes)
        return "\n".join(lines)


@dataclass(frozen=True)
class _Source:
    skeleton: Skeleton
    rot: np.ndarray  # (T, J, 3, 3) world bone rotations
    pos: np.ndarray  # (T, J, 3) world heads


def retarget(
    source_skeleton: Skeleton,
    source_animation: Animation,
    target_skeleton: Skeleton,
    *,
    source_map: str | os.PathLike[str] = "auto",
    target_map: str | os.PathLike[str] = "auto",
    frames: slice | None = None,
    fps: float | None = None,
    in_place: bool = False,
    fix_feet: bool = True,
    match_names: bool = True,
    measure: bool = True,
) -> tuple[Animation, RetargetReport]:
    """Transfer ``source_animation`` onto ``target_skeleton``.

    source_skeleton/source_animation: the clip (e.g. from ``avatar.motion.load_bvh``).
    target_skeleton: any rig (``Human(...).skeleton``), metres, Z-up, facing -Y.
    source_map/target_map: convention name, bone map JSON path, or "auto".
    frames: source frames to keep (slice, applied before resampling); fps: output rate.
    in_place: remove horizontal root motion. fix_feet: keep contacts planted (leg IK).
    match_names: also drive target bones whose names equal a source bone's.
    measure: compute ``RetargetReport.quality`` (cheap; off for the fastest batch runs).
    Returns the target ``Animation`` (T, J_target) and a ``RetargetReport``.
    """
    anim = timing.resample(timing.select(source_animation, frames), fps)
    src = _forward(source_skeleton, anim)
    smap = bonemap.detect(source_skeleton, source_map, src.pos)
    tmap = bonemap.detect(target_skeleton, target_map)
    pairs = make_pairs(source_skeleton, smap, target_skeleton, tmap, match_names)
    align = calibrate.offsets(pairs, source_skeleton, src.rot, src.pos, target_skeleton)
    world = _transfer(pairs, align, src, target_skeleton)
    scale = _leg_length(target_skeleton, tmap) / _leg_length(source_skeleton, smap)
    hips = tmap.bones["hips"]
    root = _root_path(src, smap, tmap, target_skeleton, scale, in_place)
    feet = contacts.detect(src.pos, smap, anim.fps, _leg_length(source_skeleton, smap))
    if fix_feet:
        world = contacts.plant(feet, tmap, target_skeleton, world, root, anim.fps)
    out = _to_local(target_skeleton, world, hips, root, anim.fps)
    quality = None
    if measure:
        pos = geometry.positions(
            target_skeleton,
            world,
            {hips: root},
            _ancestors(target_skeleton, [p.target for p in pairs] + [_far(p) for p in pairs]),
        )
        quality = metrics.measure(pairs, src, target_skeleton, world, pos, tmap, feet, anim.fps)
    return out, _report(pairs, smap, tmap, source_skeleton, target_skeleton, scale, out, quality)


def _forward(skeleton: Skeleton, anim: Animation) -> _Source:
    world = forward(skeleton, anim.rotations, anim.translations)
    return _Source(skeleton, world[..., :3, :3], world[..., :3, 3])


def _transfer(pairs: list[Pair], align: np.ndarray, src: _Source, target: Skeleton) -> np.ndarray:
    """(T, Jt, 3, 3) target world bone rotations."""
    world = np.full((src.rot.shape[0], len(target.names), 3, 3), np.nan)
    for k, p in enumerate(pairs):
        world[:, p.target] = src.rot[:, p.source] @ align[k]
    # Bones that only follow their parent keep an identity pose rotation whatever happens
    # above them, so only those that carry driven bones or segment ends are evaluated.
    needed = _ancestors(target, [p.target for p in pairs] + [_far(p) for p in pairs])
    free = np.isnan(world[0, :, 0, 0])
    _inherit(world, target, free & needed)
    free &= ~_share_chains(world, pairs, target)
    _aim_chains(world, pairs, src, target)
    _aim_limbs(world, pairs, src, target)
    _inherit(world, target, free & needed)  # side branches follow the turned bones
    return world


def _far(p: Pair) -> int:
    """The target bone whose head or tail ends a pair's segment (-1: none)."""
    return p.target_end if p.target_end >= -1 else -2 - p.target_end


def _heads_along(target: Skeleton, world: np.ndarray, path: list[int]) -> np.ndarray:
    """(T, J, 3) heads of the bones on ``path`` relative to the first one (others NaN)."""
    off = geometry.offsets(target)
    pos = np.full(world.shape[:2] + (3,), np.nan)
    pos[:, path[0]] = 0.0
    for parent, j in zip(path[:-1], path[1:], strict=True):
        pos[:, j] = pos[:, parent] + world[:, parent] @ off[j]
    return pos


def _ancestors(skeleton: Skeleton, bones) -> np.ndarray:
    """(J,) bool: the given bones (negative ones ignored) and all their ancestors."""
    out = np.zeros(len(skeleton.names), dtype=bool)
    for j in bones:
        while j >= 0 and not out[j]:
            out[j] = True
            j = int(skeleton.parents[j])
    return out


def _inherit(world: np.ndarray, target: Skeleton, which: np.ndarray) -> None:
    """Bones in ``which`` keep their rest pose relative to their parent."""
    local = target.local_rest()[:, :3, :3]
    for j in np.flatnonzero(which):
        parent = target.parents[j]
        world[:, j] = local[j] if parent < 0 else world[:, parent] @ local[j]


def _aim_limbs(world: np.ndarray, pairs: list[Pair], src: _Source, target: Skeleton) -> None:
    """Turn each limb segment (its bone and any bones up to the segment's end, about the
    bone's head) onto the source segment's direction, parents first."""
    off = geometry.offsets(target)
    for p in sorted(pairs, key=lambda p: p.target):
        if p.kind == "trunk" or p.role.startswith("="):  # same-named extras keep their twist
            continue
        want = segment_world(src.skeleton, src.rot, src.pos, p.source, p.source_end)
        if p.target_end == -1:
            have = world[:, p.target] @ segment_rest(target, p.target, p.target_end)
            path = [p.target]
        elif p.target_end < -1:  # the tail of a bone starting at this one's head
            other = -2 - p.target_end
            path = _path(target, p.target, other)
            have = segment_world(target, world, _heads_along(target, world, path), p.target,
                                 p.target_end)  # fmt: skip
        else:
            path = _path(target, p.target, p.target_end)[:-1]
            if not path:
                continue
            have = sum(world[:, j] @ off[c] for j, c in zip(path, path[1:] + [p.target_end],
                                                          strict=True))  # fmt: skip
        turn = geometry.swing(have, want)
        world[:, path] = turn[:, None] @ world[:, path]


def _share_chains(world: np.ndarray, pairs: list[Pair], target: Skeleton) -> np.ndarray:
    """Undriven bones strictly between two mapped trunk bones (spine..chest, neck..head)
    turn by a blend of their ends' turns, weighted by position along the chain.
    Returns (J,) bool: the bones set here."""
    driven = {p.role: p.target for p in pairs}
    targets = {p.target for p in pairs}
    rest = target.rest[:, :3, :3]
    done = np.zeros(len(target.names), dtype=bool)
    for start, end in bonemap.CHAINS:
        if start not in driven or end not in driven:
            continue
        chain = _path(target, driven[start], driven[end])
        if len(chain) < 3:
            continue
        heads = target.heads[chain]
        cum = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(heads, axis=0), axis=1))])
        u = cum / max(cum[-1], 1e-9)
        q0 = quaternion.from_matrix(world[:, chain[0]] @ rest[chain[0]].T)
        q1 = quaternion.from_matrix(world[:, chain[-1]] @ rest[chain[-1]].T)
        for i, j in enumerate(chain[1:-1], 1):
            if j in targets:
                continue
            turn = quaternion.slerp(q0, q1, np.full(len(q0), u[i]))
            world[:, j] = quaternion.to_matrix(turn) @ rest[j]
            done[j] = True
    return done


def _aim_chains(world: np.ndarray, pairs: list[Pair], src: _Source, target: Skeleton) -> None:
    """Turn each trunk chain (start bone and in-between bones, about the start's head) so
    the chain's far end lies along the source's start-to-end segment. Exact: the far end
    depends only on the chain's own rotations."""
    by_role = {p.role: p for p in pairs}
    off = geometry.offsets(target)
    for start, end in bonemap.CHAINS:
        a, b = by_role.get(start), by_role.get(end)
        if a is None or b is None:
            continue
        chain = _path(target, a.target, b.target)
        if len(chain) < 2:
            continue
        reach = np.zeros((world.shape[0], 3))
        for j, child in zip(chain[:-1], chain[1:], strict=True):
            reach += world[:, j] @ off[child]
        want = src.pos[:, b.source] - src.pos[:, a.source]
        turn = geometry.swing(reach, want)
        world[:, chain[:-1]] = turn[:, None] @ world[:, chain[:-1]]


def _path(skeleton: Skeleton, top: int, bottom: int) -> list[int]:
    """Bones from ``top`` down to ``bottom`` (inclusive); [] when not an ancestor."""
    path = [bottom]
    while path[-1] != top:
        parent = int(skeleton.parents[path[-1]])
        if parent < 0:
            return []
        path.append(parent)
    return path[::-1]


def _leg_length(skeleton: Skeleton, bmap: bonemap.BoneMap) -> float:
    """Mean hip-to-ankle length along thigh and shin (metres); body height / 2 fallback."""
    total = []
    for side in ("L", "R"):
        b = [bmap.bones.get(f"{r}.{side}") for r in ("thigh", "shin", "foot")]
        if None not in b:
            h = skeleton.heads[b]
            total.append(np.linalg.norm(h[1] - h[0]) + np.linalg.norm(h[2] - h[1]))
    if total:
        return float(np.mean(total))
    return float(np.ptp(skeleton.heads[:, 2])) / 2 or 1.0


def _root_path(src: _Source, smap, tmap, target: Skeleton, scale: float, in_place: bool):
    """(T, 3) target hips positions: the source's scaled, with foot level mapped to foot
    level (each skeleton's lowest foot joint in contact lands on the other's)."""
    hips_s = src.pos[:, smap.bones["hips"]]
    floor_s = contacts.foot_level(src.pos, smap)
    feet_t = [tmap.bones[b] for b in contacts.FOOT_ROLES if b in tmap.bones]
    floor_t = float(target.heads[feet_t, 2].min()) if feet_t else 0.0
    out = hips_s * scale
    out[:, 2] = floor_t + scale * (hips_s[:, 2] - floor_s)
    if in_place:
        out[:, :2] = target.heads[tmap.bones["hips"], :2]
    return out


def _to_local(target: Skeleton, world: np.ndarray, hips: int, root: np.ndarray, fps: float):
    """World rotations (T, J, 3, 3) and hips heads (T, 3) -> Blender pose-bone values.

    Bones left unevaluated (NaN: they only follow their parent) get the identity.
    """
    t, j = world.shape[:2]
    posed = ~np.isnan(world[0, :, 0, 0])
    parents = target.parents
    free = ~posed | ((parents >= 0) & ~posed[np.maximum(parents, 0)])
    bones = np.flatnonzero(~free)
    local_rest = target.local_rest()[bones, :3, :3]
    p = parents[bones]
    parent_world = np.where((p >= 0)[None, :, None, None], world[:, np.maximum(p, 0)], np.eye(3))
    base = parent_world @ local_rest  # each bone's frame before its own pose rotation
    rotations = np.zeros((t, j, 4))
    rotations[..., 0] = 1.0
    rotations[:, bones] = quaternion.from_matrix(np.swapaxes(base, -1, -2) @ world[:, bones])
    translations = np.zeros((t, j, 3))
    ph = parents[hips]
    if ph < 0:
        head0, frame0 = target.heads[hips], target.rest[hips, :3, :3]
    else:
        anc = _ancestors(target, [ph])
        pos = geometry.positions(target, world, {}, anc)
        head0 = pos[:, ph] + world[:, ph] @ geometry.offsets(target)[hips]
        frame0 = world[:, ph] @ target.local_rest()[hips, :3, :3]
    translations[:, hips] = np.einsum("...ba,...b->...a", frame0, root - head0)
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

"""Floor contact of the skinned body: penetration below z = 0 and hovering during contacts.

Joint heights say little about the mesh (a heel or a toe tip lies centimetres below its
joint), so this skins the body surface and looks at its lowest point:
1. pick frames (every frame of short clips, an even subsample of long ones);
2. forward kinematics on every frame; skin the body vertices (helpers excluded) on the
   picked frames in chunks (LBS, as the exporters' viewers do);
3. penetration: the lowest vertex below the floor, per frame;
4. hover: while a foot is in contact (its ankle or toe still, ``contacts.detect``) at its
   lowest level over the clip (not on a step), the height of that foot's lowest sole
   vertex above the floor.
``settle`` moves a motion up or down, frame by frame, so planted feet touch the floor.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from avatar.body.shaped import Body
from avatar.motion import bonemap, contacts
from avatar.rig import kinematics, skinning
from avatar.rig.skeleton import Animation, Skeleton
from avatar.rig.skinning import SkinWeights

_TOLERANCE = 0.001  # metres below the floor that count as touching, not penetrating
_STEP = 0.05  # metres: a contact this far above the foot's lowest level is on a step/box
_CHUNK = 32


@dataclass(frozen=True)
class FloorReport:
    """How the skinned body meets the floor (z = 0) over an animation.

    frames: frames measured (of ``total_frames``).
    penetration_cm: deepest body vertex below the floor over those frames (0 when none).
    penetrating: fraction of measured frames with a vertex over 1 mm below the floor.
    hover_cm: median height of a planted foot's lowest sole vertex above the floor over
        floor contacts (0 when there are none); hover_max_cm: its maximum.
    contact_frames: measured frames with a foot planted near the floor.
    lowest_cm: (frames,) lowest body vertex per measured frame (cm; negative: below).
    contact_cm: (frames,) lowest sole vertex of the planted feet per measured frame (cm;
        NaN where no foot is planted on the floor).
    sampled: (frames,) the frame indices measured.
    """

    frames: int
    total_frames: int
    penetration_cm: float
    penetrating: float
    hover_cm: float
    hover_max_cm: float
    contact_frames: int
    lowest_cm: np.ndarray
    contact_cm: np.ndarray
    sampled: np.ndarray

    def summary(self) -> str:
        return (
            f"mesh on floor: penetration {self.penetration_cm:.2f} cm max, in "
            f"{self.penetrating * 100:.0f}% of frames; feet hover {self.hover_cm:.2f} cm "
            f"(max {self.hover_max_cm:.2f}) over {self.contact_frames} contact frames "
            f"({self.frames} of {self.total_frames} frames skinned)"
        )

    def as_dict(self) -> dict:
        arrays = ("lowest_cm", "contact_cm", "sampled")
        return {k: getattr(self, k) for k in self.__dataclass_fields__ if k not in arrays}

    @classmethod
    def of(cls, total: int, sampled: np.ndarray, lowest_m: np.ndarray, contact_m: np.ndarray):
        """The report from per-frame lowest vertex and planted sole heights (metres)."""
        hover = np.maximum(contact_m[~np.isnan(contact_m)], 0.0)
        depth = np.maximum(-lowest_m, 0.0)
        return cls(
            frames=len(sampled),
            total_frames=total,
            penetration_cm=float(depth.max(initial=0.0) * 100),
            penetrating=float(np.mean(depth > _TOLERANCE)) if len(sampled) else 0.0,
            hover_cm=float(np.median(hover) * 100) if len(hover) else 0.0,
            hover_max_cm=float(hover.max() * 100) if len(hover) else 0.0,
            contact_frames=len(hover),
            lowest_cm=lowest_m * 100,
            contact_cm=contact_m * 100,
            sampled=sampled,
        )

    def shifted(self, shift: np.ndarray) -> FloorReport:
        """The report after moving the body up by ``shift`` (T,) metres per frame (what
        ``settle`` does), without skinning again: heights move by the shift; the contact
        frames are kept."""
        dz = np.asarray(shift, dtype=float)[self.sampled]
        return FloorReport.of(self.total_frames, self.sampled, self.lowest_cm / 100 + dz,
                              self.contact_cm / 100 + dz)  # fmt: skip


def pick_frames(total: int, most: int) -> np.ndarray:
    """(n,) frame indices: all when ``total <= most``, else ``most`` evenly spaced."""
    if total <= most:
        return np.arange(total)
    return np.unique(np.linspace(0, total - 1, most).round().astype(int))


def measure(
    skeleton: Skeleton,
    vertices: np.ndarray,
    weights: SkinWeights,
    animation: Animation,
    most_frames: int = 300,
) -> FloorReport:
    """Penetration and hover of a skinned surface over ``animation``.

    skeleton: the rig (J bones) the animation drives; vertices: (V, 3) rest positions of
    the surface to test (e.g. ``human.vertices[human.part_vertices("body")]``, feet on
    z = 0); weights: their skin weights over the J bones; animation: (T, J) motion;
    most_frames: skin at most this many frames (evenly spaced).
    """
    world = kinematics.forward(skeleton, animation.rotations, animation.translations)
    frames = pick_frames(animation.frames, most_frames)
    soles = _soles(skeleton, weights)
    lowest = np.empty(len(frames))
    sole_low = {side: np.full(len(frames), np.inf) for side in soles}
    inverse_rest = np.linalg.inv(skeleton.rest)
    for start in range(0, len(frames), _CHUNK):
        pick = frames[start : start + _CHUNK]
        posed = skinning.linear_blend(vertices, weights, world[pick] @ inverse_rest)
        lowest[start : start + len(pick)] = posed[..., 2].min(axis=1)
        for side, mask in soles.items():
            sole_low[side][start : start + len(pick)] = posed[:, mask, 2].min(axis=1)
    heights = _contacts(skeleton, world, animation.fps, frames, sole_low)
    return FloorReport.of(animation.frames, frames, lowest, heights)


def _soles(skeleton: Skeleton, weights: SkinWeights) -> dict[str, np.ndarray]:
    """side -> (V,) bool: vertices moved mostly by that foot (its bone and those below)."""
    bmap = bonemap.detect(skeleton)
    out = {}
    dense = weights.dense(len(skeleton.names))
    for side in ("L", "R"):
        foot = bmap.bones.get(f"foot.{side}")
        if foot is None:
            continue
        below = np.zeros(len(skeleton.names), dtype=bool)
        below[foot] = True
        for j, p in enumerate(skeleton.parents):  # parents precede children
            if p >= 0 and below[p]:
                below[j] = True
        mask = dense[:, below].sum(axis=1) > 0.5
        if mask.any():
            out[side] = mask
    return out


def _contacts(skeleton: Skeleton, world: np.ndarray, fps: float, frames: np.ndarray,
              sole_low: dict[str, np.ndarray]) -> np.ndarray:  # fmt: skip
    """(n,) per picked frame, the lowest sole vertex (m) of the feet planted on the floor
    (NaN: none)."""
    bmap = bonemap.detect(skeleton)
    pos = world[..., :3, 3]
    thigh, foot = bmap.bones.get("thigh.L"), bmap.bones.get("foot.L")
    leg = float(np.linalg.norm(skeleton.heads[thigh] - skeleton.heads[foot])) if (
        thigh is not None and foot is not None) else 0.9  # fmt: skip
    planted = contacts.detect(pos, bmap, fps, leg)
    out = np.full(len(frames), np.inf)
    for side, low in sole_low.items():
        # The floor is the lowest level the foot gets to; contacts well above it are on
        # steps or boxes. Relative, so a whole character hovering still counts.
        level = np.percentile(low, 5) if len(low) else 0.0
        down = planted.frames(side)[frames] & (low < max(level, 0.0) + _STEP)
        out[down] = np.minimum(out[down], low[down])
    out[np.isinf(out)] = np.nan
    return out


def measure_body(body: Body, animation: Animation, most_frames: int = 300) -> FloorReport:
    """``measure`` on a shaped body's skin (13,380 vertices; helpers, eyes excluded)."""
    return measure(body.skeleton, body.vertices[body.skin_index], body.skin_weights, animation,
                   most_frames)  # fmt: skip


def settle(
    skeleton: Skeleton,
    vertices: np.ndarray,
    weights: SkinWeights,
    animation: Animation,
    most_frames: int = 300,
    per_frame: bool = True,
    report: FloorReport | None = None,
) -> tuple[Animation, np.ndarray]:
    """The motion moved up or down so that planted feet touch the floor.

    per_frame: each frame with a foot planted on the floor is shifted so that foot's
    lowest sole vertex is at z = 0; frames between contacts (steps, jumps) blend linearly
    between the shifts around them, smoothed over 0.1 s, and any frame whose lowest
    vertex would still be under the floor is lifted onto it. False: one shift for the whole
    clip (the median of those). Without contacts (a single pose, a clip in the air) the
    lowest vertex (5th percentile over frames) goes to the floor.
    Arguments as ``measure``; ``report``: its result when already at hand. Returns the
    moved Animation and the (T,) shifts (metres); ``report.shifted(shifts)`` tells how it
    meets the floor now.
    """
    report = report or measure(skeleton, vertices, weights, animation, most_frames)
    heights = report.contact_cm / 100
    down = ~np.isnan(heights)
    t = animation.frames
    if not down.any():
        shift = np.full(t, -float(np.percentile(report.lowest_cm, 5)) / 100)
    elif not per_frame or down.sum() < 2:
        shift = np.full(t, -float(np.median(heights[down])))
    else:
        shift = np.interp(np.arange(t), report.sampled[down], -heights[down])
        shift = _smooth(shift, max(1, int(round(0.1 * animation.fps))))
    if per_frame:
        # Never below the floor: frames between contacts (heel strike, toe off) lift the
        # body as far as their lowest vertex needs.
        lift = np.interp(np.arange(t), report.sampled, -report.lowest_cm / 100)
        shift = np.maximum(shift, lift)
    return raise_by(skeleton, animation, shift), shift


def _smooth(x: np.ndarray, width: int) -> np.ndarray:
    """Moving average over ``width`` frames (edges padded with the end values)."""
    if width < 2 or len(x) < 2:
        return x
    pad = np.pad(x, (width // 2, width - 1 - width // 2), mode="edge")
    return np.convolve(pad, np.ones(width) / width, mode="valid")


def raise_by(skeleton: Skeleton, animation: Animation, dz) -> Animation:
    """The animation with the whole body moved up by ``dz`` metres (scalar or (T,)),
    through the hips' location."""
    hips = bonemap.detect(skeleton).bones["hips"]
    parent = int(skeleton.parents[hips])
    frame = skeleton.local_rest()[hips, :3, :3]
    if parent >= 0:
        world = kinematics.forward(skeleton, animation.rotations, animation.translations)
        frame = world[:, parent, :3, :3] @ frame
    up = np.zeros((animation.frames, 3))
    up[:, 2] = dz
    translations = animation.translations.copy()
    translations[:, hips] += np.einsum("...ba,...b->...a", frame, up)
    return Animation(animation.rotations, translations, animation.fps, animation.bone_names)


def settle_body(body: Body, animation: Animation, most_frames: int = 300, per_frame: bool = True,
                report: FloorReport | None = None):  # fmt: skip
    """``settle`` on a shaped body's skin; returns (animation, (T,) shifts in metres)."""
    return settle(body.skeleton, body.vertices[body.skin_index], body.skin_weights, animation,
                  most_frames, per_frame, report)  # fmt: skip

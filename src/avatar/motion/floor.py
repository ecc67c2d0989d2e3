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
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

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
    """

    frames: int
    total_frames: int
    penetration_cm: float
    penetrating: float
    hover_cm: float
    hover_max_cm: float
    contact_frames: int
    lowest_cm: np.ndarray

    def summary(self) -> str:
        return (
            f"mesh on floor: penetration {self.penetration_cm:.2f} cm max, in "
            f"{self.penetrating * 100:.0f}% of frames; feet hover {self.hover_cm:.2f} cm "
            f"(max {self.hover_max_cm:.2f}) over {self.contact_frames} contact frames "
            f"({self.frames} of {self.total_frames} frames skinned)"
        )

    def as_dict(self) -> dict:
        return {k: getattr(self, k) for k in self.__dataclass_fields__ if k != "lowest_cm"}


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
    hover = _hover(skeleton, world, animation.fps, frames, sole_low)
    depth = np.maximum(-lowest, 0.0)
    return FloorReport(
        frames=len(frames),
        total_frames=animation.frames,
        penetration_cm=float(depth.max(initial=0.0) * 100),
        penetrating=float(np.mean(depth > _TOLERANCE)) if len(frames) else 0.0,
        hover_cm=float(np.median(hover) * 100) if len(hover) else 0.0,
        hover_max_cm=float(hover.max() * 100) if len(hover) else 0.0,
        contact_frames=len(hover),
        lowest_cm=lowest * 100,
    )


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


def _hover(skeleton: Skeleton, world: np.ndarray, fps: float, frames: np.ndarray,
           sole_low: dict[str, np.ndarray]) -> np.ndarray:  # fmt: skip
    """(n,) heights (m, >= 0) of planted feet's lowest sole vertices over floor contacts."""
    bmap = bonemap.detect(skeleton)
    pos = world[..., :3, 3]
    thigh, foot = bmap.bones.get("thigh.L"), bmap.bones.get("foot.L")
    leg = float(np.linalg.norm(skeleton.heads[thigh] - skeleton.heads[foot])) if (
        thigh is not None and foot is not None) else 0.9  # fmt: skip
    planted = contacts.detect(pos, bmap, fps, leg)
    out = []
    for side, low in sole_low.items():
        # The floor is the lowest level the foot gets to; contacts well above it are on
        # steps or boxes. Relative, so a whole character hovering still counts.
        level = np.percentile(low, 5) if len(low) else 0.0
        down = planted.frames(side)[frames] & (low < max(level, 0.0) + _STEP)
        out.append(np.maximum(low[down], 0.0))
    return np.concatenate(out) if out else np.zeros(0)


def measure_human(human, animation: Animation, most_frames: int = 300) -> FloorReport:
    """``measure`` on a Human's skin (13,380 body vertices; helpers, eyes excluded)."""
    index = human.part_vertices("body")
    return measure(human.skeleton, human.vertices[index], human.weights.subset(index),
                   animation, most_frames)  # fmt: skip

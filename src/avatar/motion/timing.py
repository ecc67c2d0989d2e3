"""Frame ranges and frame-rate changes of an ``Animation``."""

from __future__ import annotations

import numpy as np

from avatar.errors import ParameterError
from avatar.rig import quaternion
from avatar.rig.skeleton import Animation


def parse_frames(text: str | None) -> slice | None:
    """ "A:B" (either side optional, B exclusive, Python style) -> slice; None -> None."""
    if text is None or text == "":
        return None
    parts = text.split(":")
    try:
        if len(parts) != 2:
            raise ValueError
        start, stop = (int(p) if p.strip() else None for p in parts)
    except ValueError:
        raise ParameterError(f"frames must look like A:B, got {text!r}") from None
    return slice(start, stop)


def select(animation: Animation, frames: slice | None) -> Animation:
    """The frames in ``frames`` (a slice); raises ParameterError when it selects nothing
    (or the animation has no frame at all)."""
    if animation.frames == 0:
        raise ParameterError("the clip has no frames")
    if frames is None:
        return animation
    rot, trans = animation.rotations[frames], animation.translations[frames]
    if len(rot) == 0:
        raise ParameterError(f"frame range {frames} selects no frame of {animation.frames}")
    return Animation(rot, trans, animation.fps, animation.bone_names)


def resample(animation: Animation, fps: float | None) -> Animation:
    """Resample to ``fps`` frames per second: slerp rotations, lerp translations.

    The first frame is kept; the last new frame is the last one not past the clip's end.
    """
    if fps is None or abs(fps - animation.fps) < 1e-9 or animation.frames < 2:
        return animation if fps is None else _with_fps(animation, fps)
    if fps <= 0:
        raise ParameterError(f"fps must be positive, got {fps}")
    duration = (animation.frames - 1) / animation.fps
    t = np.arange(int(np.floor(duration * fps + 1e-9)) + 1) * (animation.fps / fps)
    i0 = np.minimum(np.floor(t).astype(int), animation.frames - 2)
    w = t - i0
    r0, r1 = animation.rotations[i0], animation.rotations[i0 + 1]
    rot = quaternion.slerp(r0, r1, np.broadcast_to(w[:, None], r0.shape[:-1]))
    tr0, tr1 = animation.translations[i0], animation.translations[i0 + 1]
    trans = tr0 + (tr1 - tr0) * w[:, None, None]
    return Animation(rot, trans, float(fps), animation.bone_names)


def _with_fps(animation: Animation, fps: float) -> Animation:
    return Animation(animation.rotations, animation.translations, float(fps), animation.bone_names)

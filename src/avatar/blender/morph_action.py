"""Morph weights over time -> an action on a mesh's shape keys (Blender 4.4+ slotted actions).

The baked garment corrections (``avatar.clothes.bake``) are a few correction shape keys a
garment, driven by per-frame values (their weights at each frame, held until the next:
glTF's STEP). Each weight column becomes one F-curve on its shape key's ``value`` with
CONSTANT interpolation, keyed only where the value changes, written as whole arrays with
``foreach_set`` like ``avatar.blender.action``.
"""

from __future__ import annotations

from collections.abc import Sequence

import bpy
import numpy as np

from avatar.blender.action import CONSTANT, new_action, write_curve
from avatar.errors import AvatarError


def apply_morph_weights(
    obj: bpy.types.Object,
    names: Sequence[str],
    weights: np.ndarray,
    action_name: str = "Avatar morphs",
    frame_start: int = 1,
) -> bpy.types.Action | None:
    """Key ``obj``'s shape keys ``names`` with ``weights`` (T, len(names)) at frames
    frame_start .. frame_start + T - 1; columns that stay 0 get no F-curve.

    Returns the action assigned to the mesh's Key datablock, or None when nothing moves.
    Raises AvatarError when a name is not a shape key of ``obj``.
    """
    weights = np.asarray(weights, dtype=np.float32)
    if weights.ndim != 2 or weights.shape[1] != len(names):
        raise AvatarError(f"morph weights of {obj.name!r} must be (T, {len(names)}), "
                          f"got {weights.shape}")  # fmt: skip
    keys = obj.data.shape_keys
    missing = [n for n in names if keys is None or n not in keys.key_blocks]
    if missing:
        raise AvatarError(f"{obj.name!r} has no shape key {missing[0]!r}")
    moving = np.flatnonzero(np.any(weights != 0, axis=0))
    if not len(moving):
        return None
    action, channelbag = new_action(keys, "KEY", action_name)
    for k in moving:
        _write_steps(channelbag, names[k], weights[:, k], frame_start)
    return action


def _write_steps(channelbag, name: str, values: np.ndarray, frame_start: int) -> None:
    """One CONSTANT F-curve ``key_blocks[name].value`` keyed at the first frame and wherever
    ``values`` (T,) changes; constant extrapolation holds the ends."""
    at = np.concatenate([[0], np.flatnonzero(np.diff(values) != 0) + 1])
    path = f'key_blocks["{bpy.utils.escape_identifier(name)}"].value'
    write_curve(channelbag, path, frame_start + at, values[at], CONSTANT)

"""Animation record -> Blender action on an armature.

Slotted actions (Blender 4.4+: ``Action.slots``, F-curves in a slot's channelbag) are
feature-detected; older Blenders (4.2 LTS, 3.x) get a legacy action whose ``fcurves``
hold the curves. Both paths write the same curves.

Keyframes are written as whole arrays with ``foreach_set`` (about 6x faster than
``keyframe_insert``), one F-curve per quaternion/location channel, linear interpolation
because the record is already sampled once per frame.
"""

from __future__ import annotations

import bpy
import numpy as np

from avatar.rig.skeleton import Animation

CONSTANT, LINEAR = 0, 1  # Keyframe.interpolation enum values


def apply_animation(
    armature_obj: bpy.types.Object,
    animation: Animation,
    name: str = "Avatar motion",
    frame_start: int = 1,
    scene: bpy.types.Scene | None = None,
) -> bpy.types.Action:
    """Create an action from ``animation`` and assign it to ``armature_obj``.

    animation.rotations (T, J, 4) wxyz and translations (T, J, 3) become the pose bones'
    ``rotation_quaternion`` and ``location`` at frames frame_start .. frame_start + T - 1.
    Bones of the animation missing from the armature are skipped. The scene's frame range
    and fps are set to the clip's.
    """
    action, channelbag = new_action(armature_obj, "OBJECT", name)
    frames = frame_start + np.arange(animation.frames, dtype=np.float32)
    for j, bone in enumerate(animation.bone_names):
        pose_bone = armature_obj.pose.bones.get(bone)
        if pose_bone is None:
            continue
        pose_bone.rotation_mode = "QUATERNION"
        group = channelbag.groups.new(bone)
        _write_channels(channelbag, group, bone, "rotation_quaternion",
                        frames, animation.rotations[:, j])  # fmt: skip
        if np.any(animation.translations[:, j]):
            _write_channels(channelbag, group, bone, "location",
                            frames, animation.translations[:, j])  # fmt: skip
    set_frame_range(scene or bpy.context.scene, frame_start, animation.frames, animation.fps)
    return action


def _write_channels(channelbag, group, bone: str, prop: str, frames, values) -> None:
    """values: (T, C) -> C F-curves ``pose.bones[bone].prop[c]`` keyed at ``frames`` (T,)."""
    path = f'pose.bones["{bpy.utils.escape_identifier(bone)}"].{prop}'
    for c in range(values.shape[1]):
        write_curve(channelbag, path, frames, values[:, c], LINEAR, index=c, group=group)


def new_action(owner, id_type: str, name: str):
    """A new action assigned to ``owner`` (an Object, a Key, ...; ``id_type`` its slot type,
    e.g. "OBJECT", "KEY"). Returns (action, the collection to add F-curves and groups to):
    the slot's channelbag where actions have slots, else the legacy action itself (its
    ``fcurves.new`` and ``groups.new`` take the same arguments)."""
    action = bpy.data.actions.new(name)
    owner.animation_data_create()
    if not has_slots():
        owner.animation_data.action = action
        return action, action
    slot = action.slots.new(id_type=id_type, name=owner.name)
    owner.animation_data.action = action
    owner.animation_data.action_slot = slot
    return action, _ensure_channelbag(action, slot)


def _ensure_channelbag(action: bpy.types.Action, slot):
    """The slot's channelbag on the action's first keyframe strip, made if missing (what
    ``bpy_extras.anim_utils.action_ensure_channelbag_for_slot`` does from 4.5; Blender 4.4
    has slots but not that function)."""
    layer = action.layers[0] if len(action.layers) else action.layers.new("Layer")
    strip = layer.strips[0] if len(layer.strips) else layer.strips.new(type="KEYFRAME")
    return strip.channelbag(slot, ensure=True)


def has_slots() -> bool:
    """Whether this Blender has slotted actions (4.4+)."""
    return "slots" in bpy.types.Action.bl_rna.properties


def action_curves(action: bpy.types.Action):
    """Every F-curve of an action, slotted (4.4+: all its channelbags) or legacy."""
    if not has_slots():
        return list(action.fcurves)
    return [c for layer in action.layers for strip in layer.strips
            for bag in strip.channelbags for c in bag.fcurves]  # fmt: skip


def write_curve(channelbag, path: str, frames, values, interpolation: int, index: int = 0,
                group=None) -> None:  # fmt: skip
    """One F-curve ``path[index]`` keyed at ``frames`` (T,) with ``values`` (T,), written as
    whole arrays; interpolation: LINEAR or CONSTANT."""
    curve = channelbag.fcurves.new(path, index=index)
    if group is not None:
        curve.group = group
    points = curve.keyframe_points
    points.add(len(frames))
    co = np.empty((len(frames), 2), dtype=np.float32)
    co[:, 0], co[:, 1] = frames, values
    points.foreach_set("co", co.ravel())
    points.foreach_set("interpolation", np.full(len(frames), interpolation, dtype=np.int32))
    curve.update()


def set_frame_range(scene: bpy.types.Scene, start: int, count: int, fps: float) -> None:
    """Scene frames start .. start + count - 1 at ``fps`` (fractional rates via fps_base)."""
    scene.frame_start = start
    scene.frame_end = start + max(count, 1) - 1
    rounded = max(1, round(fps))
    scene.render.fps = rounded
    scene.render.fps_base = rounded / fps

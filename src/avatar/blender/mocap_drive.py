"""Live poses -> an armature's pose bones, and a recorded take -> an Action.

``PoseWriter`` writes one pose, ``rotations`` (J, 4) quaternions (w, x, y, z) and
``translations`` (J, 3) in each bone's rest frame (``Animation``'s layout: exactly the
pose bones' ``rotation_quaternion`` and ``location``), as two whole-array writes
(``foreach_set``) over the armature's pose bones; bones the skeleton lacks keep their
values. A live pose would be overwritten whenever the armature's Action is evaluated, so
``hold_action`` detaches it while a stream drives the armature and ``restore_action`` puts
it back (or ``keep_action`` keeps it, with a fake user, when a take replaced it).
``write_take`` keys a recorded take, one key per frame, through ``avatar.blender.action``
(slotted actions feature-detected).

Nothing here keeps a Blender reference between calls; callers look the armature up by
name each time (undo and deletion invalidate references).
"""

from __future__ import annotations

from collections.abc import Sequence

import bpy
import numpy as np

from avatar.blender import action as action_bridge
from avatar.rig.skeleton import Animation


class PoseWriter:
    """Bulk writes of poses on one armature's pose bones, by bone name."""

    def __init__(self, armature_obj: bpy.types.Object, bone_names: Sequence[str]):
        bones = armature_obj.pose.bones
        index = {name: j for j, name in enumerate(bone_names)}
        self.order = np.array([index.get(b.name, -1) for b in bones], dtype=np.int64)
        self.mapped = self.order >= 0
        if not np.any(self.mapped):
            raise ValueError(f"{armature_obj.name!r} has none of the skeleton's bones")
        count = len(bones)
        # bones the stream does not drive keep the values they had when it started
        self.rotations = np.empty(count * 4, dtype=np.float32)
        self.locations = np.empty(count * 3, dtype=np.float32)
        bones.foreach_get("rotation_quaternion", self.rotations)
        bones.foreach_get("location", self.locations)
        self.rotations = self.rotations.reshape(count, 4)
        self.locations = self.locations.reshape(count, 3)
        for bone, mapped in zip(bones, self.mapped, strict=True):
            if mapped and bone.rotation_mode != "QUATERNION":
                bone.rotation_mode = "QUATERNION"

    def fits(self, armature_obj: bpy.types.Object) -> bool:
        """Whether ``armature_obj`` still has the pose bones this writer was made for."""
        return armature_obj.type == "ARMATURE" and len(armature_obj.pose.bones) == len(self.order)

    def write(self, armature_obj: bpy.types.Object, rotations: np.ndarray,
              translations: np.ndarray) -> None:  # fmt: skip
        """Set the pose: rotations (J, 4) wxyz and translations (J, 3) in the skeleton's order."""
        self.rotations[self.mapped] = np.asarray(rotations)[self.order[self.mapped]]
        self.locations[self.mapped] = np.asarray(translations)[self.order[self.mapped]]
        bones = armature_obj.pose.bones
        bones.foreach_set("rotation_quaternion", self.rotations.ravel())
        bones.foreach_set("location", self.locations.ravel())
        # foreach_set skips RNA's update callbacks: tag the pose for re-evaluation
        armature_obj.update_tag(refresh={"DATA"})


def hold_action(armature_obj: bpy.types.Object) -> str | None:
    """Detach the armature's Action (it would overwrite live poses); returns its name."""
    data = armature_obj.animation_data
    if data is None or data.action is None:
        return None
    name = data.action.name
    data.action = None
    return name


def restore_action(armature_obj: bpy.types.Object, name: str | None) -> None:
    """Give the armature back the Action ``hold_action`` detached (if it still exists)."""
    found = bpy.data.actions.get(name) if name else None
    if found is None:
        return
    armature_obj.animation_data_create()
    armature_obj.animation_data.action = found
    if action_bridge.has_slots() and armature_obj.animation_data.action_slot is None:
        slots = [s for s in found.slots if s.target_id_type == "OBJECT"]
        if slots:
            armature_obj.animation_data.action_slot = slots[0]


def keep_action(name: str | None) -> bool:
    """Give the Action ``name`` a fake user if nothing uses it any more (a take replaced it
    on the armature), so saving the file does not drop it; True when one was given."""
    found = bpy.data.actions.get(name) if name else None
    if found is None or found.users > 0:
        return False
    found.use_fake_user = True
    return True


def write_take(
    armature_obj: bpy.types.Object,
    take: Animation,
    name: str = "Mocap take",
    frame_start: int = 1,
    scene: bpy.types.Scene | None = None,
) -> bpy.types.Action:
    """Key ``take`` (T frames) into a new Action on the armature, one key per frame from
    ``frame_start``; the scene's frame range and rate become the take's (the sender's)."""
    return action_bridge.apply_animation(armature_obj, take, name, frame_start, scene)

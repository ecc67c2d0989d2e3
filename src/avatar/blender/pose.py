"""Static poses on a character's armature: pose bones set from an Animation frame, cleared
to the rest pose, and a character's motion stopped (its actions taken off).

The pose is written straight into the pose bones (``rotation_quaternion``, ``location``);
meshes skinned to the armature (body, garments) follow through their Armature modifiers.
"""

from __future__ import annotations

import bpy
import numpy as np

from avatar.blender import live
from avatar.rig.skeleton import Animation

CORRECTION_PREFIX = "correction"  # garment shape keys baked for a motion (export.character)


def set_pose(armature_obj: bpy.types.Object, pose: Animation, frame: int = 0) -> int:
    """Pose ``armature_obj``'s bones as ``pose`` frame ``frame`` (rotations (T, J, 4) wxyz,
    translations (T, J, 3) in each bone's rest frame); bones the pose does not name go to
    rest. Returns how many bones the pose set."""
    live.end_drag(armature_obj)  # true rest bones first, if a slider drag left them posed
    by_name = {n: j for j, n in enumerate(pose.bone_names)}
    rotations = np.asarray(pose.rotations[frame], dtype=np.float64)
    locations = np.asarray(pose.translations[frame], dtype=np.float64)
    count = 0
    for bone in armature_obj.pose.bones:
        bone.rotation_mode = "QUATERNION"
        j = by_name.get(bone.name)
        if j is None:
            _rest(bone)
            continue
        bone.rotation_quaternion = tuple(rotations[j])
        bone.location = tuple(locations[j])
        bone.scale = (1.0, 1.0, 1.0)
        count += 1
    armature_obj.update_tag()
    return count


def clear_pose(armature_obj: bpy.types.Object) -> None:
    """Every pose bone back to its rest (identity rotation, no location, unit scale)."""
    live.end_drag(armature_obj)  # true rest bones first, if a slider drag left them posed
    for bone in armature_obj.pose.bones:
        _rest(bone)
    armature_obj.update_tag()


def _rest(bone: bpy.types.PoseBone) -> None:
    bone.rotation_quaternion = (1.0, 0.0, 0.0, 0.0)
    bone.rotation_euler = (0.0, 0.0, 0.0)
    bone.location = (0.0, 0.0, 0.0)
    bone.scale = (1.0, 1.0, 1.0)


def stop_motion(root: bpy.types.Object) -> int:
    """Take the actions off a character (its armature's and its garments' correction shape
    keys'), set those corrections to 0 (plainly skinned garments) and delete the actions
    nothing else uses. Returns how many actions were taken off."""
    actions = []
    for obj in (root, *root.children_recursive):
        keys = getattr(obj.data, "shape_keys", None)
        for owner in (obj, keys):
            data = getattr(owner, "animation_data", None)
            if data is not None and data.action is not None:
                actions.append(data.action)
                data.action = None
        if keys is not None:
            for block in keys.key_blocks:
                if block.name.startswith(CORRECTION_PREFIX) and block != keys.reference_key:
                    block.value = 0.0
    for action in set(actions):
        if action.users == 0:
            bpy.data.actions.remove(action)
    return len(actions)


def is_posed(armature_obj: bpy.types.Object, tolerance: float = 1e-6) -> bool:
    """Whether any pose bone is away from its rest."""
    for bone in armature_obj.pose.bones:
        q = np.array(bone.rotation_quaternion)
        if bone.rotation_mode != "QUATERNION":
            q = np.array(bone.rotation_euler.to_quaternion())
        if (abs(abs(q[0]) - 1.0) > tolerance or np.abs(bone.location).max() > tolerance
                or np.abs(np.array(bone.scale) - 1.0).max() > tolerance):  # fmt: skip
            return True
    return False

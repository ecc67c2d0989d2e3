"""Skeleton record -> Blender armature with exactly the Skeleton's rest matrices."""

from __future__ import annotations

from collections.abc import Sequence

import bpy
import numpy as np
from mathutils import Matrix

from avatar.rig.skeleton import Skeleton


def new_armature_object(
    name: str, skeleton: Skeleton, collection: bpy.types.Collection | None = None
) -> bpy.types.Object:
    """A new armature object whose bone rest matrices equal ``skeleton.rest``.

    Each edit bone gets its length from head->tail and its orientation (including roll)
    from the rest matrix, which is how Blender itself stores bones, so ``bone.matrix_local``
    reproduces ``skeleton.rest`` up to float32 rounding.
    """
    data = bpy.data.armatures.new(name)
    obj = bpy.data.objects.new(name, data)
    (collection or bpy.context.scene.collection).objects.link(obj)
    with _edit_mode(obj):
        _add_edit_bones(data, skeleton)
    return obj


def _add_edit_bones(data: bpy.types.Armature, skeleton: Skeleton) -> None:
    lengths = np.maximum(skeleton.lengths, 1e-4)  # Blender deletes zero-length bones
    bones = []
    for name, rest, length in zip(skeleton.names, skeleton.rest, lengths, strict=True):
        bone = data.edit_bones.new(name)
        bone.head = (0.0, 0.0, 0.0)
        bone.tail = (0.0, float(length), 0.0)
        # Setting .matrix keeps the length and derives head, tail and roll from it.
        bone.matrix = Matrix(_orthonormal(rest).tolist())
        bones.append(bone)
    for bone, parent in zip(bones, skeleton.parents, strict=True):
        if parent >= 0:
            bone.parent = bones[parent]


def _orthonormal(m: np.ndarray) -> np.ndarray:
    """(4, 4) with its rotation part re-orthonormalised (SVD), so Blender accepts it exactly."""
    u, _, vt = np.linalg.svd(m[:3, :3])
    out = np.array(m, dtype=np.float64)
    out[:3, :3] = u @ vt
    return out


class _edit_mode:
    """Context manager: make ``obj`` active and enter edit mode; restore object mode after."""

    def __init__(self, obj: bpy.types.Object):
        self.obj = obj

    def __enter__(self) -> bpy.types.Object:
        view_layer = bpy.context.view_layer
        if bpy.context.object is not None and bpy.context.object.mode != "OBJECT":
            bpy.ops.object.mode_set(mode="OBJECT")
        view_layer.objects.active = self.obj
        bpy.ops.object.mode_set(mode="EDIT")
        return self.obj

    def __exit__(self, *exc: object) -> None:
        bpy.ops.object.mode_set(mode="OBJECT")


def bind(mesh_obj: bpy.types.Object, armature_obj: bpy.types.Object) -> None:
    """Parent a mesh to an armature and deform it through an Armature modifier.

    The mesh's vertex groups (named after bones) carry the skin weights.
    """
    mesh_obj.parent = armature_obj
    modifier = mesh_obj.modifiers.new(name="Armature", type="ARMATURE")
    modifier.object = armature_obj
    modifier.use_vertex_groups = True
    modifier.use_deform_preserve_volume = False  # linear blend, as Avatar's LBS and glTF


def rest_matrices(armature_obj: bpy.types.Object, names: Sequence[str]) -> np.ndarray:
    """(J, 4, 4) float64 bone rest matrices in armature space, for the named bones."""
    bones = armature_obj.data.bones
    return np.array([np.array(bones[n].matrix_local) for n in names], dtype=np.float64)


def pose_matrices(armature_obj: bpy.types.Object, names: Sequence[str]) -> np.ndarray:
    """(J, 4, 4) float64 evaluated pose-bone matrices in armature space, for the named bones."""
    bones = armature_obj.pose.bones
    return np.array([np.array(bones[n].matrix) for n in names], dtype=np.float64)

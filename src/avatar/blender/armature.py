"""Skeleton record -> Blender armature with exactly the Skeleton's rest matrices."""

from __future__ import annotations

from collections.abc import Sequence

import bpy
import numpy as np

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
    bones = [data.edit_bones.new(name) for name in skeleton.names]
    for bone, parent in zip(bones, skeleton.parents, strict=True):
        bone.tail = (0.0, 1.0, 0.0)  # a bone needs a length before it can be placed
        if parent >= 0:
            bone.parent = bones[parent]
    _place_edit_bones(data, skeleton)


def _place_edit_bones(data: bpy.types.Armature, skeleton: Skeleton) -> None:
    """Every edit bone of ``data`` at ``skeleton``'s rest matrix, in three array writes.

    An edit bone's ``matrix`` setter keeps its current length and derives head, tail and
    roll from the matrix, so the lengths go in first as tails along Y from the origin.
    Bones are matched by name; bones the skeleton lacks are left alone.
    """
    edit = data.edit_bones
    index = {name: j for j, name in enumerate(skeleton.names)}
    order = np.array([index.get(b.name, -1) for b in edit], dtype=np.int64)
    if np.any(order < 0):
        raise ValueError("the armature has bones the skeleton lacks")
    n = len(order)
    lengths = np.maximum(skeleton.lengths, 1e-4)[order]  # Blender deletes zero-length bones
    edit.foreach_set("head", np.zeros(3 * n, np.float32))
    tails = np.zeros((n, 3), np.float32)
    tails[:, 1] = lengths
    edit.foreach_set("tail", tails.ravel())
    # Matrix properties are read and written column-major: transpose each 4x4.
    matrices = _orthonormal(np.asarray(skeleton.rest, np.float64)[order])
    columns = np.ascontiguousarray(matrices.transpose(0, 2, 1), np.float32)
    edit.foreach_set("matrix", columns.ravel())


def set_rest(armature_obj: bpy.types.Object, skeleton: Skeleton) -> None:
    """Move the armature's rest bones to ``skeleton.rest`` in place (same bones, by name):
    one trip through edit mode, whatever mode the armature was in (restored after)."""
    with _edit_mode(armature_obj):
        _place_edit_bones(armature_obj.data, skeleton)


def _orthonormal(m: np.ndarray) -> np.ndarray:
    """(..., 4, 4) with each rotation part re-orthonormalised (SVD), so Blender accepts it
    exactly."""
    u, _, vt = np.linalg.svd(m[..., :3, :3])
    out = np.array(m, dtype=np.float64)
    out[..., :3, :3] = u @ vt
    return out


class _edit_mode:
    """Context manager: ``obj`` in edit mode, then back in the mode it was in (object mode
    for a new one), the previously active object active again. Works from timers and
    property callbacks too: the operator gets ``obj`` through a context override."""

    def __init__(self, obj: bpy.types.Object):
        self.obj = obj

    def __enter__(self) -> bpy.types.Object:
        context = bpy.context
        self.view_layer = context.view_layer
        self.active = self.view_layer.objects.active
        self.mode = self.obj.mode
        current = context.object
        if current is not None and current is not self.obj and current.mode != "OBJECT":
            _mode_set(current, "OBJECT")
        self.view_layer.objects.active = self.obj
        _mode_set(self.obj, "EDIT")
        return self.obj

    def __exit__(self, *exc: object) -> None:
        _mode_set(self.obj, self.mode if self.mode in ("OBJECT", "POSE") else "OBJECT")
        if self.active is not None and self.active.name in self.view_layer.objects:
            self.view_layer.objects.active = self.active


def _mode_set(obj: bpy.types.Object, mode: str) -> None:
    """``object.mode_set`` on ``obj``, without the depsgraph evaluations ``bpy.ops`` adds
    before and after every call (with a few characters in the scene they cost ~10 ms, far
    more than the mode switch): the operator is called through the C function ``bpy.ops``
    wraps (its signature lost the context argument in 4.0), else (Blender 5.1+ has no such
    function: ``bpy.ops._op_call`` is gone and its name resolves to an operator submodule)
    through ``bpy.ops``."""
    with bpy.context.temp_override(active_object=obj, object=obj):
        try:
            from _bpy import ops as c_ops  # the C module bpy.ops wraps
        except ImportError:
            c_ops = None
        _op_call = getattr(c_ops, "call", None)
        if not callable(_op_call):
            bpy.ops.object.mode_set(mode=mode)
            return
        if bpy.app.version >= (4, 0):
            _op_call("OBJECT_OT_mode_set", {"mode": mode})
        else:
            _op_call("OBJECT_OT_mode_set", None, {"mode": mode})


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

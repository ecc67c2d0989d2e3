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


def show_rest_as_pose(armature_obj: bpy.types.Object, skeleton: Skeleton) -> None:
    """Show ``skeleton``'s rest through the pose, without edit mode: each pose bone's
    basis is set so that its pose matrix is the skeleton's rest matrix (head and
    orientation; a bone keeps its drawn length, that of the armature's rest).

    The armature's rest (``bone.matrix_local``) is not touched, so Blender re-evaluates
    this armature and what depends on it, nothing else (an edit-mode trip makes it
    re-evaluate every object in the scene). A mesh skinned to the armature would now be
    deformed by each bone's pose times its inverse rest: the caller (``avatar.blender.
    live``) turns those Armature modifiers off while the pose stands in for the rest, and
    ``set_rest`` + ``reset_pose`` end it. Assumes Blender's default bone inheritance
    (location, rotation and scale from the parent; no constraints), as Avatar makes bones.
    """
    pose_bones = armature_obj.pose.bones
    pose_order, bone_order = _bone_orders(armature_obj, tuple(skeleton.names))
    n = len(pose_order)
    flat = np.empty(16 * n, dtype=np.float32)
    armature_obj.data.bones.foreach_get("matrix_local", flat)
    shown = np.empty((n, 4, 4), dtype=np.float64)  # Blender's rest, in skeleton order
    shown[bone_order] = flat.reshape(n, 4, 4).transpose(0, 2, 1)
    target = np.asarray(skeleton.rest, np.float64)
    basis = pose_basis(shown, target, skeleton.parents)[pose_order]
    pose_bones.foreach_set("matrix_basis", np.ascontiguousarray(
        basis.transpose(0, 2, 1), dtype=np.float32).ravel())  # fmt: skip
    armature_obj.update_tag(refresh={"DATA"})


_ORDERS: dict[tuple[int, tuple[str, ...]], tuple[np.ndarray, np.ndarray]] = {}


def _bone_orders(armature_obj: bpy.types.Object, names: tuple[str, ...]):
    """(skeleton index of each pose bone, of each bone of ``armature.bones``), read once per
    armature and skeleton (a drag step then reads no bone name; a spot check of three
    names catches an armature that changed under the same address)."""
    pose_bones = armature_obj.pose.bones
    key = (armature_obj.data.as_pointer(), names)
    found = _ORDERS.get(key)
    if found is not None and len(pose_bones) == len(names):
        pose_order = found[0]
        if all(pose_bones[k].name == names[pose_order[k]] for k in (0, len(names) // 2, -1)):
            return found
    index = {name: j for j, name in enumerate(names)}
    orders = tuple(np.array([index.get(b.name, -1) for b in bones], dtype=np.int64)
                   for bones in (pose_bones, armature_obj.data.bones))  # fmt: skip
    if len(pose_bones) != len(names) or any(np.any(o < 0) for o in orders):
        raise ValueError("the armature's bones are not the skeleton's")
    if len(_ORDERS) >= 32:
        _ORDERS.clear()
    _ORDERS[key] = found = (orders[0], orders[1])
    return found


def pose_basis(rest: np.ndarray, target: np.ndarray, parents: Sequence[int]) -> np.ndarray:
    """(J, 4, 4) each bone's pose basis that puts bones resting at ``rest`` (J, 4, 4,
    armature space) at ``target`` (J, 4, 4): with Blender's pose rule ``P_j = P_p
    (R_p^-1 R_j) B_j``, ``B_j = R_j^-1 R_p T_p^-1 T_j`` (``B_j = R_j^-1 T_j`` for a root).
    ``parents`` (J,): parent index, -1 for a root."""
    parents = np.asarray(parents, dtype=np.int64)
    has_parent = parents >= 0
    parent_rest = rest[np.where(has_parent, parents, 0)]
    parent_target = target[np.where(has_parent, parents, 0)]
    step = parent_rest @ affine_inverse(parent_target)  # R_p T_p^-1
    step[~has_parent] = np.eye(4)
    return affine_inverse(rest) @ step @ target


def affine_inverse(m: np.ndarray) -> np.ndarray:
    """(..., 4, 4) inverses of affine matrices (last row 0 0 0 1), written out (adjugate
    by cross products): ``np.linalg.inv`` goes through LAPACK, which OpenBLAS runs on
    every core; on a loaded machine that was ~1 ms for 163 bones instead of ~0.05."""
    a = m[..., :3, :3]
    rows = [a[..., 0, :], a[..., 1, :], a[..., 2, :]]
    adjugate = np.stack([np.cross(rows[1], rows[2]), np.cross(rows[2], rows[0]),
                         np.cross(rows[0], rows[1])], axis=-1)  # fmt: skip
    det = np.sum(rows[0] * adjugate[..., :, 0], axis=-1)[..., None, None]
    out = np.zeros(m.shape, dtype=np.float64)
    out[..., :3, :3] = adjugate / det
    out[..., :3, 3] = -np.einsum("...ij,...j->...i", out[..., :3, :3], m[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out


def reset_pose(armature_obj: bpy.types.Object) -> None:
    """Every pose bone's basis back to identity (the rest pose), in one array write."""
    pose_bones = armature_obj.pose.bones
    identity = np.tile(np.eye(4, dtype=np.float32).ravel(), len(pose_bones))
    pose_bones.foreach_set("matrix_basis", identity)
    armature_obj.update_tag(refresh={"DATA"})


def pose_is_rest(armature_obj: bpy.types.Object, tolerance: float = 1e-6) -> bool:
    """Whether every pose bone's basis is the identity (within ``tolerance``)."""
    pose_bones = armature_obj.pose.bones
    flat = np.empty(16 * len(pose_bones), dtype=np.float32)
    pose_bones.foreach_get("matrix_basis", flat)
    identity = np.tile(np.eye(4, dtype=np.float32).ravel(), len(pose_bones))
    return bool(np.all(np.abs(flat - identity) <= tolerance))


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

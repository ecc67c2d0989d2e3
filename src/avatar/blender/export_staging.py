"""A throw-away copy of a character made ready for one engine: what the exporters write.

``staged_copy(root, preset)`` copies the character's armature and meshes (data, shape keys
and actions too, so nothing of the user's character changes), gives the copies the
originals' names for the length of the export (the originals step aside under temporary
names), applies the engine preset to the copies (bone names, a root bone at the origin,
shape keys baked, at most N bone weights per vertex, file units), and on leaving deletes
the copies and puts every name back, whatever happened in between.
"""

from __future__ import annotations

import contextlib
import re
import secrets
from collections.abc import Iterator
from dataclasses import dataclass

import bpy
import numpy as np
from mathutils import Matrix

from avatar.blender import action as action_bridge
from avatar.blender import armature as armature_bridge
from avatar.blender.engine_presets import EnginePreset


@dataclass
class Staged:
    """The copies an exporter writes: ``root`` (armature, or the body of an unrigged
    character), ``armature`` (or None) and ``meshes``; ``frames`` (start, end) of their
    animation, None when nothing is animated."""

    root: bpy.types.Object
    armature: bpy.types.Object | None
    meshes: list[bpy.types.Object]
    frames: tuple[int, int] | None

    @property
    def objects(self) -> list[bpy.types.Object]:
        return [self.root, *(m for m in self.meshes if m is not self.root)]


@contextlib.contextmanager
def staged_copy(
    root: bpy.types.Object, preset: EnginePreset, shape_keys: str = ""
) -> Iterator[Staged]:
    """The character ``root`` heads, copied and prepared for ``preset`` (see module doc).

    shape_keys: "KEEP" or "BAKE"; "" takes the preset's. The scene is as before on exit.
    """
    originals = [root, *(o for o in root.children_recursive if o.type == "MESH")]
    collection = bpy.data.collections.new(f"avatar-export-{secrets.token_hex(3)}")
    bpy.context.scene.collection.children.link(collection)
    renamed: dict[bpy.types.ID, str] = {}
    made: list = []
    try:
        copies = _copy(originals, collection, made)
        _swap_names(originals, copies, renamed)
        staged = _prepare(copies[root], [copies[o] for o in originals], preset,
                          shape_keys or preset.shape_keys, renamed)  # fmt: skip
        yield staged
    finally:
        _remove(made, collection)
        for obj, name in renamed.items():
            obj.name = name


def _copy(originals, collection, made) -> dict:
    """Copies of ``originals`` (object, data, actions), linked into ``collection``, visible,
    parented and deformed among themselves. Everything made is appended to ``made``."""
    copies = {}
    for obj in originals:
        copy = obj.copy()
        made.append(copy)
        if obj.data is not None:
            copy.data = obj.data.copy()
            made.append(copy.data)
        collection.objects.link(copy)
        copies[obj] = copy
    for obj, copy in copies.items():
        copy.parent = copies.get(obj.parent)
        if obj.parent is not None and obj.parent not in copies:  # keep where it shows
            copy.matrix_world = obj.matrix_world
        for modifier in copy.modifiers:
            if modifier.type == "ARMATURE" and modifier.object in copies:
                modifier.object = copies[modifier.object]
        for owner in (copy, getattr(copy.data, "shape_keys", None)):
            anim = owner.animation_data if owner is not None else None
            if anim is not None and anim.action is not None:
                slot = getattr(anim, "action_slot", None)  # slotted actions: 4.4+
                identifier = slot.identifier if slot is not None else None
                action = anim.action.copy()  # its curves are renamed and scaled, not the user's
                made.append(action)
                anim.action = action
                if identifier is not None and anim.action_slot is None:
                    anim.action_slot = next(s for s in action.slots
                                            if s.identifier == identifier)  # fmt: skip
    bpy.context.view_layer.update()
    for copy in copies.values():
        copy.hide_viewport = copy.hide_render = False
        copy.hide_set(False)
    return copies


def _swap_names(originals, copies, renamed) -> None:
    """The copies take the originals' names (what the file shows); the originals wait under
    temporary ones, recorded in ``renamed`` to be put back."""
    token = secrets.token_hex(3)
    for obj in originals:
        pairs = [(obj, copies[obj])]
        if obj.data is not None and obj.data.users == 1:  # glTF names meshes after data
            pairs.append((obj.data, copies[obj].data))
        for original, copy in pairs:
            name = original.name
            renamed[original] = name
            original.name = f"{name[:40]}~{token}"
            copy.name = name


def _claim_name(obj: bpy.types.Object, name: str, renamed) -> None:
    """Give ``obj`` the name ``name``, moving any other object holding it aside."""
    holder = bpy.data.objects.get(name)
    if holder is not None and holder is not obj:
        renamed.setdefault(holder, holder.name)
        holder.name = f"{name}~{secrets.token_hex(3)}"
    obj.name = name


def _prepare(root, objects, preset: EnginePreset, shape_keys: str, renamed) -> Staged:
    armature = root if root.type == "ARMATURE" else None
    meshes = [o for o in objects if o.type == "MESH"]
    if preset.at_origin:
        root.location = (0.0, 0.0, 0.0)
    if shape_keys == "BAKE":
        for obj in meshes:
            bake_shape_keys(obj)
    if armature is not None:
        if preset.bone_names == "identifier":
            rename_bones(armature, identifier)
        if preset.root_bone:
            add_root_bone(armature, preset.root_bone)
        if preset.armature_name:
            _claim_name(armature, preset.armature_name, renamed)
    if preset.max_influences:
        for obj in meshes:
            limit_influences(obj, preset.max_influences)
    return Staged(root, armature, meshes, _frame_range(objects))


def _remove(made, collection) -> None:
    for item in made:
        with contextlib.suppress(ReferenceError):  # an object's mesh goes with it, etc.
            pool = _pool(item)
            if item.name in pool:
                pool.remove(item)
    bpy.data.collections.remove(collection)
    bpy.context.view_layer.update()


def _pool(item):
    if isinstance(item, bpy.types.Object):
        return bpy.data.objects
    if isinstance(item, bpy.types.Action):
        return bpy.data.actions
    return bpy.data.armatures if isinstance(item, bpy.types.Armature) else bpy.data.meshes


def identifier(name: str) -> str:
    """``name`` with every character outside [A-Za-z0-9_] replaced by _ ("upperarm01.L" ->
    "upperarm01_L")."""
    return re.sub(r"[^A-Za-z0-9_]", "_", name)


def rename_bones(armature: bpy.types.Object, rename) -> None:
    """Rename every bone of ``armature`` by ``rename(name)`` (a clash gets _2, _3...).
    Blender renames the vertex groups of the meshes it deforms and its action's curves."""
    taken: set[str] = set()
    plan = []
    for bone in armature.data.bones:
        new = rename(bone.name)
        base, n = new, 2
        while new.lower() in taken:
            new, n = f"{base}_{n}", n + 1
        taken.add(new.lower())
        plan.append((bone.name, new))
    for old, new in plan:
        if old != new:
            armature.data.bones[old].name = new


def add_root_bone(armature: bpy.types.Object, name: str) -> None:
    """A bone ``name`` at the armature's origin pointing up (10 cm), parenting every bone
    that had no parent. A top bone already called ``name`` with its head at the origin is
    used as it is; any other bone of that name (any case: engines compare names without
    case) is renamed ``<name>_0`` first. The new bone deforms nothing and is not animated,
    so the pose is unchanged."""
    bones = armature.data.bones
    top = [b for b in bones if b.parent is None]
    if len(top) == 1 and top[0].name == name and top[0].head_local.length < 1e-5:
        return
    for bone in list(bones):
        if bone.name.lower() == name.lower():
            bone.name = f"{name}_0"
    length = 0.1  # metres, before any unit scaling
    with armature_bridge._edit_mode(armature) as obj:
        edit = obj.data.edit_bones
        root = edit.new(name)
        root.head, root.tail, root.roll = (0.0, 0.0, 0.0), (0.0, 0.0, length), 0.0
        root.use_deform = False
        for bone in edit:
            if bone.parent is None and bone is not root:
                bone.parent = root
                bone.use_connect = False


def bake_shape_keys(obj: bpy.types.Object) -> None:
    """The mesh as its shape keys mix now, with no shape keys (and no shape-key action)."""
    keys = obj.data.shape_keys
    if keys is None:
        return
    blocks = keys.key_blocks
    count = len(obj.data.vertices)
    basis = _key_co(blocks[0], count)
    mixed = basis.copy()
    for block in list(blocks)[1:]:
        if block.value != 0.0 and not block.mute:
            relative = _key_co(block.relative_key, count)
            mixed += block.value * (_key_co(block, count) - relative)
    if keys.animation_data is not None:
        keys.animation_data_clear()
    name = keys.name
    obj.shape_key_clear()
    left = bpy.data.shape_keys.get(name)  # kept alive (its cleared animation's users)
    if left is not None and obj.data.shape_keys is None:
        bpy.data.batch_remove([left])  # else it outlives the mesh and breaks a .blend save
    obj.data.vertices.foreach_set("co", mixed.ravel())
    obj.data.update()


def _key_co(block, count: int) -> np.ndarray:
    out = np.empty(count * 3, dtype=np.float32)
    block.data.foreach_get("co", out)
    return out.reshape(count, 3)


def limit_influences(obj: bpy.types.Object, limit: int) -> None:
    """At most ``limit`` bone weights per vertex of ``obj``: the largest kept, renormalised
    to their old sum (others removed from their vertex groups)."""
    groups = obj.vertex_groups
    if not len(groups):
        return
    for vertex in obj.data.vertices:
        weights = [(g.weight, g.group) for g in vertex.groups]
        if len(weights) <= limit:
            continue
        weights.sort(reverse=True)
        total = sum(w for w, _ in weights)
        kept = weights[:limit]
        scale = total / max(sum(w for w, _ in kept), 1e-12)
        index = [vertex.index]
        for _, group in weights[limit:]:
            groups[group].remove(index)
        for weight, group in kept:
            groups[group].add(index, weight * scale, "REPLACE")


def scale_units(staged: Staged, factor: float) -> None:
    """Scale the staged copies' world by ``factor`` about the origin while keeping every
    object's scale 1: vertices and shape keys, bone rests, translations (objects, parent
    inverses, animated bone locations) all multiplied; rotations untouched."""
    scale = Matrix.Scale(factor, 4)
    for obj in staged.objects:
        obj.matrix_basis.translation *= factor
        inverse = obj.matrix_parent_inverse.copy()
        inverse.translation *= factor
        obj.matrix_parent_inverse = inverse
        if obj.type == "MESH":
            obj.data.transform(scale, shape_keys=True)
        elif obj.type == "ARMATURE":
            obj.data.transform(scale)
        anim = obj.animation_data
        if anim is not None and anim.action is not None:
            for curve in action_bridge.action_curves(anim.action):
                if curve.data_path.endswith("location"):
                    _scale_curve(curve, factor)
    bpy.context.view_layer.update()


def _scale_curve(curve, factor: float) -> None:
    points = curve.keyframe_points
    for attribute in ("co", "handle_left", "handle_right"):
        values = np.empty(len(points) * 2, dtype=np.float32)
        points.foreach_get(attribute, values)
        values[1::2] *= factor
        points.foreach_set(attribute, values)
    curve.update()


def _frame_range(objects) -> tuple[int, int] | None:
    """(first, last) frame over the actions of ``objects`` and their shape keys."""
    ranges = []
    for obj in objects:
        for owner in (obj, getattr(obj.data, "shape_keys", None)):
            anim = owner.animation_data if owner is not None else None
            if anim is not None and anim.action is not None:
                ranges.append(tuple(anim.action.frame_range))
    if not ranges:
        return None
    return int(round(min(r[0] for r in ranges))), int(round(max(r[1] for r in ranges)))

"""Write the scene (or some objects) with Blender's own exporters: FBX, USD, .blend.

glTF/GLB and OBJ are written by ``avatar.io`` without Blender; these formats need it.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import bpy

from avatar.errors import AvatarError


def export(path: str | os.PathLike[str], objects: Sequence[bpy.types.Object] | None = None) -> Path:
    """Write ``objects`` (default: the whole scene) to ``path``; the suffix picks the format.

    .fbx (armature, skinned meshes, baked animation, packed textures), .usd/.usda/.usdc/.usdz,
    .blend (the whole file, a copy: the session keeps its own file name).
    """
    path = Path(path).resolve()
    writer = _WRITERS.get(path.suffix.lower())
    if writer is None:
        raise AvatarError(f"cannot export {path.name}: use one of {', '.join(sorted(_WRITERS))}")
    path.parent.mkdir(parents=True, exist_ok=True)
    _select(objects)
    writer(str(path), objects is not None)
    return path


def _select(objects: Sequence[bpy.types.Object] | None) -> None:
    if objects is None:
        return
    for obj in bpy.context.view_layer.objects:
        obj.select_set(False)
    for obj in objects:
        obj.select_set(True)
        for child in obj.children_recursive:  # a character's parts hang under its armature
            child.select_set(True)


def _fbx(path: str, selected: bool) -> None:
    bpy.ops.export_scene.fbx(
        filepath=path,
        use_selection=selected,
        add_leaf_bones=False,  # Avatar's bones have real tails; leaf bones only add clutter
        bake_anim=True,
        # One animation stack of the scene's timeline: armature action and shape-key
        # actions together. (The default exports NLA strips only: none, so no animation.)
        bake_anim_use_nla_strips=False,
        bake_anim_use_all_actions=False,
        path_mode="COPY",
        embed_textures=True,
        # FBX tools expect Y-up; Blender's exporter converts from Z-up itself.
        axis_forward="-Z",
        axis_up="Y",
    )


def _usd(path: str, selected: bool) -> None:
    bpy.ops.wm.usd_export(filepath=path, selected_objects_only=selected, export_animation=True)


def _blend(path: str, selected: bool) -> None:
    bpy.ops.wm.save_as_mainfile(filepath=path, copy=True)


_WRITERS = {
    ".fbx": _fbx,
    ".usd": _usd,
    ".usda": _usd,
    ".usdc": _usd,
    ".usdz": _usd,
    ".blend": _blend,
}

"""Write with Blender's own exporters: the scene (or some objects) as FBX, USD, .blend
(``export``); a character for a game engine as glTF/GLB, FBX or USD (``export_character``);
a camera's OpenCV intrinsics and extrinsics as JSON (``export_camera``).

glTF/GLB and OBJ of a ``Human`` are written by ``avatar.io`` without Blender. A character in
a scene goes through Blender's glTF exporter instead: it writes what the scene holds (the
user's edits, the live body, the motion as it plays, shape-key animation) from the same
staged copy as FBX and USD, so one engine preset applies alike to all three formats, where
``avatar.io.gltf`` would need the recipe realised again and the motion retargeted again.
Every file is written into a temporary folder beside the destination and moved into place
only once the exporter finished: a failed export leaves no file behind.
"""

from __future__ import annotations

import contextlib
import json
import os
import secrets
import shutil
from collections.abc import Iterator, Sequence
from pathlib import Path

import bpy
import numpy as np

from avatar import camera as camera_maths
from avatar.blender import camera as camera_bridge
from avatar.blender import export_staging
from avatar.blender.engine_presets import FORMATS, SUFFIXES, EnginePreset
from avatar.blender.engine_presets import preset as find_preset
from avatar.errors import AvatarError
from avatar.io import atomic


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


def export_character(
    root: bpy.types.Object,
    path: str | os.PathLike[str],
    preset: str = "BLENDER",
    file_format: str = "",
    shape_keys: str = "",
) -> Path:
    """Write the character ``root`` heads (armature, body, garments, hair, ..., with its
    animation) for an engine; returns the path written.

    preset: a name of ``engine_presets.PRESETS`` (BLENDER, UNITY, UNREAL, GODOT).
    file_format: "GLB", "FBX" or "USD"; "" takes the path's suffix, else the preset's format.
    The suffix is made to match the format (.glb, .fbx, .usdz; .gltf, .usd/.usda/.usdc are
    kept). shape_keys: "KEEP", "BAKE" or "" (the preset's).
    Raises AvatarError (unknown preset or format, a path that cannot be written, an
    exporter failure) with nothing written and the character unchanged.
    """
    try:
        spec = find_preset(preset)
    except KeyError as exc:
        raise AvatarError(exc.args[0]) from None
    path = Path(os.path.abspath(os.fspath(path)))
    fmt = (file_format or SUFFIXES.get(path.suffix.lower(), "") or spec.format).upper()
    if fmt not in FORMATS:
        raise AvatarError(f"no export format {file_format!r}; there are {', '.join(FORMATS)}")
    if shape_keys.upper() not in ("", "KEEP", "BAKE"):
        raise AvatarError(f"shape_keys is KEEP or BAKE, not {shape_keys!r}")
    if SUFFIXES.get(path.suffix.lower()) != fmt:
        path = path.with_name(path.name + FORMATS[fmt])
    with _staging_folder(path) as folder, \
            export_staging.staged_copy(root, spec, shape_keys.upper()) as staged:  # fmt: skip
        if fmt == "FBX" and spec.unit_scale != 1.0:
            export_staging.scale_units(staged, spec.unit_scale)
        _select(staged.objects)
        with _scene_settings(staged, spec if fmt == "FBX" else None):
            try:
                _CHARACTER_WRITERS[fmt](str(folder / path.name), spec, staged)
            except RuntimeError as exc:  # the exporter's own error report
                raise AvatarError(f"{path.name}: {_first_line(exc)}") from None
        _commit(folder, path)
    return path


def _first_line(exc: BaseException) -> str:
    lines = [ln.strip() for ln in str(exc).splitlines() if ln.strip()]
    return lines[-1] if lines else type(exc).__name__


@contextlib.contextmanager
def _staging_folder(path: Path) -> Iterator[Path]:
    """A new hidden folder beside ``path`` (same filesystem: the final moves are renames),
    removed with whatever is left in it. Raises AvatarError for a destination that cannot
    be written: a folder, a parent that is a file, no permission."""
    if path.is_dir():
        raise AvatarError(f"{path}: is a folder; give a file name")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        folder = path.parent / f".{path.stem}.{secrets.token_hex(4)}.export"
        folder.mkdir()
    except (FileExistsError, NotADirectoryError):
        raise AvatarError(f"{path}: a parent of this path is a file, not a folder") from None
    except OSError as exc:
        raise AvatarError(f"cannot write in {path.parent}: {exc.strerror or exc}") from None
    try:
        yield folder
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def _commit(folder: Path, path: Path) -> None:
    """Move what the exporter wrote into ``path``'s folder: the main file last, so a reader
    that sees it also sees its textures."""
    main = folder / path.name
    if not main.is_file():
        raise AvatarError(f"{path.name}: the exporter wrote no file")
    for item in sorted(folder.rglob("*")):
        if item.is_file() and item != main:
            target = path.parent / item.relative_to(folder)
            target.parent.mkdir(parents=True, exist_ok=True)
            os.replace(item, target)
    os.replace(main, path)


@contextlib.contextmanager
def _scene_settings(staged: export_staging.Staged, fbx_units: EnginePreset | None):
    """The scene's frame range set to the staged animation's, and (FBX in other units) its
    unit scale set to match the staged copy; both put back afterwards."""
    scene = bpy.context.scene
    saved = scene.frame_start, scene.frame_end, scene.frame_current
    units = scene.unit_settings
    saved_units = units.system, units.scale_length
    try:
        if staged.frames is not None:
            scene.frame_start, scene.frame_end = staged.frames
            scene.frame_set(staged.frames[0])
        if fbx_units is not None and fbx_units.unit_scale != 1.0:
            units.system = "METRIC"
            units.scale_length = 1.0 / fbx_units.unit_scale
        yield
    finally:
        units.system, units.scale_length = saved_units
        scene.frame_start, scene.frame_end = saved[:2]
        scene.frame_set(saved[2])


def _gltf_character(path: str, spec: EnginePreset, staged: export_staging.Staged) -> None:
    keep = any(o.data.shape_keys is not None for o in staged.meshes)
    bpy.ops.export_scene.gltf(
        filepath=path,
        export_format="GLTF_SEPARATE" if path.lower().endswith(".gltf") else "GLB",
        use_selection=True,
        export_yup=True,  # glTF is Y-up by its spec; the importer turns it back
        export_apply=False,  # applying modifiers would apply the Armature one: no skin
        export_skins=True,
        export_influence_nb=spec.max_influences or 4,
        export_all_influences=not spec.max_influences,
        export_def_bones=False,  # a root bone deforms nothing but must be there
        export_leaf_bone=False,
        export_morph=keep,
        export_morph_animation=keep,
        export_animations=staged.frames is not None,
        # The staged copies' own actions (armature + shape keys) as one animation; "ACTIONS"
        # would also write every other compatible action in the file.
        export_animation_mode="ACTIVE_ACTIONS",
        export_materials="EXPORT",
        export_image_format="AUTO",
        export_cameras=False,
        export_lights=False,
    )


def _fbx_character(path: str, spec: EnginePreset, staged: export_staging.Staged) -> None:
    bpy.ops.export_scene.fbx(
        filepath=path,
        use_selection=True,
        object_types={"ARMATURE", "MESH"},
        use_mesh_modifiers=False,  # the armature deforms in the engine; keys stay keys
        mesh_smooth_type="FACE",  # engines warn about files without smoothing groups
        add_leaf_bones=False,  # Avatar's bones have real tails; leaf bones are clutter
        primary_bone_axis="Y",
        secondary_bone_axis="X",
        armature_nodetype="NULL",
        use_armature_deform_only=False,  # keep the root bone, which deforms nothing
        bake_anim=staged.frames is not None,
        bake_anim_use_all_bones=True,
        bake_anim_use_nla_strips=False,
        bake_anim_use_all_actions=False,
        bake_anim_force_startend_keying=True,
        bake_anim_simplify_factor=0.0,  # every frame as it was (no curve simplification)
        path_mode="COPY",
        embed_textures=True,
        apply_unit_scale=True,  # the file's unit is the scene's (centimetres for Unreal)
        apply_scale_options="FBX_SCALE_NONE",
        global_scale=1.0,
        axis_forward=spec.fbx_axis_forward,
        axis_up=spec.fbx_axis_up,
    )


def _usd_character(path: str, spec: EnginePreset, staged: export_staging.Staged) -> None:
    options = dict(
        filepath=path,
        selected_objects_only=True,
        export_animation=staged.frames is not None,
        export_armatures=True,
        only_deform_bones=False,
        export_shapekeys=any(o.data.shape_keys is not None for o in staged.meshes),
        export_materials=True,
        generate_preview_surface=True,  # UsdPreviewSurface: what every USD reader shows
        export_uvmaps=True,
        export_normals=True,
        relative_paths=True,
    )
    known = bpy.ops.wm.usd_export.get_rna_type().properties.keys()
    optional = {
        "export_textures_mode": "NEW",  # 4.3+: textures written beside (or into the .usdz)
        "export_textures": True,  # 4.2
        "export_cameras": False,
        "export_lights": False,
        "convert_orientation": spec.usd_y_up,
        "export_global_up_selection": "Y" if spec.usd_y_up else "Z",
        "export_global_forward_selection": "NEGATIVE_Z" if spec.usd_y_up else "NEGATIVE_Y",
    }
    options.update({k: v for k, v in optional.items() if k in known})
    bpy.ops.wm.usd_export(**options)


_CHARACTER_WRITERS = {"GLB": _gltf_character, "FBX": _fbx_character, "USD": _usd_character}


def camera_record(obj: bpy.types.Object, scene: bpy.types.Scene | None = None) -> dict:
    """A perspective camera as ``scene`` renders it, in OpenCV convention (x right, y down,
    z forward; pixel (0, 0) the centre of the top-left pixel), JSON-able:

    K (3x3, pixels), world_to_camera (4x4, metres), camera_to_world (its inverse), R and t
    (world_to_camera's rotation and translation), width and height (pixels, after
    ``resolution_percentage``), distortion (OpenCV's five, all zero), the frame, and the
    Blender settings it came from (lens, sensor, sensor_fit, shifts, resolution,
    percentage, pixel aspect).
    """
    scene = scene or bpy.context.scene
    try:
        model = camera_bridge.camera_model(obj, scene)
    except ValueError as exc:
        raise AvatarError(str(exc)) from None
    K = camera_maths.intrinsics(model)
    w2c = camera_maths.world_to_camera(model)
    width, height = model.size
    return {
        "convention": "opencv",
        "camera": obj.name,
        "frame": scene.frame_current,
        "width": width,
        "height": height,
        "K": K.tolist(),
        "world_to_camera": w2c.tolist(),
        "camera_to_world": np.linalg.inv(w2c).tolist(),
        "R": w2c[:3, :3].tolist(),
        "t": w2c[:3, 3].tolist(),
        "distortion": [0.0] * 5,
        "units": "metres",
        "blender": {
            "lens_mm": model.lens,
            "sensor_width_mm": model.sensor_width,
            "sensor_height_mm": model.sensor_height,
            "sensor_fit": model.sensor_fit,
            "shift_x": model.shift_x,
            "shift_y": model.shift_y,
            "resolution": list(model.resolution),
            "percentage": model.percentage,
            "pixel_aspect": list(model.pixel_aspect),
        },  # fmt: skip
    }


def export_camera(
    path: str | os.PathLike[str],
    obj: bpy.types.Object | None = None,
    scene: bpy.types.Scene | None = None,
) -> Path:
    """Write ``camera_record`` of ``obj`` (default: the scene's camera) as JSON to ``path``
    (atomically; ".json" added when missing). Raises AvatarError without a camera, for an
    orthographic one and for a path that cannot be written."""
    scene = scene or bpy.context.scene
    obj = obj or scene.camera
    if obj is None or obj.type != "CAMERA":
        raise AvatarError("no camera: make a camera active or set the scene's camera")
    record = camera_record(obj, scene)
    path = Path(os.path.abspath(os.fspath(path)))
    if path.suffix.lower() != ".json":
        path = path.with_name(path.name + ".json")
    if path.is_dir():
        raise AvatarError(f"{path}: is a folder; give a file name")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        atomic.write_text(path, json.dumps(record, indent=1) + "\n")
    except (FileExistsError, NotADirectoryError):
        raise AvatarError(f"{path}: a parent of this path is a file, not a folder") from None
    except OSError as exc:
        raise AvatarError(f"cannot write {path}: {exc.strerror or exc}") from None
    return path

"""Motion panel: BVH clips (a file or a folder of them) retargeted onto the active character
with an editable bone mapping and its quality report; the pose library (thumbnails), rest,
T-pose and A-pose; the built-in walk.

Settings live on the scene (``scene.avatar_motion``); what a motion did lives on the
character (``avatar.blender.character``: the spec, the report's summary and numbers).
Apply and Walk rebuild the character playing the motion (garments get their baked
corrections), building the new one before removing the old, so a failure leaves it as it
was. Poses are written into the armature's pose bones (garments follow through their
Armature modifiers) after the pose is computed; a pose, like Rest, stops the character's
motion so it stays.

Scripts: ``scene.avatar_motion.bvh_path = "clip.bvh"`` (or a folder, then
``clip_index``), ``bpy.ops.avatar.apply_motion()``; ``bpy.ops.avatar.map_bones()`` fills
``scene.avatar_motion.bones`` (source bone -> ``target`` Avatar bone; setting a row's
``target``, "" for none, edits the mapping Apply uses); ``bpy.ops.avatar.save_bone_map(
filepath=...)`` / ``load_bone_map``; ``bpy.ops.avatar.apply_pose(name="t-pose")``,
``rest_pose()``, ``walk(speed=1.3, steps=8)``.
"""

from __future__ import annotations

import json
import os
from contextlib import contextmanager

import bpy
from bpy.props import (
    BoolProperty,
    CollectionProperty,
    FloatProperty,
    IntProperty,
    StringProperty,
)

from . import live, motion_cache
from .operators import _call, _select, root_of

_SYNC = {"on": False}  # rows being written by code: their update callbacks stay quiet


@contextmanager
def _syncing():
    _SYNC["on"] = True
    try:
        yield
    finally:
        _SYNC["on"] = False


def _error_type():
    from avatar.errors import AvatarError

    return AvatarError


# ------------------------------------------------------------------------ settings


class AvatarClip(bpy.types.PropertyGroup):
    """One clip of a folder (its name relative to the folder)."""

    name: StringProperty(name="Clip")
    path: StringProperty(name="Path", subtype="FILE_PATH")
    frames: IntProperty(name="Frames")
    fps: FloatProperty(name="FPS")
    error: StringProperty(name="Error", description="Why this clip cannot be used")


def _target_changed(self, context):
    if not _SYNC["on"]:
        edit_row(context.scene.avatar_motion, self)


class AvatarBoneRow(bpy.types.PropertyGroup):
    """One source (clip) bone: the Avatar bone it drives ("" for none)."""

    name: StringProperty(name="Source bone")
    target: StringProperty(name="Avatar bone", update=_target_changed,
                           description="The Avatar bone it drives (empty: none)")  # fmt: skip
    role: StringProperty(name="Role", description="The canonical role both bones play")
    how: StringProperty(name="How", description="role, name (same names) or empty")


class AvatarRoleBone(bpy.types.PropertyGroup):
    """An Avatar bone a clip bone can be mapped onto, and its canonical role."""

    name: StringProperty(name="Avatar bone")
    role: StringProperty(name="Role")


class AvatarPose(bpy.types.PropertyGroup):
    """One pose of the library (built-in or a pose file)."""

    name: StringProperty(name="Pose")
    path: StringProperty(name="Path", subtype="FILE_PATH")
    source: StringProperty(name="Source")
    description: StringProperty(name="Description")


def _path_changed(self, context):
    self.bones.clear()
    self.mapped_clip = ""
    self.clips.clear()
    self.folder_error = ""
    path = bpy.path.abspath(self.bvh_path) if self.bvh_path else ""
    if path and os.path.isdir(path):
        try:
            list_clips(self)
        except _error_type() as exc:
            self.folder_error = str(exc)


def _clip_changed(self, context):
    self.bones.clear()
    self.mapped_clip = ""


def _match_changed(self, context):
    root = root_of(context.object)
    if self.mapped_clip and root is not None:
        try:
            map_bones(self, root)
        except _error_type() as exc:
            self.map_error = str(exc)


class AvatarMotionSettings(bpy.types.PropertyGroup):
    """The Motion panel's options (``scene.avatar_motion``)."""

    __annotations__ = {
        "bvh_path": StringProperty(name="BVH", subtype="FILE_PATH", update=_path_changed,
                                   description="A .bvh clip, or a folder of them"),
        "clips": CollectionProperty(type=AvatarClip),
        "clip_index": IntProperty(name="Clip", default=0, update=_clip_changed),
        "folder_error": StringProperty(name="Folder error"),
        "listed_folder": StringProperty(name="Listed folder", subtype="DIR_PATH"),
        "frame_start": IntProperty(
            name="Start", min=0, default=0,
            description="First source frame, 0-based (as the CLI's --frames A:B)",
        ),
        "frame_end": IntProperty(
            name="Stop", min=0, default=0,
            description="Source frame to stop before (0 = to the end of the clip)",
        ),
        "resample": BoolProperty(name="Resample", default=False,
                                 description="Resample the clip to FPS (off: its own rate)"),
        "fps": FloatProperty(name="FPS", min=1.0, max=1000.0, default=30.0,
                             description="The rate to resample to (with Resample on)"),
        "in_place": BoolProperty(name="In place", default=False,
                                 description="Remove the horizontal root motion"),
        "bones": CollectionProperty(type=AvatarBoneRow),
        "bone_index": IntProperty(default=0),
        "avatar_bones": CollectionProperty(type=AvatarRoleBone),
        "mapped_clip": StringProperty(name="Mapped clip", subtype="FILE_PATH"),
        "map_error": StringProperty(name="Mapping error"),
        "custom_map": BoolProperty(
            name="Edited mapping", default=False,
            description="Apply uses the mapping edited or loaded here (off: automatic)",
        ),
        "custom_table": StringProperty(name="Mapping", default="{}",
                                       description="{role: [clip bone]} as JSON"),
        "match_names": BoolProperty(
            name="Same names", default=True, update=_match_changed,
            description="Also drive Avatar bones named as a clip bone (MakeHuman clips)",
        ),
        "map_path": StringProperty(name="Bone map", subtype="FILE_PATH",
                                   description="A bone map .json file"),
        "show_mapping": BoolProperty(name="Bone mapping", default=False),
        "show_poses": BoolProperty(name="Pose library", default=True),
        "walk_speed": FloatProperty(name="Speed", min=0.2, max=3.0, default=1.3,
                                    unit="VELOCITY", description="Walking speed (m/s)"),
        "walk_steps": IntProperty(name="Steps", min=1, max=200, default=8,
                                  description="Number of steps (two make a stride)"),
        "poses": CollectionProperty(type=AvatarPose),
        "pose_folder": StringProperty(name="Pose folder", subtype="DIR_PATH",
                                      description="More poses (.bvh, MPFB .json)"),
        "pose_search": StringProperty(name="Search", options={"TEXTEDIT_UPDATE"}),
    }  # fmt: skip


# ------------------------------------------------------------------------ the logic


def list_clips(settings) -> int:
    """Fill ``settings.clips`` from the folder ``bvh_path`` (bad clips listed with their
    error); returns how many. Raises AvatarError for a missing or empty folder."""
    from avatar.motion import clips

    folder = bpy.path.abspath(settings.bvh_path)
    found = clips.list_folder(folder)
    settings.clips.clear()
    settings.listed_folder = folder
    for clip in found:
        item = settings.clips.add()
        item.name, item.path, item.error = clip.name, str(clip.path), clip.error
        item.frames, item.fps = clip.frames, clip.fps
    settings.folder_error = ""
    usable = [i for i, c in enumerate(found) if not c.error]
    if not 0 <= settings.clip_index < len(found) or found[settings.clip_index].error:
        settings.clip_index = usable[0] if usable else 0
    return len(found)


def selected_clip(settings) -> str:
    """The clip Apply uses: the file ``bvh_path``, or the clip chosen in its folder.
    Raises AvatarError when there is none (no path, empty folder, a bad clip chosen)."""
    from avatar.errors import AvatarError

    if not settings.bvh_path.strip():
        raise AvatarError("choose a BVH file or folder first")
    path = bpy.path.abspath(settings.bvh_path)
    if not os.path.isdir(path):
        return path
    if not len(settings.clips) or settings.listed_folder != path:
        list_clips(settings)  # raises for an empty folder
    if not 0 <= settings.clip_index < len(settings.clips):
        raise AvatarError("choose a clip in the list")
    clip = settings.clips[settings.clip_index]
    if clip.error:
        raise AvatarError(f"{clip.name}: {clip.error}")
    return clip.path


def custom_table(settings) -> dict:
    """The edited mapping {role: [clip bone]} (AvatarError when it is not one)."""
    from avatar.errors import AvatarError

    try:
        table = json.loads(settings.custom_table or "{}")
    except json.JSONDecodeError as exc:
        raise AvatarError(f"the edited bone mapping is not JSON: {exc}") from None
    if not isinstance(table, dict):
        raise AvatarError("the edited bone mapping is not a {role: [bone]} table")
    return table


def motion_spec(settings, path: str) -> dict:
    """The Motion panel as the spec ``avatar.blender.character.apply_motion`` takes."""
    frames = None
    if settings.frame_start or settings.frame_end:
        frames = [settings.frame_start, settings.frame_end or None]  # a Python slice, A:B
    spec = {"path": path, "frames": frames, "fps": settings.fps if settings.resample else None,
            "in_place": settings.in_place}  # fmt: skip
    if settings.custom_map:
        spec["bone_map"] = custom_table(settings)
    if not settings.match_names:
        spec["match_names"] = False
    return spec


def map_bones(settings, root) -> int:
    """Fill ``settings.bones`` with the mapping of the selected clip onto ``root``'s rig
    (the edited one when ``custom_map``); returns how many clip bones drive a bone."""
    from avatar.errors import AvatarError
    from avatar.motion import mapping

    path = selected_clip(settings)
    if not os.path.isfile(path):
        raise AvatarError(f"{path}: no such BVH file")
    skeleton, clip = motion_cache.clip(path)
    human = motion_cache.human(root)
    table = custom_table(settings) if settings.custom_map else None
    rows = mapping.rows(skeleton, clip, human.skeleton, table, settings.match_names)
    roles = motion_cache.roles(root)
    _write_rows(settings, rows)
    if [b.name for b in settings.avatar_bones] != list(roles):
        settings.avatar_bones.clear()
        for name, role in roles.items():
            item = settings.avatar_bones.add()
            item.name, item.role = name, role
    settings.mapped_clip = path
    settings.map_error = ""
    return sum(1 for r in rows if r.target)


def _write_rows(settings, rows) -> None:
    """Rows into ``settings.bones``, in place when the bones are the same (an edit's
    callback runs on one of these items: it must not be freed under it)."""
    with _syncing():
        if [b.name for b in settings.bones] != [r.source for r in rows]:
            settings.bones.clear()
            for _ in rows:
                settings.bones.add()
        for item, row in zip(settings.bones, rows, strict=True):
            item.name, item.target, item.role, item.how = row.source, row.target, row.role, row.how


def edit_row(settings, row) -> None:
    """A row's target was changed (by hand or script): make the mapping the edited one,
    with the row's clip bone playing the role of its new Avatar bone ("" none), and show
    what Apply will now do."""
    from avatar.motion import mapping

    roles = {b.name: b.role for b in settings.avatar_bones}
    role = roles.get(row.target, "")
    if row.target and not role:
        settings.map_error = f"{row.target!r} is not an Avatar bone with a role; pick one"
        with _syncing():
            row.target = ""
    pairs = [(b.name, b.role) for b in settings.bones
             if b.role and b.role != role and b.as_pointer() != row.as_pointer()]  # fmt: skip
    pairs.append((row.name, role))
    settings.custom_table = json.dumps(mapping.table_of(pairs))
    settings.custom_map = True
    with _syncing():
        for b in settings.bones:
            if role and b.role == role and b.as_pointer() != row.as_pointer():
                b.target, b.role, b.how = "", "", ""
        row.role, row.how = role, "role" if role else ""
    root = root_of(bpy.context.object)
    if root is not None and settings.mapped_clip:
        try:  # show what Apply will do (same-named bones may still pair)
            map_bones(settings, root)
        except _error_type() as exc:
            settings.map_error = str(exc)


def refresh_poses(settings) -> int:
    """Fill ``settings.poses`` from the pose library; returns how many."""
    from avatar.motion import poselib

    found = poselib.list_poses(_pose_folders(settings))
    settings.poses.clear()
    for entry in found:
        item = settings.poses.add()
        item.name, item.source, item.description = entry.name, entry.source, entry.description
        item.path = str(entry.path) if entry.path is not None else ""
    return len(found)


def _pose_folders(settings) -> list[str]:
    return [bpy.path.abspath(settings.pose_folder)] if settings.pose_folder else []


def forget_motion(root) -> None:
    """Take the motion off a character: its actions, garment corrections and the stored
    motion, so later changes do not bring it back."""
    from avatar.blender import character
    from avatar.blender import pose as pose_bridge

    pose_bridge.stop_motion(root)
    for key in (character.MOTION_KEY, character.REPORT_KEY, character.CARD_KEY):
        if key in root.keys():
            del root[key]


def _rigged_root(context):
    from avatar.errors import AvatarError

    root = root_of(context.object)
    if root is None or root.type != "ARMATURE":
        raise AvatarError("select a rigged Avatar character first")
    return root


def _apply(context, spec: dict) -> str:
    """Rebuild the active character playing ``spec`` (a clip or the walk)."""
    from avatar.blender import character

    built, summary = character.apply_motion(context.object, spec)
    _select(context, built)
    live.sync_from_recipe(built.root)
    return summary


# ------------------------------------------------------------------------ operators


class _OnCharacter:
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return root_of(context.object) is not None


class AVATAR_OT_apply_motion(_OnCharacter, bpy.types.Operator):
    """Retarget the BVH clip (or the clip chosen in the folder) onto the active character
    and play it"""

    bl_idname = "avatar.apply_motion"
    bl_label = "Apply"

    def execute(self, context):
        settings = context.scene.avatar_motion

        def apply():  # the character is rebuilt (garments get per-frame shape keys)
            return _apply(context, motion_spec(settings, selected_clip(settings)))

        return _call(self, apply)


class AVATAR_OT_list_clips(bpy.types.Operator):
    """List the clips of the BVH folder again"""

    bl_idname = "avatar.list_clips"
    bl_label = "Refresh Clips"

    def execute(self, context):
        settings = context.scene.avatar_motion

        def scan():
            count = list_clips(settings)
            bad = sum(1 for c in settings.clips if c.error)
            return f"{count} clips" + (f", {bad} unusable" if bad else "")

        return _call(self, scan)


class AVATAR_OT_map_bones(_OnCharacter, bpy.types.Operator):
    """Show how the clip's bones map onto the active character's (editable)"""

    bl_idname = "avatar.map_bones"
    bl_label = "Map Bones"

    def execute(self, context):
        settings = context.scene.avatar_motion

        def show():
            count = map_bones(settings, root_of(context.object))
            settings.show_mapping = True
            return f"{count} of {len(settings.bones)} clip bones drive an Avatar bone"

        return _call(self, show)


class AVATAR_OT_reset_bone_map(bpy.types.Operator):
    """Forget the edited mapping: map the clip's bones automatically again"""

    bl_idname = "avatar.reset_bone_map"
    bl_label = "Automatic Mapping"

    def execute(self, context):
        settings = context.scene.avatar_motion
        root = root_of(context.object)

        def reset():
            settings.custom_map = False
            settings.custom_table = "{}"
            if settings.mapped_clip and root is not None:
                map_bones(settings, root)
            return "Bone mapping: automatic"

        return _call(self, reset)


class AVATAR_OT_save_bone_map(bpy.types.Operator):
    """Save the bone mapping shown as a bone map file (reusable for clips of this skeleton)"""

    bl_idname = "avatar.save_bone_map"
    bl_label = "Save Bone Map"

    filepath: StringProperty(subtype="FILE_PATH")
    filter_glob: StringProperty(default="*.json", options={"HIDDEN"})

    @classmethod
    def poll(cls, context):
        settings = context.scene.avatar_motion
        return settings.custom_map or len(settings.bones) > 0

    def invoke(self, context, event):
        settings = context.scene.avatar_motion
        stem = os.path.splitext(os.path.basename(settings.mapped_clip or "bonemap"))[0]
        self.filepath = settings.map_path or f"{stem}_bonemap.json"
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        settings = context.scene.avatar_motion
        path = bpy.path.ensure_ext(bpy.path.abspath(self.filepath or settings.map_path), ".json")

        def save():
            from avatar.errors import AvatarError
            from avatar.motion import mapping

            if settings.custom_map:
                table = custom_table(settings)
            else:
                table = mapping.table_of((b.name, b.role) for b in settings.bones)
            if not table:
                raise AvatarError("the mapping is empty: map the bones first")
            try:
                mapping.save(path, table, description="saved from Avatar's Motion panel")
            except OSError as exc:
                raise AvatarError(f"{path}: {exc.strerror or exc}") from None
            settings.map_path = path
            return f"Saved {len(table)} roles to {path}"

        return _call(self, save)


class AVATAR_OT_load_bone_map(bpy.types.Operator):
    """Use a bone map file for the clips (Apply uses it)"""

    bl_idname = "avatar.load_bone_map"
    bl_label = "Load Bone Map"

    filepath: StringProperty(subtype="FILE_PATH")
    filter_glob: StringProperty(default="*.json", options={"HIDDEN"})

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        settings = context.scene.avatar_motion
        path = bpy.path.abspath(self.filepath or settings.map_path)
        root = root_of(context.object)

        def load():
            from avatar.motion import mapping

            table = mapping.load(path)  # raises before anything changes
            settings.custom_table = json.dumps(table)
            settings.custom_map = True
            settings.map_path = path
            if root is not None and settings.bvh_path:
                try:
                    map_bones(settings, root)
                except _error_type() as exc:
                    settings.map_error = str(exc)
            return f"Bone map {os.path.basename(path)}: {len(table)} roles"

        return _call(self, load)


class AVATAR_OT_apply_pose(_OnCharacter, bpy.types.Operator):
    """Pose the active character (its motion stops; garments follow)"""

    bl_idname = "avatar.apply_pose"
    bl_label = "Pose"

    name: StringProperty(name="Pose", default="t-pose",
                         description="A built-in pose, a library pose or a pose file")  # fmt: skip

    def execute(self, context):
        settings = context.scene.avatar_motion

        def pose():
            from avatar.blender import pose as pose_bridge

            root = _rigged_root(context)
            posed = motion_cache.human(root).pose(self.name, _pose_folders(settings))
            forget_motion(root)  # the pose is computed: now change the character
            pose_bridge.set_pose(root, posed)
            return f"{root.name}: {self.name}"

        return _call(self, pose)


class AVATAR_OT_rest_pose(_OnCharacter, bpy.types.Operator):
    """Put the active character in its rest pose (its pose and motion cleared)"""

    bl_idname = "avatar.rest_pose"
    bl_label = "Rest"

    def execute(self, context):
        def rest():
            from avatar.blender import pose as pose_bridge

            root = _rigged_root(context)
            forget_motion(root)
            pose_bridge.clear_pose(root)
            return f"{root.name}: rest pose"

        return _call(self, rest)


class AVATAR_OT_walk(_OnCharacter, bpy.types.Operator):
    """Make the active character walk (the built-in procedural walk; no clip needed)"""

    bl_idname = "avatar.walk"
    bl_label = "Walk"

    speed: FloatProperty(name="Speed", min=0.2, max=3.0, default=1.3, unit="VELOCITY")
    steps: IntProperty(name="Steps", min=1, max=200, default=8)
    use_panel: BoolProperty(default=True, options={"SKIP_SAVE", "HIDDEN"})

    def invoke(self, context, event):
        return self.execute(context)

    def execute(self, context):
        settings = context.scene.avatar_motion
        speed, steps = self.speed, self.steps
        if self.use_panel and not self.properties.is_property_set("speed"):
            speed, steps = settings.walk_speed, settings.walk_steps
        render = context.scene.render
        walk = {"speed": round(float(speed), 4), "steps": int(steps)}  # not float32 noise
        spec = {"walk": walk, "fps": render.fps / render.fps_base}
        return _call(self, lambda: _apply(context, spec))


class AVATAR_OT_refresh_poses(bpy.types.Operator):
    """List the pose library (built-in poses, your pose folder, AVATAR_POSES_PATH)"""

    bl_idname = "avatar.refresh_poses"
    bl_label = "Load Poses"

    def execute(self, context):
        return _call(self, lambda: f"{refresh_poses(context.scene.avatar_motion)} poses")


# ------------------------------------------------------------------------ lists, panel


class AVATAR_UL_clips(bpy.types.UIList):
    def draw_item(self, context, layout, data, item, icon, active_data, active_propname):
        row = layout.row()
        if item.error:
            row.label(text=item.name, icon="ERROR")
            row.label(text=item.error)
        else:
            row.label(text=item.name, icon="ARMATURE_DATA")
            row.label(text=f"{item.frames} @ {item.fps:.0f} fps")


class AVATAR_UL_bones(bpy.types.UIList):
    def draw_item(self, context, layout, data, item, icon, active_data, active_propname):
        row = layout.row(align=True)
        split = row.split(factor=0.42, align=True)
        split.label(text=item.name, icon="BONE_DATA" if item.target else "BLANK1")
        sub = split.row(align=True)
        sub.prop_search(item, "target", data, "avatar_bones", text="")
        if item.how == "name":
            sub.label(text="", icon="LINKED")


class AVATAR_PT_motion(bpy.types.Panel):
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Avatar"
    bl_label = "Motion"
    bl_idname = "AVATAR_PT_motion"
    bl_order = 2  # after Body (0) and Dress (1)

    def draw(self, context):
        settings = context.scene.avatar_motion
        layout = self.layout
        root = root_of(context.object)
        _draw_clip(layout, settings)
        _draw_mapping(layout, settings, root)
        _draw_report(layout, root)
        _draw_poses(layout, settings, root)


def _draw_clip(layout, settings):
    layout.prop(settings, "bvh_path")
    if settings.folder_error:
        layout.label(text=settings.folder_error, icon="ERROR")
    if len(settings.clips):
        row = layout.row()
        row.template_list("AVATAR_UL_clips", "", settings, "clips", settings, "clip_index",
                          rows=4)  # fmt: skip
        row.operator("avatar.list_clips", text="", icon="FILE_REFRESH")
    row = layout.row(align=True)
    row.prop(settings, "frame_start")
    row.prop(settings, "frame_end")
    row = layout.row(align=True)
    row.prop(settings, "resample", toggle=True)
    fps = row.row(align=True)
    fps.active = settings.resample  # "FPS 0.00" read as a broken clip; off, it is the clip's
    fps.prop(settings, "fps")
    layout.prop(settings, "in_place")
    row = layout.row()
    row.scale_y = 1.3
    row.operator("avatar.apply_motion", icon="PLAY")


def _draw_mapping(layout, settings, root):
    box = layout.box()
    icon = "TRIA_DOWN" if settings.show_mapping else "TRIA_RIGHT"
    # One label, short enough for the default width (split in two it showed "Bone m...").
    state = "edited" if settings.custom_map else "automatic"
    box.prop(settings, "show_mapping", text=f"Bone map: {state}", icon=icon, emboss=False)
    if not settings.show_mapping:
        return
    row = box.row(align=True)
    row.operator("avatar.map_bones", icon="BONE_DATA")
    row.prop(settings, "match_names", toggle=True)
    if settings.map_error:
        box.label(text=settings.map_error, icon="ERROR")
    if len(settings.bones):
        box.template_list("AVATAR_UL_bones", "", settings, "bones", settings, "bone_index",
                          rows=8)  # fmt: skip
    row = box.row(align=True)
    row.prop(settings, "map_path", text="")
    row.operator("avatar.load_bone_map", text="", icon="IMPORT")
    row.operator("avatar.save_bone_map", text="", icon="EXPORT")
    row.operator("avatar.reset_bone_map", text="", icon="LOOP_BACK")


def _draw_report(layout, root):
    if root is None:
        return
    from . import motion_report

    rows = motion_report.rows(root)
    if not rows:
        return
    box = layout.box()
    alerts = sum(alert for _, _, alert in rows)
    box.label(text=f"Retarget quality: {alerts} to check" if alerts else "Retarget quality",
              icon="ERROR" if alerts else "CHECKMARK")  # fmt: skip
    column = box.column(align=True)
    for label, value, alert in rows:
        # No icon per row: at the sidebar's default width it cut the labels to two letters.
        split = column.split(factor=motion_report.LABEL_SHARE)
        split.alert = alert  # drawn red
        split.label(text=label)
        split.label(text=value)


def _draw_poses(layout, settings, root):
    box = layout.box()
    row = box.row(align=True)
    row.scale_y = 1.2
    row.operator("avatar.rest_pose", icon="ARMATURE_DATA")
    row.operator("avatar.apply_pose", text="T-pose").name = "t-pose"
    row.operator("avatar.apply_pose", text="A-pose").name = "a-pose"
    row = box.row(align=True)
    row.operator("avatar.walk", icon="MOD_DYNAMICPAINT")
    row.prop(settings, "walk_speed")
    row.prop(settings, "walk_steps")
    icon = "TRIA_DOWN" if settings.show_poses else "TRIA_RIGHT"
    box.prop(settings, "show_poses", icon=icon, emboss=False)
    if not settings.show_poses:
        return
    row = box.row(align=True)
    row.prop(settings, "pose_folder", text="")
    row.operator("avatar.refresh_poses", text="" if len(settings.poses) else "Load Poses",
                 icon="FILE_REFRESH")  # fmt: skip
    if not len(settings.poses):
        return
    box.prop(settings, "pose_search", text="", icon="VIEWZOOM")
    text = settings.pose_search.strip().lower()
    grid = box.grid_flow(row_major=True, columns=0, even_columns=True, align=True)
    for item in settings.poses:
        if item.name == "rest" or (text and text not in item.name.lower()):
            continue
        cell = grid.column(align=True)
        icon_id = motion_cache.pose_icon(item.name, item.path)
        if icon_id:
            cell.template_icon(icon_value=icon_id, scale=3.0)
        cell.operator("avatar.apply_pose", text=item.name).name = item.path or item.name
        cell.enabled = root is not None


CLASSES = (
    AvatarClip,
    AvatarBoneRow,
    AvatarRoleBone,
    AvatarPose,
    AvatarMotionSettings,
    AVATAR_OT_apply_motion,
    AVATAR_OT_list_clips,
    AVATAR_OT_map_bones,
    AVATAR_OT_reset_bone_map,
    AVATAR_OT_save_bone_map,
    AVATAR_OT_load_bone_map,
    AVATAR_OT_apply_pose,
    AVATAR_OT_rest_pose,
    AVATAR_OT_walk,
    AVATAR_OT_refresh_poses,
    AVATAR_UL_clips,
    AVATAR_UL_bones,
    AVATAR_PT_motion,
)

POINTERS = {(bpy.types.Scene, "avatar_motion"): AvatarMotionSettings}


def release() -> None:
    motion_cache.release()

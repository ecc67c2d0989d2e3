"""Export panel: the active character to glTF/GLB, FBX or USD with an engine preset (Unity,
Unreal, Godot, Blender), a photo studio around it, and the camera as OpenCV JSON.

For scripts::

    bpy.ops.avatar.export_character(filepath="/tmp/hero.fbx", preset="UNREAL")
    bpy.ops.avatar.studio(engine="CYCLES")
    bpy.ops.avatar.export_camera(filepath="/tmp/camera.json")

Called from the panel's buttons (``use_panel``) they take the panel's settings. Errors (no
character, a path that cannot be written, an exporter failure) are one-line reports; the
file is written to a temporary name and moved into place only when complete.
"""

import os

import bpy
from bpy.props import BoolProperty, EnumProperty, IntProperty, StringProperty
from bpy_extras.io_utils import ExportHelper

from . import live
from .operators import _call, root_of

# avatar.blender.engine_presets.PRESETS, spelt out so the panel draws without the library.
PRESETS = (
    ("UNITY", "Unity", "FBX in metres, Y-up, 4 bone weights per vertex"),
    (
        "UNREAL",
        "Unreal",
        "FBX in centimetres, a root bone at the origin, identifier bone "
        "names, 4 bone weights per vertex",
    ),  # fmt: skip
    ("GODOT", "Godot", "glTF binary, identifier bone names, 4 bone weights per vertex"),
    ("BLENDER", "Blender / generic", "Metres, every bone weight, names as they are"),
)
FORMATS = (
    ("GLB", "glTF (.glb)", "glTF 2.0 binary: textures inside"),
    ("FBX", "FBX (.fbx)", "FBX binary: textures embedded"),
    ("USD", "USD (.usdz)", "USD zip package: textures inside"),
)
AUTO = (("AUTO", "From preset", "The file's suffix, else the preset's format"),)
SHAPE_KEYS = (
    ("PRESET", "Preset", "As the engine preset says (kept)"),
    ("KEEP", "Keep", "Shape keys and their animation (face units, garment corrections)"),
    ("BAKE", "Bake", "The current shape-key mix becomes the mesh; no shape keys"),
)
ENGINES = (("CYCLES", "Cycles", "Path traced"), ("EEVEE", "EEVEE", "Real time"))


class AvatarExportSettings(bpy.types.PropertyGroup):
    filepath: StringProperty(name="File", subtype="FILE_PATH", default="//avatar.fbx")
    preset: EnumProperty(name="Engine", items=PRESETS, default="UNITY")
    file_format: EnumProperty(name="Format", items=AUTO + FORMATS, default="AUTO")
    shape_keys: EnumProperty(name="Shape Keys", items=SHAPE_KEYS, default="PRESET")
    engine: EnumProperty(name="Render", items=ENGINES, default="CYCLES")
    samples: IntProperty(name="Samples", min=1, max=4096, default=64)
    camera_path: StringProperty(name="Camera", subtype="FILE_PATH", default="//camera.json")


def _settings(context):
    return context.scene.avatar_export


def _path(value):
    """An absolute file path from a property ('//' is the .blend's folder)."""
    return os.path.abspath(bpy.path.abspath(value)) if value else ""


class AVATAR_OT_export_character(bpy.types.Operator, ExportHelper):
    """Export the active character (armature, body, garments, hair, animation) for a game
    engine or another application"""

    bl_idname = "avatar.export_character"
    bl_label = "Export Character"
    bl_options = {"REGISTER"}

    filename_ext = ".fbx"  # ExportHelper wants one; execute makes it match the format
    filter_glob: StringProperty(default="*.glb;*.gltf;*.fbx;*.usd;*.usda;*.usdc;*.usdz",
                                options={"HIDDEN"})  # fmt: skip
    filepath: StringProperty(name="File", subtype="FILE_PATH", default="")
    preset: EnumProperty(name="Engine", items=PRESETS, default="UNITY")
    format: EnumProperty(name="Format", items=AUTO + FORMATS, default="AUTO")
    shape_keys: EnumProperty(name="Shape Keys", items=SHAPE_KEYS, default="PRESET")
    use_panel: BoolProperty(default=False, options={"SKIP_SAVE", "HIDDEN"})

    def check(self, context):
        return False  # keep the typed suffix; execute picks the format from it

    def invoke(self, context, event):
        settings = _settings(context)
        self.preset, self.format = settings.preset, settings.file_format
        self.shape_keys = settings.shape_keys
        root = root_of(context.object)
        name = bpy.path.clean_name(root.name) if root is not None else "avatar"
        self.filepath = os.path.join(os.path.dirname(_path(settings.filepath)) or "",
                                     name + ".fbx")  # fmt: skip
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        settings = _settings(context)
        if self.use_panel:
            filepath, preset = settings.filepath, settings.preset
            fmt, keys = settings.file_format, settings.shape_keys
        else:
            filepath, preset, fmt, keys = self.filepath, self.preset, self.format, self.shape_keys
        root = root_of(context.object)
        if root is None:
            self.report({"ERROR"}, "select an Avatar character to export")
            return {"CANCELLED"}
        if not filepath.strip():
            self.report({"ERROR"}, "choose a file to export to")
            return {"CANCELLED"}

        def export():
            from avatar.blender import export as exporter

            if not root.get("avatar_settled", 1):  # a slider just moved: exact garments first
                live.settle_now(root)
            path = exporter.export_character(
                root, _path(filepath), preset,
                "" if fmt == "AUTO" else fmt, "" if keys == "PRESET" else keys,
            )  # fmt: skip
            return f"Exported {root.name} for {preset.title()}: {path}"

        return _call(self, export)


class AVATAR_OT_studio(bpy.types.Operator):
    """Set up a photo studio around the active character: a curved backdrop, a camera
    framing it, key, fill and rim lights, render settings (running it again updates them)"""

    bl_idname = "avatar.studio"
    bl_label = "Studio"
    bl_options = {"REGISTER", "UNDO"}

    engine: EnumProperty(name="Render", items=ENGINES, default="CYCLES")
    samples: IntProperty(name="Samples", min=1, max=4096, default=64)
    use_panel: BoolProperty(default=False, options={"SKIP_SAVE", "HIDDEN"})

    def execute(self, context):
        settings = _settings(context)
        engine = settings.engine if self.use_panel else self.engine
        samples = settings.samples if self.use_panel else self.samples
        root = root_of(context.object)
        if root is None:
            self.report({"ERROR"}, "select an Avatar character to set the studio around")
            return {"CANCELLED"}

        def stage():
            from avatar.blender import studio

            parts = [o for o in (root, *root.children_recursive) if o.type == "MESH"]
            studio.setup(parts, engine=engine, samples=samples, scene=context.scene)
            return f"Studio around {root.name} ({engine.title()}, {samples} samples)"

        return _call(self, stage)


class AVATAR_OT_export_camera(bpy.types.Operator):
    """Write the active camera (or the scene's) as OpenCV intrinsics K and extrinsics
    world_to_camera in JSON, as the scene renders it"""

    bl_idname = "avatar.export_camera"
    bl_label = "Export Camera"
    bl_options = {"REGISTER"}

    filepath: StringProperty(name="File", subtype="FILE_PATH", default="")
    filter_glob: StringProperty(default="*.json", options={"HIDDEN"})
    use_panel: BoolProperty(default=False, options={"SKIP_SAVE", "HIDDEN"})

    def execute(self, context):
        filepath = _settings(context).camera_path if self.use_panel else self.filepath
        active = context.object
        camera = active if active is not None and active.type == "CAMERA" else None
        if not filepath.strip():
            self.report({"ERROR"}, "choose a file to write the camera to")
            return {"CANCELLED"}

        def export():
            from avatar.blender import export as exporter

            path = exporter.export_camera(_path(filepath), camera, context.scene)
            return f"Camera written to {path}"

        return _call(self, export)


class AVATAR_PT_export(bpy.types.Panel):
    bl_label = "Export"
    bl_idname = "AVATAR_PT_export"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Avatar"
    bl_order = 10

    def draw(self, context):
        settings = _settings(context)
        layout = self.layout
        root = root_of(context.object)
        if root is None:
            layout.label(text="Select a character to export it", icon="INFO")
        col = layout.column(align=True)
        col.prop(settings, "preset")
        col.prop(settings, "file_format")
        col.prop(settings, "shape_keys")
        col.prop(settings, "filepath", text="")
        row = layout.row()
        row.scale_y = 1.3
        row.enabled = root is not None
        row.operator("avatar.export_character", text="Export", icon="EXPORT").use_panel = True
        box = layout.box()
        row = box.row(align=True)
        row.prop(settings, "engine", text="")
        row.prop(settings, "samples")
        row = box.row()
        row.enabled = root is not None
        row.operator("avatar.studio", text="Studio", icon="LIGHT_AREA").use_panel = True
        box = layout.box()
        box.prop(settings, "camera_path", text="")
        box.operator("avatar.export_camera", icon="CAMERA_DATA").use_panel = True


CLASSES = (
    AvatarExportSettings,
    AVATAR_OT_export_character,
    AVATAR_OT_studio,
    AVATAR_OT_export_camera,
    AVATAR_PT_export,
)
POINTERS = {(bpy.types.Scene, "avatar_export"): AvatarExportSettings}

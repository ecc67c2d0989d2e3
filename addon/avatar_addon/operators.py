"""Operators: adapters of a few lines (settings -> recipe -> one library call -> report).

``AvatarError`` becomes an error report and ``{'CANCELLED'}``; anything else is a bug and
propagates with its traceback.
"""

import os

import bpy

from . import catalogue

INSTALL_HINT = ("the avatar library is not importable: install the extension zip built by "
                "addon/build.py, or set AVATAR_PYTHONPATH to its src folder")  # fmt: skip


def _call(operator, action):
    """Run ``action()`` (one library call) and turn AvatarError into an error report."""
    try:
        from avatar.errors import AvatarError
    except ImportError:
        operator.report({"ERROR"}, INSTALL_HINT)
        return {"CANCELLED"}
    _use_preferences()
    try:
        message = action()
    except AvatarError as exc:
        operator.report({"ERROR"}, str(exc))
        return {"CANCELLED"}
    operator.report({"INFO"}, message)
    return {"FINISHED"}


def _use_preferences():
    """The add-on's folders, when set: assets are the library's AVATAR_ASSETS, and the
    clothes folder is scanned for the Dress panel's list."""
    addon = bpy.context.preferences.addons.get(__package__)
    prefs = addon.preferences if addon is not None else None
    if prefs is not None and prefs.assets:
        os.environ["AVATAR_ASSETS"] = bpy.path.abspath(prefs.assets)
    if prefs is not None and prefs.clothes:
        _scan_clothes(bpy.path.abspath(prefs.clothes))


# avatar.clothes.library.ENV_PATH; spelt out so the panels work without the library.
CLOTHES_PATH = "AVATAR_CLOTHES_PATH"


def _clothes_folders():
    return [p for p in os.environ.get(CLOTHES_PATH, "").split(os.pathsep) if p]


def _scan_clothes(folder):
    """Let the library list the garments in ``folder`` for the rest of this session."""
    folders = _clothes_folders()
    if os.path.normpath(folder) not in map(os.path.normpath, folders):
        os.environ[CLOTHES_PATH] = os.pathsep.join([*folders, folder])


def _character():
    from avatar.blender import character

    return character


class AVATAR_OT_create_human(bpy.types.Operator):
    """Create a new character from the Body panel's settings"""

    bl_idname = "avatar.create_human"
    bl_label = "Create"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        recipe = context.scene.avatar.recipe()
        location = tuple(context.scene.cursor.location)

        def create():
            built = _character().create(recipe, location=location)
            _select(context, built)
            return f"Created {built.root.name}"

        return _call(self, create)


class AVATAR_OT_update_human(bpy.types.Operator):
    """Rebuild the active character with the Body panel's settings (keeps clothes, motion)"""

    bl_idname = "avatar.update_human"
    bl_label = "Update"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _stored_recipe(context) is not None

    def execute(self, context):
        recipe = context.scene.avatar.recipe(_stored_recipe(context))
        obj = context.object
        return _call(self, lambda: _rebuild(context, obj, recipe, "Updated"))


class AVATAR_OT_load_recipe(bpy.types.Operator):
    """Set the Body panel's sliders from the active character"""

    bl_idname = "avatar.load_recipe"
    bl_label = "From Selected"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _stored_recipe(context) is not None

    def execute(self, context):
        context.scene.avatar.load(_stored_recipe(context))
        return {"FINISHED"}


class AVATAR_OT_add_target(bpy.types.Operator):
    """Add the searched local target as a slider"""

    bl_idname = "avatar.add_target"
    bl_label = "Add"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        settings = context.scene.avatar
        name = settings.target_search.strip()
        if name not in catalogue.local_targets():
            self.report({"ERROR"}, f"unknown local target {name!r}")
            return {"CANCELLED"}
        if name not in settings.targets:
            settings.targets.add().name = name
        return {"FINISHED"}


class AVATAR_OT_remove_target(bpy.types.Operator):
    """Remove a local target slider"""

    bl_idname = "avatar.remove_target"
    bl_label = "Remove"
    bl_options = {"REGISTER", "UNDO"}

    name: bpy.props.StringProperty()

    def execute(self, context):
        targets = context.scene.avatar.targets
        index = targets.find(self.name)
        if index >= 0:
            targets.remove(index)
        return {"FINISHED"}


class AVATAR_OT_refresh_library(bpy.types.Operator):
    """Reload the clothes library list"""

    bl_idname = "avatar.refresh_library"
    bl_label = "Refresh"

    def execute(self, context):
        return _call(self, lambda: f"{_refresh_garments(context.scene.avatar)} garments")


def _refresh_garments(settings):
    """Fill the Dress panel's list from the library; returns how many it holds."""
    items = settings.garments
    items.clear()
    for name, category, entry in catalogue.garments():
        item = items.add()
        item.name, item.category, item.entry = name, category, entry
    return len(items)


class _DressOperator:
    """Shared by Wear / Take Off: edit the active character's clothes list, rebuild."""

    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        settings = context.scene.avatar
        return (_stored_recipe(context) is not None
                and 0 <= settings.garment_index < len(settings.garments))  # fmt: skip

    def execute(self, context):
        settings = context.scene.avatar
        garment = settings.garments[settings.garment_index].entry
        recipe = _stored_recipe(context)
        clothes = [c for c in recipe.get("clothes") or [] if c != garment]
        recipe["clothes"] = clothes + [garment] if self.wear else clothes
        obj = context.object
        verb = "Wearing" if self.wear else "Took off"
        return _call(self, lambda: _rebuild(context, obj, recipe, f"{verb} {garment} on"))


class AVATAR_OT_wear(_DressOperator, bpy.types.Operator):
    """Put the selected garment on the active character"""

    bl_idname = "avatar.wear"
    bl_label = "Wear"
    wear = True


class AVATAR_OT_take_off(_DressOperator, bpy.types.Operator):
    """Take the selected garment off the active character"""

    bl_idname = "avatar.take_off"
    bl_label = "Remove"
    wear = False


class AVATAR_OT_apply_motion(bpy.types.Operator):
    """Retarget the BVH clip onto the active character and play it"""

    bl_idname = "avatar.apply_motion"
    bl_label = "Apply"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _stored_recipe(context) is not None and bool(context.scene.avatar.bvh_path)

    def execute(self, context):
        motion = context.scene.avatar.motion()
        obj = context.object

        def apply():  # the character is rebuilt (garments get per-frame shape keys)
            built, summary = _character().apply_motion(obj, motion)
            _select(context, built)
            return summary

        return _call(self, apply)


class AVATAR_OT_bind_garment(bpy.types.Operator):
    """Save the selected mesh, modelled on an Avatar character, as a garment that fits every body"""

    bl_idname = "avatar.bind_garment"
    bl_label = "Bind Selected as Garment"

    name: bpy.props.StringProperty(name="Name", description="The garment's name and file name")
    folder: bpy.props.StringProperty(
        name="Folder", subtype="DIR_PATH",
        description="Where to save it (default: your clothes folder, which the list scans)",
    )  # fmt: skip
    tags: bpy.props.StringProperty(name="Tags", description="Comma-separated, e.g. top, casual")

    @classmethod
    def poll(cls, context):
        return _garment_object(context) is not None

    def invoke(self, context, event):
        _use_preferences()
        self.name = bpy.path.clean_name(_garment_object(context).name)  # not the last one's
        self.folder = self.folder or _default_clothes_folder()
        return context.window_manager.invoke_props_dialog(self)

    def execute(self, context):
        garment = _garment_object(context)
        body = next((o for o in context.selected_objects if o is not garment and _root_of(o)), None)
        name = bpy.path.clean_name(self.name.strip() or garment.name)  # a safe file name
        tags = tuple(t.strip() for t in self.tags.split(",") if t.strip())

        def bind():
            folder = bpy.path.abspath(self.folder) if self.folder else _default_clothes_folder()
            path = _character().bind_garment(garment, folder, name, tags, body)
            _show_in_library(context.scene.avatar, folder, path)
            return f"Saved {path}: wear it from the Dress panel"

        return _call(self, bind)


def _garment_object(context):
    """The mesh to bind: the active object or the one selected mesh that is not part of a
    character; else an active selected mesh parented to one (modelled in its hierarchy)."""
    active = context.active_object
    meshes = [o for o in context.selected_objects if o.type == "MESH"]
    free = [o for o in meshes if _root_of(o) is None]
    if active in free:
        return active
    if len(free) == 1:
        return free[0]
    return active if active in meshes and not free else None


def _default_clothes_folder():
    """The first clothes folder the library scans, else one in Blender's user resources."""
    folders = _clothes_folders()
    return folders[0] if folders else bpy.utils.user_resource("DATAFILES", path="avatar/clothes")


def _show_in_library(settings, folder, path):
    """List the new garment in the Dress panel (scanning its folder from now on), selected."""
    _scan_clothes(folder)
    _refresh_garments(settings)
    entries = [os.path.normpath(g.entry) for g in settings.garments]
    if os.path.normpath(str(path)) in entries:
        settings.garment_index = entries.index(os.path.normpath(str(path)))


def _rebuild(context, obj, recipe, verb):
    """Rebuild ``obj``'s character from ``recipe``, keep it active; a one-line report."""
    built = _character().update(obj, recipe)
    _select(context, built)
    return f"{verb} {built.root.name}"


def _select(context, built):
    """Make the new character the selection, its root active (as Blender's Add menu does)."""
    for obj in context.view_layer.objects:
        obj.select_set(False)
    for obj in (built.root, *built.parts):
        obj.select_set(True)
    context.view_layer.objects.active = built.root


def _stored_recipe(context):
    """The recipe of the character the active object belongs to, or None."""
    root = _root_of(context.object)
    if root is None:
        return None
    import json

    return json.loads(root["avatar_recipe"])


def _root_of(obj):
    """The character root (holding the recipe) ``obj`` belongs to, or None; no library needed."""
    while obj is not None:
        if "avatar_recipe" in obj.keys():
            return obj
        obj = obj.parent
    return None

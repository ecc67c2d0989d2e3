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
    """The add-on's assets folder, when set, is the library's AVATAR_ASSETS."""
    addon = bpy.context.preferences.addons.get(__package__)
    folder = addon.preferences.assets if addon is not None else ""
    if folder:
        os.environ["AVATAR_ASSETS"] = bpy.path.abspath(folder)


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
        def refresh():
            items = context.scene.avatar.garments
            items.clear()
            for name, category, entry in catalogue.garments():
                item = items.add()
                item.name, item.category, item.entry = name, category, entry
            return f"{len(items)} garments"

        return _call(self, refresh)


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
        return _call(self, lambda: _character().apply_motion(obj, motion))


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
    obj = context.object
    while obj is not None:
        if "avatar_recipe" in obj.keys():
            import json

            return json.loads(obj["avatar_recipe"])
        obj = obj.parent
    return None

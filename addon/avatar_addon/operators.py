"""Operators: adapters of a few lines (properties -> recipe -> one library call -> report).

``AvatarError`` becomes an error report in the status bar and ``{'CANCELLED'}``; the library
computes every new state before it touches the scene, so a cancelled operator leaves the
character as it was. Anything else is a bug and propagates with its traceback.
"""

import os

import bpy
from bpy.props import BoolProperty, IntProperty, StringProperty

from . import catalogue, live, presets

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


def root_of(obj):
    """The character root (holding the recipe) ``obj`` belongs to, or None; no library needed."""
    while obj is not None:
        if "avatar_recipe" in obj.keys():
            return obj
        obj = obj.parent
    return None


def _active_root(context):
    return root_of(context.object)


class _OnCharacter:
    """Operators that act on the active character."""

    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _active_root(context) is not None


class AVATAR_OT_create_human(bpy.types.Operator):
    """Create a new human at the 3D cursor (rigged, with hair, brows and lashes by default)"""

    bl_idname = "avatar.create_human"
    bl_label = "Create Human"
    bl_options = {"REGISTER", "UNDO"}

    rig: StringProperty(name="Rig", default="", description="Rig name (default: the panel's)")
    rigged: BoolProperty(name="Rigged", default=True)
    default_look: BoolProperty(name="Hair, brows, lashes", default=True)
    name: StringProperty(name="Name", default="Avatar")

    def invoke(self, context, event):
        settings = context.scene.avatar
        self.rigged, self.default_look = settings.rigged, settings.default_look
        return self.execute(context)

    def execute(self, context):
        rig = self.rig or context.scene.avatar.rig
        clothes = list(_character().DEFAULT_LOOK) if self.default_look else []
        recipe = {"params": {}, "rig": rig, "clothes": clothes}
        location = tuple(context.scene.cursor.location)

        def create():
            built = _character().create(recipe, self.name or "Avatar", location, self.rigged,
                                        exact=False)  # fmt: skip
            _select(context, built)
            live.sync_from_recipe(built.root)
            live.schedule_settle(built.root)
            return f"Created {built.root.name}"

        return _call(self, create)


class AVATAR_OT_settle(_OnCharacter, bpy.types.Operator):
    """Fit the active character's garments exactly and refresh its skin now (this happens
    by itself a moment after the last slider change)"""

    bl_idname = "avatar.settle"
    bl_label = "Settle"

    def execute(self, context):
        root = _active_root(context)

        def settle():
            live.settle_now(root)
            return f"Settled {root.name}"

        return _call(self, settle)


def _set_body(context, params, verb):
    """Give the active character ``params`` (replacing its body), then settle it."""
    from avatar.blender import live as engine

    root = _active_root(context)
    engine.set_params(root, params)  # checks every name and value before changing anything
    live.sync_from_recipe(root)
    live.settle_now(root)
    return f"{verb} {root.name}"


class AVATAR_OT_reset_body(_OnCharacter, bpy.types.Operator):
    """Every body parameter of the active character back to its default"""

    bl_idname = "avatar.reset_body"
    bl_label = "Reset"

    def execute(self, context):
        return _call(self, lambda: _set_body(context, {}, "Reset"))


class AVATAR_OT_randomise(_OnCharacter, bpy.types.Operator):
    """A random body for the active character (the same seed gives the same body)"""

    bl_idname = "avatar.randomise"
    bl_label = "Randomise"

    seed: IntProperty(name="Seed", min=0, default=0)
    realistic: BoolProperty(name="Realistic", default=True)
    use_panel: BoolProperty(default=True, options={"SKIP_SAVE", "HIDDEN"})

    def execute(self, context):
        settings = context.scene.avatar
        seed = settings.seed if self.use_panel else self.seed
        realistic = settings.realistic if self.use_panel else self.realistic

        def randomise():
            from avatar.body.model import BodyModel
            from avatar.body.sampling import random_params

            params = random_params(BodyModel.shared(), seed, realistic)
            if self.use_panel:
                settings.seed = seed + 1  # the next click, the next body
            return _set_body(context, params, f"Seed {seed}:")

        return _call(self, randomise)


class AVATAR_OT_apply_preset(_OnCharacter, bpy.types.Operator):
    """Give the active character a preset body (built-in or saved)"""

    bl_idname = "avatar.apply_preset"
    bl_label = "Apply Preset"

    name: StringProperty(name="Preset", default="")

    def execute(self, context):
        from avatar.errors import AvatarError

        name = self.name or context.scene.avatar.preset

        def apply():
            try:
                params = presets.load(name)
            except KeyError:
                known = ", ".join(presets.names())
                raise AvatarError(f"no preset {name!r}; there are {known}") from None
            except ValueError as exc:
                raise AvatarError(str(exc)) from None
            return _set_body(context, params, f"Preset {name}:")

        return _call(self, apply)


class AVATAR_OT_save_preset(_OnCharacter, bpy.types.Operator):
    """Save the active character's body as a preset"""

    bl_idname = "avatar.save_preset"
    bl_label = "Save Preset"

    name: StringProperty(name="Name", default="my_body")

    def invoke(self, context, event):
        return context.window_manager.invoke_props_dialog(self)

    def execute(self, context):
        from avatar.errors import AvatarError

        root = _active_root(context)

        def save():
            params = _character().recipe_of(root).get("params") or {}
            try:
                path = presets.save(self.name, params)
            except (OSError, ValueError) as exc:
                raise AvatarError(str(exc)) from None
            return f"Saved preset {os.path.basename(path)[:-5]}"

        return _call(self, save)


class AVATAR_OT_fit_measurements(_OnCharacter, bpy.types.Operator):
    """Shape the active character to the measurement targets (cm; 0 keeps one as it is)"""

    bl_idname = "avatar.fit_measurements"
    bl_label = "Fit Measurements"

    def execute(self, context):
        from avatar.errors import AvatarError

        targets = context.scene.avatar.measurements()
        root = _active_root(context)

        def fit():
            from avatar.body import measures
            from avatar.body.model import BodyModel

            if not targets:
                raise AvatarError("set a height, chest, waist or hips target (cm) first")
            params = _character().recipe_of(root).get("params") or {}
            solved, got = measures.fit(BodyModel.shared(), targets, params)
            _set_body(context, solved, "Fitted")
            return "Fitted: " + ", ".join(f"{k} {v * 100:.1f} cm" for k, v in got.items())

        return _call(self, fit)


class AVATAR_OT_import_mhm(bpy.types.Operator):
    """Create a character from a MakeHuman .mhm file (modifiers, skeleton, clothes)"""

    bl_idname = "avatar.import_mhm"
    bl_label = "Import .mhm"
    bl_options = {"REGISTER", "UNDO"}

    filepath: StringProperty(subtype="FILE_PATH")
    filter_glob: StringProperty(default="*.mhm", options={"HIDDEN"})

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        from avatar.errors import AvatarError

        path = bpy.path.abspath(self.filepath)

        def load():
            from avatar.human import Recipe

            if not os.path.isfile(path):
                raise AvatarError(f"{path}: no such file")
            recipe = Recipe.from_mhm(path)
            name = os.path.splitext(os.path.basename(path))[0]
            location = tuple(context.scene.cursor.location)
            built = _character().create(recipe.to_dict(), name, location, exact=False)
            _select(context, built)
            live.sync_from_recipe(built.root)
            live.schedule_settle(built.root)
            return f"Loaded {name}"

        return _call(self, load)


class AVATAR_OT_export_mhm(_OnCharacter, bpy.types.Operator):
    """Save the active character as a MakeHuman .mhm file"""

    bl_idname = "avatar.export_mhm"
    bl_label = "Export .mhm"

    filepath: StringProperty(subtype="FILE_PATH")
    filter_glob: StringProperty(default="*.mhm", options={"HIDDEN"})

    def invoke(self, context, event):
        self.filepath = bpy.path.ensure_ext(_active_root(context).name, ".mhm")
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        root = _active_root(context)
        path = bpy.path.ensure_ext(bpy.path.abspath(self.filepath), ".mhm")

        def save():
            from avatar import export

            export.save(_character().realise(_character().recipe_of(root)), path)
            return f"Saved {path}"

        return _call(self, save)


class AVATAR_OT_toggle_group(bpy.types.Operator):
    """Show or hide a group of local modifiers"""

    bl_idname = "avatar.toggle_group"
    bl_label = "Toggle Group"

    group: StringProperty()

    def execute(self, context):
        settings = context.scene.avatar
        open_groups = [g for g in settings.expanded.split(",") if g]
        if self.group in open_groups:
            open_groups.remove(self.group)
        else:
            open_groups.append(self.group)
        settings.expanded = ",".join(open_groups)
        return {"FINISHED"}


class AVATAR_OT_refresh_library(bpy.types.Operator):
    """Reload the clothes library (built-ins and your clothes folders)"""

    bl_idname = "avatar.refresh_library"
    bl_label = "Refresh"

    def execute(self, context):
        return _call(self, lambda: f"{refresh_garments(context.scene.avatar)} garments")


class AVATAR_OT_set_skin(_OnCharacter, bpy.types.Operator):
    """Give the character this MakeHuman skin, or Avatar's own (by ethnicity, age and gender)"""

    bl_idname = "avatar.set_skin"
    bl_label = "Set Skin"

    path: StringProperty(name="Skin", description="A skin .mhmat; empty: Avatar's own skin")

    def execute(self, context):
        from avatar.blender import character

        root = _active_root(context)

        def set_skin():
            character.set_looks(root, skin_material=self.path or None)
            return f"Skin: {os.path.basename(self.path) if self.path else 'Avatar'}"

        return _call(self, set_skin)


def refresh_garments(settings):
    """Fill the Dress panel's list from the library (and the Body panel's skins); returns
    how many garments it holds."""
    catalogue.skins.cache_clear()
    items = settings.garments
    items.clear()
    for name, category, entry, thumbnail in catalogue.garments():
        item = items.add()
        item.name, item.category, item.entry, item.thumbnail = name, category, entry, thumbnail
    return len(items)


def _worn(root):
    import json

    return list(json.loads(root["avatar_recipe"]).get("clothes") or [])


def _dress(operator, context, entry, wear):
    """Wear (or take off) ``entry`` on the active character."""
    root = _active_root(context)

    def dress():
        from avatar.clothes.library import find_garment

        source = find_garment(entry)  # unknown names: ParameterError with close matches
        recipe = _character().recipe_of(root)
        clothes = [c for c in recipe.get("clothes") or [] if c not in (entry, source)]
        recipe["clothes"] = clothes + [source] if wear else clothes
        built = _character().update(root, recipe)
        _select(context, built)
        live.sync_from_recipe(built.root)
        verb = "Wearing" if wear else "Took off"
        return f"{verb} {os.path.basename(entry)} on {built.root.name}"

    return _call(operator, dress)


class _DressOperator(_OnCharacter):
    name: StringProperty(
        name="Garment", default="", description="Library name or .mhclo path (default: the list's)"
    )

    def _entry(self, context):
        if self.name:
            return self.name
        settings = context.scene.avatar
        if 0 <= settings.garment_index < len(settings.garments):
            return settings.garments[settings.garment_index].entry
        return ""

    def execute(self, context):
        entry = self._entry(context)
        if not entry:
            self.report({"ERROR"}, "choose a garment first")
            return {"CANCELLED"}
        return _dress(self, context, entry, self.wear)


class AVATAR_OT_wear(_DressOperator, bpy.types.Operator):
    """Put a garment from the library on the active character"""

    bl_idname = "avatar.wear"
    bl_label = "Wear"
    wear = True


class AVATAR_OT_take_off(_DressOperator, bpy.types.Operator):
    """Take a garment off the active character"""

    bl_idname = "avatar.take_off"
    bl_label = "Remove"
    wear = False


class AVATAR_OT_toggle_garment(_DressOperator, bpy.types.Operator):
    """Wear this garment, or take it off when it is worn"""

    bl_idname = "avatar.toggle_garment"
    bl_label = "Wear / Remove"
    wear = True

    def execute(self, context):
        entry = self._entry(context)
        root = _active_root(context)
        return _dress(self, context, entry, entry not in _worn(root))


class AVATAR_OT_bind_garment(bpy.types.Operator):
    """Save the selected mesh, modelled on an Avatar character, as a garment that fits every body"""

    bl_idname = "avatar.bind_garment"
    bl_label = "Bind Selected as Garment"

    name: StringProperty(name="Name", description="The garment's name and file name")
    folder: StringProperty(
        name="Folder", subtype="DIR_PATH",
        description="Where to save it (default: your clothes folder, which the list scans)",
    )  # fmt: skip
    tags: StringProperty(name="Tags", description="Comma-separated, e.g. top, casual")

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
        body = next((o for o in context.selected_objects if o is not garment and root_of(o)), None)
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
    free = [o for o in meshes if root_of(o) is None]
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
    refresh_garments(settings)
    entries = [os.path.normpath(g.entry) for g in settings.garments]
    if os.path.normpath(str(path)) in entries:
        settings.garment_index = entries.index(os.path.normpath(str(path)))


def _select(context, built):
    """Make the character the selection, its root active (as Blender's Add menu does)."""
    for obj in context.view_layer.objects:
        if obj is not None:
            obj.select_set(False)
    for obj in (built.root, *built.parts):
        obj.select_set(True)
    context.view_layer.objects.active = built.root


CLASSES = (
    AVATAR_OT_create_human,
    AVATAR_OT_settle,
    AVATAR_OT_reset_body,
    AVATAR_OT_randomise,
    AVATAR_OT_apply_preset,
    AVATAR_OT_save_preset,
    AVATAR_OT_fit_measurements,
    AVATAR_OT_import_mhm,
    AVATAR_OT_export_mhm,
    AVATAR_OT_toggle_group,
    AVATAR_OT_refresh_library,
    AVATAR_OT_set_skin,
    AVATAR_OT_wear,
    AVATAR_OT_take_off,
    AVATAR_OT_toggle_garment,
    AVATAR_OT_bind_garment,
)  # Motion operators: panel_motion.py

"""Dress > Variants & Outfits: a worn garment's colour and fabric, and named outfits.

Colour and fabric change only the garment's material (``avatar.blender.garment_looks``;
the recipe keeps them as ``garment_options``). Outfits are sets of garments with their
variants (``avatar.clothes.wardrobe``): a few built in, the user's saved as JSON files in
Blender's user config folder (``avatar/outfits/<name>.json``, beside the body presets).

For scripts: ``bpy.ops.avatar.set_garment_colour(name="tshirt", colour="navy")`` (a
swatch name, ``"#rrggbb"`` or ``"default"``; ``fabric="linen"`` too),
``bpy.ops.avatar.save_outfit(name="mine")``, ``bpy.ops.avatar.apply_outfit(name="casual")``,
``bpy.ops.avatar.delete_outfit(name="mine")``.
"""

from __future__ import annotations

import json
import os

import bpy
from bpy.props import EnumProperty, FloatVectorProperty, StringProperty

from . import live
from .operators import _call, _select, root_of

_ENUM_CACHE: dict[str, list] = {}  # Blender needs dynamic enum items kept alive


def folder() -> str:
    """The user's outfit folder (created when the first outfit is saved)."""
    return bpy.utils.user_resource("CONFIG", path=os.path.join("avatar", "outfits"))


def _wardrobe():
    from avatar.clothes import wardrobe

    return wardrobe


def outfit_names() -> list[str]:
    """Built-in outfits, then the user's saved ones."""
    try:
        builtin = list(_wardrobe().BUILTIN)
    except ImportError:
        return []
    user = []
    if os.path.isdir(folder()):
        user = sorted(f[:-5] for f in os.listdir(folder()) if f.endswith(".json"))
    return builtin + [n for n in user if n not in builtin]


def _worn(root) -> list[str]:
    return list(json.loads(root["avatar_recipe"]).get("clothes") or []) if root else []


def _variant_garments(root) -> list[str]:
    """Worn garments that have colour variants (the built-ins but shoes)."""
    try:
        from avatar.clothes import variants
    except ImportError:
        return []
    return [e for e in _worn(root) if variants.colours(e)]


def _garment_items(self, context):
    names = _variant_garments(root_of(context.object))
    _ENUM_CACHE["garments"] = [(n, n, f"Colour and fabric of {n}") for n in names] or [
        ("NONE", "No garment with variants worn", "")
    ]
    return _ENUM_CACHE["garments"]


def _outfit_items(self, context):
    _ENUM_CACHE["outfits"] = [(n, n, f"Outfit {n}") for n in outfit_names()] or [
        ("NONE", "No outfits", "")
    ]
    return _ENUM_CACHE["outfits"]


class AvatarOutfitSettings(bpy.types.PropertyGroup):
    garment: EnumProperty(name="Garment", items=_garment_items,
                          description="The worn garment to recolour")  # fmt: skip
    custom_colour: FloatVectorProperty(name="Custom Colour", subtype="COLOR_GAMMA", size=3,
                                       min=0.0, max=1.0, default=(0.2, 0.35, 0.6))  # fmt: skip
    outfit: EnumProperty(name="Outfit", items=_outfit_items)
    new_name: StringProperty(name="Name", default="my_outfit",
                             description="Name to save the worn set under")  # fmt: skip


def hex_colour(rgb) -> str:
    """'#rrggbb' of an sRGB colour (three floats in [0, 1])."""
    return "#" + "".join(f"{round(min(max(c, 0.0), 1.0) * 255):02x}" for c in rgb[:3])


class _OnCharacter:
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return root_of(context.object) is not None


class AVATAR_OT_set_garment_colour(_OnCharacter, bpy.types.Operator):
    """Give a worn garment another colour (and/or fabric): only its material changes"""

    bl_idname = "avatar.set_garment_colour"
    bl_label = "Set Garment Colour"

    name: StringProperty(name="Garment", description="Worn garment (default: the panel's)")
    colour: StringProperty(name="Colour",
                           description="Swatch name, #rrggbb, or 'default' (its own)")  # fmt: skip
    fabric: StringProperty(name="Fabric", description="Fabric name, or 'default' (its own)")

    def execute(self, context):
        from avatar.errors import AvatarError

        root = root_of(context.object)
        name = self.name or context.scene.avatar_outfits.garment

        def recolour():
            from avatar.blender import garment_looks

            if not name or name == "NONE":
                raise AvatarError("wear a garment with colour variants first")
            if not self.colour and not self.fabric:
                raise AvatarError("choose a colour or a fabric")
            asked = (("colour", self.colour), ("fabric", self.fabric))
            change = {k: (None if v == "default" else v) for k, v in asked if v}
            got = garment_looks.set_options(root, name, change)
            look = ", ".join(got.values()) or "its own colours"
            return f"{name} on {root.name}: {look}"

        return _call(self, recolour)


class AVATAR_OT_save_outfit(_OnCharacter, bpy.types.Operator):
    """Save what the active character wears (with colours and fabrics) as a named outfit"""

    bl_idname = "avatar.save_outfit"
    bl_label = "Save Outfit"
    bl_options = {"REGISTER"}

    name: StringProperty(name="Name", default="")

    def execute(self, context):
        from avatar.errors import AvatarError

        root = root_of(context.object)
        name = self.name or context.scene.avatar_outfits.new_name

        def save():
            from avatar.human import Recipe

            wardrobe = _wardrobe()
            clean = wardrobe.clean_name(name)
            if not clean or clean in wardrobe.BUILTIN:
                raise AvatarError(f"choose another outfit name than {name!r}")
            recipe = Recipe.from_dict(json.loads(root["avatar_recipe"]))
            outfit = wardrobe.Outfit(recipe.clothes, recipe.worn_options())
            try:
                path = wardrobe.save(os.path.join(folder(), f"{clean}.json"), outfit)
            except OSError as exc:
                raise AvatarError(f"cannot save outfit {clean}: {exc.strerror}") from None
            context.scene.avatar_outfits.outfit = clean
            return f"Saved outfit {clean} ({len(outfit.clothes)} items) to {path}"

        return _call(self, save)


def load_outfit(name: str):
    """A checked outfit by name (built-in or saved); AvatarError when unknown or bad."""
    from avatar.errors import AvatarError

    wardrobe = _wardrobe()
    if name in wardrobe.BUILTIN:
        return wardrobe.check(wardrobe.BUILTIN[name], where=f"outfit {name}")
    path = os.path.join(folder(), f"{wardrobe.clean_name(name)}.json")
    if not name or not os.path.isfile(path):
        known = ", ".join(outfit_names())
        raise AvatarError(f"no outfit {name!r}; there are {known}")
    return wardrobe.load(path)


class AVATAR_OT_apply_outfit(_OnCharacter, bpy.types.Operator):
    """Dress the active character in an outfit: exactly its garments and colours (its own
    hair, brows and lashes stay unless the outfit has some)"""

    bl_idname = "avatar.apply_outfit"
    bl_label = "Apply Outfit"

    name: StringProperty(name="Outfit", default="")

    def execute(self, context):
        root = root_of(context.object)
        name = self.name or context.scene.avatar_outfits.outfit

        def apply():
            from avatar.blender import character

            outfit = load_outfit(name)  # every item checked before the character changes
            recipe = character.recipe_of(root)
            clothes, options = _wardrobe().wear(recipe.get("clothes") or [],
                                                recipe.get("garment_options") or {}, outfit,
                                                recipe.get("folders") or ())  # fmt: skip
            recipe["clothes"], recipe["garment_options"] = clothes, options
            built = character.update(root, recipe)
            _select(context, built)
            live.sync_from_recipe(built.root)
            return f"{built.root.name} wears {name} ({len(clothes)} items)"

        return _call(self, apply)


class AVATAR_OT_delete_outfit(bpy.types.Operator):
    """Delete a saved outfit (built-in outfits stay)"""

    bl_idname = "avatar.delete_outfit"
    bl_label = "Delete Outfit"
    bl_options = {"REGISTER"}

    name: StringProperty(name="Outfit", default="")

    def execute(self, context):
        from avatar.errors import AvatarError

        name = self.name or context.scene.avatar_outfits.outfit

        def delete():
            wardrobe = _wardrobe()
            if name in wardrobe.BUILTIN:
                raise AvatarError(f"{name} is a built-in outfit: it cannot be deleted")
            path = os.path.join(folder(), f"{wardrobe.clean_name(name)}.json")
            if not name or not os.path.isfile(path):
                raise AvatarError(f"no saved outfit {name!r}")
            try:
                os.remove(path)
            except OSError as exc:
                raise AvatarError(f"cannot delete outfit {name}: {exc.strerror}") from None
            return f"Deleted outfit {name}"

        return _call(self, delete)


class AVATAR_PT_outfits(bpy.types.Panel):
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Avatar"
    bl_label = "Variants & Outfits"
    bl_idname = "AVATAR_PT_outfits"
    bl_parent_id = "AVATAR_PT_dress"
    bl_order = 0

    def draw(self, context):
        layout = self.layout
        settings = context.scene.avatar_outfits
        root = root_of(context.object)
        if root is None:
            layout.label(text="Select a character to dress it", icon="INFO")
            return
        try:
            from avatar.clothes import variants
        except ImportError:
            layout.label(text="The avatar library is not installed", icon="ERROR")
            return
        box = layout.box()
        box.prop(settings, "garment", text="")
        name = settings.garment
        if name and name != "NONE":
            grid = box.grid_flow(columns=2, even_columns=True, align=True)
            for colour in variants.colours(name):
                op = grid.operator("avatar.set_garment_colour", text=colour.replace(" hair", ""))
                op.name, op.colour, op.fabric = name, colour, ""
            row = box.row(align=True)
            row.prop(settings, "custom_colour", text="")
            op = row.operator("avatar.set_garment_colour", text="Custom", icon="COLOR")
            op.name, op.colour, op.fabric = name, hex_colour(settings.custom_colour), ""
            fabrics = variants.fabric_choices(name)
            if len(fabrics) > 1:
                row = box.row(align=True)
                for fabric in fabrics:
                    op = row.operator("avatar.set_garment_colour", text=fabric.title())
                    op.name, op.colour, op.fabric = name, "", fabric
            op = box.operator("avatar.set_garment_colour", text="Its Own Look", icon="LOOP_BACK")
            op.name, op.colour, op.fabric = name, "default", "default"
        box = layout.box()
        row = box.row(align=True)
        row.prop(settings, "outfit", text="")
        row.operator("avatar.apply_outfit", text="", icon="CHECKMARK").name = ""
        row.operator("avatar.delete_outfit", text="", icon="TRASH").name = ""
        row = box.row(align=True)
        row.prop(settings, "new_name", text="")
        row.operator("avatar.save_outfit", text="", icon="ADD").name = ""


CLASSES = (
    AvatarOutfitSettings,
    AVATAR_OT_set_garment_colour,
    AVATAR_OT_save_outfit,
    AVATAR_OT_apply_outfit,
    AVATAR_OT_delete_outfit,
    AVATAR_PT_outfits,
)
POINTERS = {(bpy.types.Scene, "avatar_outfits"): AvatarOutfitSettings}


def release() -> None:
    _ENUM_CACHE.clear()

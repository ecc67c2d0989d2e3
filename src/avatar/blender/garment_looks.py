"""Fabric and colour variants of worn garments in the scene: a material swap, no geometry.

A character's recipe (``avatar_recipe`` on its root) keeps each worn built-in's variant in
``garment_options`` ({entry: {"colour": ..., "fabric": ...}}, ``avatar.clothes.variants``).
``set_options`` checks a variant, writes it into the recipe and swaps the garment object's
material; ``apply`` gives every worn garment the material its recipe entry asks for (after
a character is built or restyled). Materials come from ``materials.material``, which
reuses one made from an equal record, so a (garment, variant) material exists once however
many characters wear it; the one a garment leaves goes with its images when nothing else
uses it, so switching colours back and forth grows nothing.
"""

from __future__ import annotations

import json
from collections.abc import Mapping

import bpy

from avatar.blender import live
from avatar.blender import materials as material_bridge
from avatar.body.model import BodyModel
from avatar.clothes import library, variants
from avatar.errors import AvatarError
from avatar.human import Human, Recipe


def options_of(root: bpy.types.Object) -> dict[str, dict[str, str]]:
    """{worn entry: its variant options} of the character ``root`` heads."""
    return live.recipe_of(root).worn_options()


def apply(root: bpy.types.Object) -> int:
    """Give each worn built-in garment of ``root``'s character the material of its variant
    (or its own when it has none), brows, facial hair and hair aged for the wearer
    (``live.worn_looks``); returns how many materials were swapped. A user's .mhclo keeps
    the material it was made with (and is not read again here)."""
    recipe = live.recipe_of(root)
    parts = live.part_objects(root)
    swapped = 0
    for name, look in live.worn_looks(recipe, BodyModel.shared()).items():
        obj = parts.get(name)
        if obj is None or obj.type != "MESH":
            continue
        swapped += _swap(obj, material_bridge.material(look, name))
    return swapped


def set_options(root: bpy.types.Object, entry: str, options: Mapping[str, str | None]) -> dict:
    """Change the variant of the worn garment ``entry`` on ``root``'s character: ``options``
    ({"colour": ..., "fabric": ...}; a None value goes back to the garment's own) merged
    into its current ones. Only its material changes. Returns the garment's new options.

    Raises AvatarError (a garment not worn, or without variants; an unknown colour or
    fabric) before anything changes."""
    data = json.loads(root[live.RECIPE_KEY])
    recipe = Recipe.from_dict(data)
    if entry not in recipe.clothes:
        worn = ", ".join(recipe.clothes) or "nothing"
        raise AvatarError(f"{root.name} does not wear {entry!r} (it wears {worn})")
    merged = dict(recipe.garment_options.get(entry, {}))
    for key, value in options.items():
        if value is None or value == "":
            merged.pop(key, None)
        else:
            merged[key] = value
    source = library.find_garment(entry, recipe.folders)
    checked = variants.check(source, merged)  # ParameterError: nothing changed yet
    new_options = {**recipe.garment_options, entry: checked}
    new = Recipe.from_dict({**recipe.to_dict(), "garment_options": new_options})
    Human.from_recipe(new)  # the whole recipe still realises
    garment = library.load_garment(source, recipe.folders, options=checked)
    if garment.name not in live.part_objects(root):
        raise AvatarError(f"{root.name} has no {garment.name!r} object to recolour")
    root[live.RECIPE_KEY] = json.dumps(new.to_dict())
    apply(root)  # it, aged for the wearer, and the brows and beard that follow a hair colour
    return checked


def _swap(obj: bpy.types.Object, new: bpy.types.Material) -> int:
    """Put ``new`` in ``obj``'s first material slot; the old one goes if nothing uses it."""
    slots = obj.data.materials
    old = slots[0] if len(slots) else None
    if old == new:
        return 0
    if len(slots):
        slots[0] = new
    else:
        slots.append(new)
    material_bridge.release([old])
    return 1

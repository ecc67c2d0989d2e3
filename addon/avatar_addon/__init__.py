"""Avatar: create rigged, dressed, animated MakeHuman humans from Blender's sidebar.

An extension for Blender 4.2+ (blender_manifest.toml) that also loads as a legacy add-on
(bl_info) in older Blenders, e.g. 3.4 for the UI smoke test. The ``avatar`` library is
imported lazily by the operators, so the panels register even when it is missing and say
how to install it.

For scripts: ``bpy.ops.avatar.create_human()`` adds a human (hair, brows, lashes) and makes
it active; ``obj.avatar.weight = 0.8`` (any body parameter, on the character's root object)
changes it live; ``bpy.ops.avatar.wear(name="tshirt")`` dresses the active character.
"""

from __future__ import annotations

import importlib
import os
import pkgutil
import sys

bl_info = {  # legacy add-ons only; Blender 4.2+ reads blender_manifest.toml
    "name": "Avatar",
    "author": "Avatar developers",
    "version": (0, 0, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > Avatar",
    "description": "Rigged, dressed, animated humans from the MakeHuman body model",
    "category": "Add Mesh",
}


def _add_library_path() -> None:
    """Legacy installs: ``AVATAR_PYTHONPATH`` (os.pathsep-separated) points at the library."""
    for entry in reversed(os.environ.get("AVATAR_PYTHONPATH", "").split(os.pathsep)):
        if entry and entry not in sys.path:
            sys.path.insert(0, entry)


_add_library_path()

import bpy  # noqa: E402

from . import operators, panels, properties, thumbnails  # noqa: E402

# Feature modules, ``panel_<name>.py`` (one sidebar panel with its operators and settings
# each, so features grow without touching the core files): each has CLASSES (registered in
# order, after the core's) and may have POINTERS, {(bpy type, attribute): PropertyGroup},
# attached after its classes register, and release() run first on unregister. Panels place
# themselves in the sidebar with bl_order.
FEATURES: tuple = tuple(
    importlib.import_module(f"{__name__}.{module.name}")
    for module in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name)
    if module.name.startswith("panel_")
)

CLASSES = (
    properties.AvatarModifier,
    properties.AvatarCharacter,
    properties.AvatarGarment,
    properties.AvatarSettings,
    properties.AvatarPreferences,
    *operators.CLASSES,
    *panels.CLASSES,
    *(cls for feature in FEATURES for cls in feature.CLASSES),
)


def _pointers() -> dict:
    pointers = {
        (bpy.types.Scene, "avatar"): properties.AvatarSettings,
        (bpy.types.Object, "avatar"): properties.AvatarCharacter,
    }
    for feature in FEATURES:
        pointers.update(getattr(feature, "POINTERS", {}))
    return pointers


def register() -> None:
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    for (owner, name), group in _pointers().items():
        setattr(owner, name, bpy.props.PointerProperty(type=group))


def unregister() -> None:
    thumbnails.release()
    for feature in FEATURES:
        getattr(feature, "release", lambda: None)()  # timers, sockets, preview collections
    for owner, name in _pointers():
        delattr(owner, name)
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)

"""Characters in a Blender scene that remember their recipe and regenerate from it.

The Blender extension's operators call these functions, one per button. A character's root
object (its armature) stores the recipe as JSON in the ``avatar_recipe`` custom property;
changing a slider, wearing a garment or applying a motion edits that recipe and rebuilds the
character from it, in place (same name, location and collection).

A recipe is what ``avatar.human.Human.to_recipe()`` returns and ``Human.from_recipe()``
accepts: a JSON-able dict (body parameters, rig, clothes, motion).

This module is the extension's composition root, as ``avatar.cli`` is the command's: it
realises recipes into ``Human``s and hands the bridge (``scene``) their records, so it sits
above ``avatar.export`` in the layers (see docs/architecture.md).
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path

import bpy
from mathutils import Vector

from avatar import export
from avatar import motion as library
from avatar.blender import mesh as mesh_bridge
from avatar.blender import scene as stage
from avatar.clothes import binder
from avatar.errors import AvatarError
from avatar.human import Human
from avatar.rig.skeleton import Animation

RECIPE_KEY = "avatar_recipe"
MOTION_KEY = "avatar_motion"  # the Motion panel's spec: {"path", "frames", "fps", "in_place"}


def create(
    recipe: Mapping[str, object], name: str = "Avatar", location=(0.0, 0.0, 0.0)
) -> stage.CharacterObjects:
    """Realise ``recipe`` with the library and add the character to the scene.

    Raises AvatarError (bad parameters, missing assets, ...) before touching the scene.
    """
    human = realise(recipe)
    return stage.build_character(export.character(human, name=name, location=tuple(location)))


def realise(recipe: Mapping[str, object]) -> Human:
    """The ``Human`` a recipe describes."""
    return Human.from_recipe(dict(recipe))


def update(obj: bpy.types.Object, recipe: Mapping[str, object]) -> stage.CharacterObjects:
    """Rebuild the character ``obj`` belongs to from a new recipe, in place.

    The new human is realised first, so a failing recipe leaves the old character intact.
    """
    root = root_of(obj)
    if root is None:
        raise AvatarError(f"{obj.name!r} is not part of an Avatar character")
    motion = json.loads(root[MOTION_KEY]) if MOTION_KEY in root.keys() else None
    return _rebuild(root, recipe, motion)[0]


def apply_motion(
    obj: bpy.types.Object, motion: Mapping[str, object]
) -> tuple[stage.CharacterObjects, str]:
    """Retarget a BVH clip onto the character ``obj`` belongs to and rebuild it playing it.

    motion: {"path": BVH file, "frames": [start, stop] (see ``load_motion``) or None,
    "fps": resample rate or None, "in_place": bool}. Stored on the character, so later
    updates re-apply it. The character is rebuilt, not just given an action, because its
    garments get one corrective shape key per frame (``avatar.export.character``).
    Returns the new objects and a one-line summary.
    """
    root = root_of(obj)
    if root is None or root.type != "ARMATURE":
        raise AvatarError("select a rigged Avatar character first")
    built, animation = _rebuild(root, recipe_of(root), dict(motion))
    return built, f"{built.root.name}: {animation.frames} frames at {animation.fps:g} fps"


def _rebuild(root: bpy.types.Object, recipe, motion):
    """(objects, Animation or None): the character ``root`` heads replaced by one realised
    from ``recipe`` playing ``motion`` (a Motion-panel spec or None). Everything that can
    fail (realise, retarget, garment bake) runs before the old character is removed."""
    human = realise(recipe)
    animation = load_motion(motion, human) if motion else None
    name, location = root.name, tuple(root.location)
    collection = root.users_collection[0] if root.users_collection else None
    character = export.character(human, animation, name=name, location=location)
    remove(root, drop_collection=False)
    built = stage.build_character(character, collection)
    if motion:
        built.root[MOTION_KEY] = json.dumps(dict(motion))
    return built, animation


def load_motion(motion: Mapping[str, object], human: Human) -> Animation:
    """The Animation of a Motion-panel spec, retargeted onto ``human`` and settled on its
    skin: planted feet on the floor.

    motion["frames"]: [start, stop] source frames as the CLI's ``--frames A:B`` (0-based,
    stop exclusive, None = to the end), or None for the whole clip.
    """
    frames = motion.get("frames")
    source_skeleton, clip = library.load_bvh(motion["path"])
    animation, _report = library.retarget(
        source_skeleton,
        clip,
        human.skeleton,
        body=human.body,
        frames=slice(*frames) if frames else None,
        fps=motion.get("fps"),
        in_place=bool(motion.get("in_place")),
    )
    return animation


def bind_garment(
    garment: bpy.types.Object,
    folder: str,
    name: str,
    tags: tuple[str, ...] = (),
    body: bpy.types.Object | None = None,
) -> Path:
    """Save the mesh object ``garment``, modelled on a character, as a garment that fits every
    body: ``folder/name.mhclo`` + ``.obj`` + ``.mhmat``; returns the .mhclo Path.

    body: an object of that character; None finds it (see ``authoring_root``). The garment is
    read as it shows and brought into the character's frame (Avatar's: its root is the
    origin), then bound to the body its recipe realises. Raises AvatarError (e.g. a vertex too
    far from the body) before anything is written.
    """
    root = authoring_root(garment, body)
    mesh = mesh_bridge.read_evaluated_mesh(garment, root.matrix_world.inverted())
    human = realise(recipe_of(root))
    base = human.model.base
    binding = binder.bind(mesh.vertices, human.vertices, base.faces[base.face_groups["body"]])
    return binder.save(folder, name, mesh, binding, tags=tags)


def authoring_root(
    garment: bpy.types.Object, body: bpy.types.Object | None = None
) -> bpy.types.Object:
    """The root of the character ``garment`` was modelled on: ``body``'s, else the one it is
    parented to, else the scene's character whose root is nearest to the garment's centre."""
    for obj in (body, garment):
        root = root_of(obj)
        if root is not None:
            return root
    roots = [o for o in bpy.context.scene.objects if RECIPE_KEY in o.keys()]
    if not roots:
        raise AvatarError("no Avatar character in the scene to bind the garment to")
    corners = [garment.matrix_world @ Vector(c) for c in garment.bound_box]
    centre = sum(corners, Vector()) / len(corners)
    return min(roots, key=lambda r: (r.matrix_world.translation - centre).length)


def root_of(obj: bpy.types.Object | None) -> bpy.types.Object | None:
    """The object holding the recipe: ``obj`` or its nearest ancestor that has one."""
    while obj is not None:
        if RECIPE_KEY in obj.keys():
            return obj
        obj = obj.parent
    return None


def recipe_of(obj: bpy.types.Object | None) -> dict | None:
    """The recipe stored on the character ``obj`` belongs to, or None."""
    root = root_of(obj)
    return json.loads(root[RECIPE_KEY]) if root is not None else None


def remove(root: bpy.types.Object, drop_collection: bool = True) -> None:
    """Delete a character: root, its descendants, their data, its action, and (when
    ``drop_collection``) the collection named after it once that is empty."""
    objects = [root, *root.children_recursive]
    action = root.animation_data.action if root.animation_data else None
    datas = [o.data for o in objects if o.data is not None]
    name = root.name
    for obj in objects:
        bpy.data.objects.remove(obj)
    for data in datas:
        if data.users == 0:
            _pool(data).remove(data)
    if action is not None and action.users == 0:
        bpy.data.actions.remove(action)
    collection = bpy.data.collections.get(name) if drop_collection else None
    if collection is not None and not collection.all_objects:
        bpy.data.collections.remove(collection)


def _pool(data: bpy.types.ID):
    return bpy.data.armatures if isinstance(data, bpy.types.Armature) else bpy.data.meshes

"""Characters in a Blender scene that remember their recipe: the extension's engine.

The Blender extension's operators call these functions, one per button. A character's root
object (its armature, or the body of an unrigged one) stores the recipe as JSON in the
``avatar_recipe`` custom property: the source of truth for files. A body change is written
into the existing objects (``avatar.blender.live``); wearing or taking off a garment adds or
removes that garment's object and refits the others in place; a new rig or a motion (whose
garments get one corrective shape key per frame) builds a new character and swaps it in.
Every change computes the new state before touching the scene, so a failure (an
AvatarError) leaves the character as it was.

A recipe is what ``avatar.human.Human.to_recipe()`` returns and ``Human.from_recipe()``
accepts: a JSON-able dict (body parameters, rig, clothes, motion).

This module is the extension's composition root, as ``avatar.cli`` is the command's: it
realises recipes into ``Human``s and hands the bridge (``scene``) their records, so it sits
above ``avatar.export`` in the layers (see docs/architecture.md).
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping
from dataclasses import replace
from pathlib import Path

import bpy
from mathutils import Vector

from avatar import export
from avatar import motion as library
from avatar.blender import garment_looks, live
from avatar.blender import materials as material_bridge
from avatar.blender import mesh as mesh_bridge
from avatar.blender import scene as stage
from avatar.body.shaped import PART_GROUPS
from avatar.clothes import binder
from avatar.clothes import library as clothes_library
from avatar.errors import AvatarError
from avatar.human import Human, Recipe
from avatar.motion import gait, report_card
from avatar.motion.retarget import RetargetReport
from avatar.rig.skeleton import Animation

RECIPE_KEY = live.RECIPE_KEY
MOTION_KEY = "avatar_motion"  # the Motion panel's spec: {"path", "frames", "fps", "in_place"}
REPORT_KEY = "avatar_motion_report"  # the last retarget's summary (shown in the panel)
CARD_KEY = "avatar_motion_card"  # its numbers as JSON (``avatar.motion.report_card.card``)
DEFAULT_LOOK = ("hair-short", "eyebrows", "eyelashes")  # what a new human wears


def create(
    recipe: Mapping[str, object],
    name: str = "Avatar",
    location=(0.0, 0.0, 0.0),
    rigged: bool = True,
    exact: bool = True,
) -> stage.CharacterObjects:
    """Realise ``recipe`` with the library and add the character to the scene.

    exact: fit garments exactly now (else the real-time fit; ``live.settle`` later).
    Raises AvatarError (bad parameters, missing assets, ...) before touching the scene.
    """
    built = live.create(recipe, name, tuple(location), rigged=rigged, exact=exact)
    garment_looks.apply(built.root)  # fabric/colour variants (garment_options)
    return built


def realise(recipe: Mapping[str, object]) -> Human:
    """The ``Human`` a recipe describes."""
    return Human.from_recipe(dict(recipe))


def update(obj: bpy.types.Object, recipe: Mapping[str, object]) -> stage.CharacterObjects:
    """Give the character ``obj`` belongs to a new recipe.

    Same rig, no motion: body and garments change in place (garments added or removed as
    objects). Otherwise a new character is built and swapped in. Either way the new state is
    computed first, so a failing recipe leaves the old character intact.
    """
    root = root_of(obj)
    if root is None:
        raise AvatarError(f"{obj.name!r} is not part of an Avatar character")
    new = Recipe.from_dict(dict(recipe))
    old = live.recipe_of(root)
    motion = json.loads(root[MOTION_KEY]) if MOTION_KEY in root.keys() else None
    if new.rig == old.rig and motion is None:
        return _restyle(root, new)
    return _rebuild(root, new.to_dict(), motion)[0]


def _restyle(root: bpy.types.Object, recipe: Recipe) -> stage.CharacterObjects:
    """``recipe`` (same rig) written into ``root``'s character: its body and worn garments
    in place, new garments as new objects, garments no longer worn removed."""
    human = Human.from_recipe(recipe)
    geo = live.geometry(human.recipe, human.model, exact=True)  # may raise: nothing touched
    parts = live.part_objects(root)
    worn = {g.name for g in geo.outfit or ()}
    added = []
    try:
        for fitted in geo.outfit or ():
            if fitted.name not in parts:
                added.append(live.add_part(root, clothes_library.garment_part(fitted), geo.body))
    except Exception:
        for obj in added:
            _delete_objects([obj])
        raise
    stale = [o for n, o in parts.items() if n not in PART_GROUPS and n not in worn]
    _delete_objects(stale)
    live.write(root, geo)
    live.refresh_materials(root, human)
    root[RECIPE_KEY] = json.dumps(human.to_recipe())
    root[live.SETTLED_KEY] = 1
    garment_looks.apply(root)
    return objects_of(root)


def set_looks(obj: bpy.types.Object, **looks: str | None) -> None:
    """Give the character ``obj`` belongs to another skin or eye material
    (``skin_material``: a MakeHuman skin ``.mhmat``, None for Avatar's own;
    ``eye_material``: e.g. ``eyes/materials/blue.mhmat``). Only materials change, so it
    is instant; the new ones are made first, so a broken skin file (AvatarError) leaves
    the character as it was."""
    root = root_of(obj)
    if root is None:
        raise AvatarError(f"{obj.name!r} is not part of an Avatar character")
    unknown = set(looks) - {"skin_material", "eye_material"}
    if unknown:
        raise AvatarError(f"set_looks takes skin_material and eye_material, not {unknown}")
    human = Human.from_recipe(replace(live.recipe_of(root), **looks))
    if human.recipe.skin_material:
        _check_skin(human)
    live.refresh_materials(root, human)
    root[RECIPE_KEY] = json.dumps(human.to_recipe())


def _check_skin(human: Human) -> None:
    """A skin the recipe names must load with its texture (``Human.material`` would fall
    back to Avatar's skin, silently, where the user asked for this one). Only the file and
    its texture's name are read: the texture itself is decoded once, for the material."""
    from avatar.io import mhmat

    path = human.skin_file()
    if path is None:
        raise AvatarError(f"{human.recipe.skin_material}: no such skin material file")
    if "diffuseTexture" not in mhmat.texture_paths(mhmat.read(path), path.parent, path):
        raise AvatarError(f"{path}: the skin has no diffuse texture")


def objects_of(root: bpy.types.Object) -> stage.CharacterObjects:
    parts = list(live.part_objects(root).values())
    arm = root if root.type == "ARMATURE" else None
    body_first = sorted(parts, key=lambda o: o[live.PART_KEY] != "body")
    return stage.CharacterObjects(root, arm, body_first)


def apply_motion(
    obj: bpy.types.Object, motion: Mapping[str, object]
) -> tuple[stage.CharacterObjects, str]:
    """Retarget a BVH clip onto the character ``obj`` belongs to and rebuild it playing it.

    motion: {"path": BVH file, "frames": [start, stop] (see ``load_motion``) or None,
    "fps": resample rate or None, "in_place": bool, optionally "bone_map": {canonical:
    [clip bone names]} and "match_names": bool}, or {"walk": {"speed": m/s, "steps": n},
    "fps": rate} for the built-in walk. Stored on the character, so later
    updates re-apply it. The character is rebuilt, not just given an action, because its
    garments get one corrective shape key per frame (``avatar.export.character``); the new
    one is built before the old one goes, so a failure leaves the character as it was.
    Returns the new objects and a one-line summary; the retarget report's summary is
    stored on the root (``REPORT_KEY``).
    """
    root = root_of(obj)
    if root is None or root.type != "ARMATURE":
        raise AvatarError("select a rigged Avatar character first")
    built, animation = _rebuild(root, recipe_of(root), dict(motion))
    return built, f"{built.root.name}: {animation.frames} frames at {animation.fps:g} fps"


def _rebuild(root: bpy.types.Object, recipe, motion):
    """(objects, Animation or None): a character realised from ``recipe`` playing
    ``motion`` (a Motion-panel spec or None) swapped in for the one ``root`` heads. Everything
    that can fail (realise, retarget, garment bake, building the objects) runs before the
    old character is removed."""
    human = realise(recipe)
    animation = report = None
    if motion:
        animation, report = load_motion(motion, human)
    name, location = root.name, tuple(root.location)
    collection = root.users_collection[0] if root.users_collection else None
    rigged = root.type == "ARMATURE"

    def build() -> stage.CharacterObjects:
        if animation is None:
            built = live.create(human.recipe, name, location, rigged, collection, exact=True)
            garment_looks.apply(built.root)
            return built
        character = export.character(human, animation, name=name, location=location)
        built = stage.build_character(character, collection)
        built.root[live.RIGGED_KEY] = 1
        built.root[live.SETTLED_KEY] = 1
        return built

    built = _swap(root, build)
    if motion:
        built.root[MOTION_KEY] = json.dumps(dict(motion))
        built.root[REPORT_KEY] = report.summary() if report is not None else ""
        built.root[CARD_KEY] = json.dumps(report_card.card(report)) if report is not None else ""
    return built, animation


def _swap(root: bpy.types.Object, build: Callable[[], stage.CharacterObjects]):
    """The character ``build()`` makes, in place of ``root``'s: same names, selection kept.
    ``build`` runs first; if it raises, the old character is untouched."""
    names = {o[live.PART_KEY]: o.name for o in live.part_objects(root).values()}
    root_name = root.name
    built = build()
    remove(root, drop_collection=False)
    built.root.name = root_name
    for obj in built.parts:
        part = obj.get(live.PART_KEY)
        if part in names and obj is not built.root:
            obj.name = names[part]
    return built


def load_motion(
    motion: Mapping[str, object], human: Human
) -> tuple[Animation, RetargetReport | None]:
    """The Animation of a Motion-panel spec, retargeted onto ``human`` and settled on its
    skin (planted feet on the floor), and the retarget's quality report (None for the
    built-in walk). Raises AvatarError for a missing, unreadable or empty clip, or a bad
    bone map.

    motion["frames"]: [start, stop] source frames as the CLI's ``--frames A:B`` (0-based,
    stop exclusive, None = to the end), or None for the whole clip.
    motion["bone_map"]: {canonical: [clip bone names]} (a mapping edited in the Motion
    panel) or None for the automatic one; motion["match_names"]: also drive same-named
    bones (default True).
    """
    walk = motion.get("walk")
    if isinstance(walk, Mapping):
        animation = gait.walk(human.skeleton, float(walk.get("speed", 1.3)),
                              int(walk.get("steps", 8)), float(motion.get("fps") or 30.0),
                              body=human.body)  # fmt: skip
        return animation, None
    frames = motion.get("frames")
    path = Path(str(motion.get("path") or ""))
    if not str(motion.get("path") or "").strip():
        raise AvatarError("choose a BVH file first")
    if not path.is_file():
        raise AvatarError(f"{path}: no such BVH file")
    source_skeleton, clip = library.load_bvh(path)
    if clip.frames == 0:
        raise AvatarError(f"{path.name}: the clip has no frames")
    animation, report = library.retarget(
        source_skeleton,
        clip,
        human.skeleton,
        body=human.body,
        frames=slice(*frames) if frames else None,
        fps=motion.get("fps"),
        in_place=bool(motion.get("in_place")),
        source_map=motion.get("bone_map") or "auto",
        match_names=bool(motion.get("match_names", True)),
    )
    if animation.frames == 0:
        raise AvatarError(f"{path.name}: no frames in {frames[0]}:{frames[1]}")
    return animation, report


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


root_of = live.root_of  # the object holding the recipe: obj or its nearest such ancestor


def recipe_of(obj: bpy.types.Object | None) -> dict | None:
    """The recipe stored on the character ``obj`` belongs to, or None."""
    root = root_of(obj)
    return json.loads(root[RECIPE_KEY]) if root is not None else None


def remove(root: bpy.types.Object, drop_collection: bool = True) -> None:
    """Delete a character: root, its descendants, their data, actions and materials that
    nothing else uses, and (when ``drop_collection``) the collection named after it once
    that is empty."""
    name = root.name
    _delete_objects([root, *root.children_recursive])
    collection = bpy.data.collections.get(name) if drop_collection else None
    if collection is not None and not collection.all_objects:
        bpy.data.collections.remove(collection)


def _delete_objects(objects: list[bpy.types.Object]) -> None:
    """Remove objects and whatever of theirs is left unused: mesh/armature data, shape
    keys' and objects' actions, Avatar's materials and their images."""
    actions, datas, mats = [], [], []
    for obj in objects:
        for owner in (obj, getattr(obj.data, "shape_keys", None)):
            if owner is not None and owner.animation_data and owner.animation_data.action:
                actions.append(owner.animation_data.action)
        if obj.data is not None:
            datas.append(obj.data)
            mats += list(getattr(obj.data, "materials", []))
    for obj in objects:
        bpy.data.objects.remove(obj)
    for data in datas:
        if data.users == 0:
            _pool(data).remove(data)
    for action in actions:
        if action.users == 0:
            bpy.data.actions.remove(action)
    material_bridge.release(mats)
    # The view layer resyncs its object list lazily; iterating it before that (selecting
    # the new character) would meet the removed objects' empty bases.
    bpy.context.view_layer.update()


def _pool(data: bpy.types.ID):
    return bpy.data.armatures if isinstance(data, bpy.types.Armature) else bpy.data.meshes

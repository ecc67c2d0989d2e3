"""Characters that change in place: a recipe's geometry written into the objects it has.

A character made here is a root object (its armature, or its body for an unrigged one)
holding the recipe as JSON (``RECIPE_KEY``), and mesh parts tagged with ``PART_KEY``
("body", "eyes", a garment's name). A parameter change (``set_params``) computes the new
body, skeleton and fitted garments with the library (``avatar.body.shaped``,
``avatar.clothes.library.dress``) and writes them into those objects: vertices with
``foreach_set`` (shape keys keep their offsets), the armature's rest bones in one trip
through edit mode. No object, mesh, material or image is created. Materials come from
``avatar.blender.materials.material``, which reuses any made from an equal record.

Two speeds: a slider change fits garments the real-time way (``exact=False``: a few
milliseconds a garment); ``settle`` then does what a freshly realised ``Human`` has (every
garment vertex tested out of the body, the skin texture of the new ethnicity, age and
gender) once the slider rests. New meshes are copies of a template per topology and rig
(``template_mesh``): faces, UVs and vertex groups are copied in C, only positions written.

Nothing here keeps Blender references between calls (undo invalidates them); the caches
hold library records keyed by value.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property, lru_cache

import bpy
import numpy as np

from avatar.blender import armature as armature_bridge
from avatar.blender import materials as material_bridge
from avatar.blender import mesh as mesh_bridge
from avatar.blender.scene import CharacterObjects, new_collection
from avatar.body import shaped
from avatar.body.model import BodyModel
from avatar.body.shaped import PART_GROUPS, Body
from avatar.clothes import builtin, face, footing, library
from avatar.clothes.binding import fit
from avatar.clothes.fitting import FittedGarment, Garment, Outfit
from avatar.errors import AvatarError
from avatar.human import Human, Recipe
from avatar.material import Material
from avatar.mesh import Mesh
from avatar.part import MeshPart

log = logging.getLogger(__name__)

RECIPE_KEY = "avatar_recipe"
PART_KEY = "avatar_part"  # on each mesh part: "body", "eyes" or the garment's name
RIGGED_KEY = "avatar_rigged"  # on the root: 0 for a character made without an armature
SETTLED_KEY = "avatar_settled"  # on the root: 1 once garments and skin are exact
TEMPLATE_KEY = "avatar_template"  # on template meshes: their cache key


class Geometry:
    """What a recipe looks like at rest: the shaped body on its rig, and its outfit.

    vertices: (19158, 3) float32 the shaped body (helpers included), feet on z = 0.
    The skeleton is placed when ``body`` is first asked for (a bare body's slider step
    never needs it).
    """

    def __init__(self, recipe: Recipe, vertices: np.ndarray, model: BodyModel,
                 outfit: Outfit | None = None):  # fmt: skip
        self.recipe = recipe
        self.vertices = vertices
        self.model = model
        self.outfit = outfit

    @cached_property
    def body(self) -> Body:
        """The shaped body on the recipe's rig (skeleton placed, skin weights)."""
        rig = self.recipe.rig
        skeleton = _rig_definition(self.model, rig).skeleton(self.vertices)
        weights = self.model.skin_weights(rig, tuple(skeleton.names))
        return Body(self.vertices, skeleton, weights, self.model, rig)

    def part_vertices(self, part: str) -> np.ndarray:
        """(n, 3) float32 the vertices of a body part ("body", "eyes", "teeth", "tongue") in
        its mesh's order, as ``Human.part`` makes them (teeth seated in their bite)."""
        vertices = self.vertices[_part_index(self.model, part)]
        if part == "teeth":
            vertices = face.seat(vertices, *face.model_bite(self.model))
        return vertices


def geometry(
    recipe: Recipe,
    model: BodyModel | None = None,
    exact: bool = True,
    dress: bool = True,
    drag: bool = False,
) -> Geometry:
    """The body, skeleton and garments of ``recipe``, as ``Human.from_recipe`` realises
    them (``exact`` outfit), or fitted the real-time way (``exact=False``); ``dress=False``
    leaves the garments out (``outfit`` None). ``drag``: a step of a slider being dragged:
    the body's macro sum may use the model's drag contraction (within float32 rounding of
    the exact sum) and the garments their cached lookup."""
    model = model or BodyModel.shared()
    if drag:  # (shape resolves and validates the parameters)
        with model.dragging():
            vertices = shaped.rest_vertices(model, recipe.params)
    else:
        vertices = shaped.rest_vertices(model, recipe.params)
    # On built-in shoes the body stands on their soles, as Human raises it (clothes.footing).
    vertices[:, 2] += np.float32(footing.sole_height(vertices, recipe.clothes, recipe.folders,
                                                     model))  # fmt: skip
    geo = Geometry(recipe, vertices, model)
    if recipe.clothes and dress:
        geo.outfit = library.dress(geo.body, garments(recipe.clothes, model, cached=drag),
                                   exact=exact)  # fmt: skip
    return geo


@lru_cache(maxsize=16)
def _rig_definition(model: BodyModel, rig: str):
    return shaped.rig_definition(model, rig)


@lru_cache(maxsize=8)
def _part_index(model: BodyModel, part: str) -> np.ndarray:
    return shaped.part_vertices(model, part)


_USER_GARMENTS: dict[tuple[str, float], Garment] = {}
# A recipe's garments as last looked up: (entries, model) -> Garments. A drag step uses
# them as they are (no path parsed, no file stat'ed: 5 garments were ~15 lookups a step);
# every other change looks them up again, so an edited .mhclo is read at the next settle.
_GARMENT_SETS: dict[tuple[tuple[str, ...], BodyModel], list[Garment]] = {}


def garments(entries: Sequence[str], model: BodyModel | None = None,
             cached: bool = False) -> list[Garment]:  # fmt: skip
    """The Garments of a recipe's clothes entries (``garment`` each); ``cached``: as last
    looked up for the same entries, when they were."""
    model = model or BodyModel.shared()
    key = (tuple(entries), model)
    found = _GARMENT_SETS.get(key) if cached else None
    if found is None:
        found = [garment(entry, model) for entry in entries]
        if len(_GARMENT_SETS) >= 16:
            _GARMENT_SETS.clear()
        _GARMENT_SETS[key] = found
    return found


def garment(entry: str, model: BodyModel | None = None) -> Garment:
    """The Garment of a recipe entry: built-ins from the library's cache, a user's
    ``.mhclo`` read once per file version (its anchors then stay cached with it).
    Raises AvatarError when the file is gone."""
    source = library.find_garment(entry)
    if source in builtin.BY_NAME:
        return library.load_garment(source, model=model)
    try:
        key = (os.path.abspath(source), os.path.getmtime(source))
    except OSError as exc:
        raise AvatarError(f"{source}: no such garment file") from exc
    if key not in _USER_GARMENTS:
        _USER_GARMENTS[key] = library.load_garment(source, model=model)
    return _USER_GARMENTS[key]


# ---------------------------------------------------------------------------- creating


def create(
    recipe: Mapping[str, object] | Recipe,
    name: str = "Avatar",
    location: Sequence[float] = (0.0, 0.0, 0.0),
    rigged: bool = True,
    collection: bpy.types.Collection | None = None,
    exact: bool = False,
) -> CharacterObjects:
    """Add a character realised from ``recipe`` to the scene (in a new collection named
    after it unless ``collection`` is given).

    rigged: False makes a bare body (no armature; the root is the body mesh).
    exact: fit garments exactly now; by default they are fitted the real-time way and
    ``settle`` makes them exact (the extension runs it once the scene is idle).
    Raises AvatarError (unknown names, missing assets) before anything is added.
    """
    human = Human.from_recipe(recipe if isinstance(recipe, Recipe) else dict(recipe))
    geo = geometry(human.recipe, human.model, exact)
    made_collection = collection is None
    collection = collection or new_collection(name)
    before = set(bpy.data.objects)
    try:
        return _create(human, geo, name, location, rigged, collection, exact)
    except Exception:
        for obj in set(bpy.data.objects) - before:
            bpy.data.objects.remove(obj)
        if made_collection:
            bpy.data.collections.remove(collection)
        raise


def _create(human: Human, geo: Geometry, name, location, rigged, collection, exact):
    arm = None
    if rigged:
        arm = armature_bridge.new_armature_object(name, geo.body.skeleton, collection)
    parts = [_new_part(p, geo.body, arm, collection, mesh) for p, mesh in _parts(human, geo)]
    root = arm or parts[0]
    if arm is None:  # the body is the root: the other parts hang under it
        for obj in parts[1:]:
            obj.parent = root
    root.location = tuple(location)
    root[RECIPE_KEY] = json.dumps(human.to_recipe())
    root[RIGGED_KEY] = int(rigged)
    root[SETTLED_KEY] = int(exact or geo.outfit is None)
    return CharacterObjects(root, arm, parts)


def _parts(human: Human, geo: Geometry) -> list[tuple[MeshPart, Mesh]]:
    """(MeshPart with material and skin, its mesh on this body) per part, body first."""
    out = []
    weights = geo.body.weights
    for part in PART_GROUPS:
        index = _part_index(geo.body.model, part)
        skin = weights.subset(index)
        mesh = _body_mesh(geo) if part == "body" else human.part(part)
        out.append((MeshPart(part, mesh, _body_material(human, part),
                             (skin.indices, skin.weights)), mesh))  # fmt: skip
    looks = worn_looks(human.recipe, human.model) if geo.outfit else {}
    for fitted in geo.outfit or ():
        part = library.garment_part(fitted)
        if fitted.name in looks:  # its variant, aged for the wearer, as Human.outfit has it
            part = MeshPart(part.name, part.mesh, looks[fitted.name], part.skin,
                            normals=part.normals)
        out.append((part, part.mesh))
    return out


def worn_looks(recipe: Recipe, model: BodyModel) -> dict[str, Material]:
    """{garment name: its Material} of the recipe's worn built-ins, as ``Human.outfit``
    dresses them: the fabric/colour variant of ``garment_options``, brows and facial hair
    in the hair's colour and the built-in hair and brows greying with the wearer's age
    (``library.wearer_looks``). User garments keep the material they were made with."""
    entries = [e for e in recipe.clothes if library.find_garment(e, recipe.folders)
               in builtin.BY_NAME]  # fmt: skip
    options = recipe.garment_options
    loaded = [library.load_garment(e, recipe.folders, model=model, options=options.get(e))
              for e in entries]  # fmt: skip
    age = (model.defaults() | recipe.params)["age"]
    worn = library.wearer_looks(loaded, entries, options, age)
    return {g.name: g.material for g in worn if g.material is not None}


def _body_mesh(geo: Geometry) -> Mesh:
    return _skin_topology(geo.body.model).with_vertices(geo.part_vertices("body"))


@lru_cache(maxsize=4)
def _skin_topology(model: BodyModel) -> Mesh:
    """The skin part's faces and UVs (as ``Human.part("body")``), made once per model."""
    base = model.base
    faces = np.sort(np.concatenate([base.face_groups[g] for g in PART_GROUPS["body"]]))
    return base.subset(faces)


def _body_material(human: Human, part: str):
    return human.material(part)


def _new_part(part: MeshPart, body: Body, arm, collection, mesh: Mesh) -> bpy.types.Object:
    """A mesh object for ``part`` (a copy of its template, then this body's vertices)."""
    key = _template_key(part, body.rig if arm is not None else None)
    data = template_mesh(key, part, body.skeleton.names if arm is not None else None).copy()
    data.name = part.name
    data.use_fake_user = False
    data.pop(TEMPLATE_KEY, None)
    obj = bpy.data.objects.new(part.name, data)
    collection.objects.link(obj)
    write_vertices(obj, mesh.vertices)
    obj.data.materials.append(material_bridge.material(part.material, part.name))
    obj[PART_KEY] = part.name
    if arm is not None:
        armature_bridge.bind(obj, arm)
    return obj


def add_part(root: bpy.types.Object, part: MeshPart, body: Body) -> bpy.types.Object:
    """A new part object (e.g. a garment just put on) of the character ``root`` heads:
    in its collection, skinned to its armature, or parented to its body."""
    arm = root if root.type == "ARMATURE" else None
    collection = root.users_collection[0] if root.users_collection else None
    obj = _new_part(part, body, arm, collection or bpy.context.scene.collection, part.mesh)
    if arm is None:
        obj.parent = root
    return obj


def _template_key(part: MeshPart, rig: str | None) -> str:
    faces = np.ascontiguousarray(part.mesh.faces)
    digest = hashlib.blake2b(faces.data, digest_size=8).hexdigest()
    return f"{part.name}:{len(part.mesh.vertices)}:{digest}:{rig or '-'}"


def template_mesh(key: str, part: MeshPart, bone_names: Sequence[str] | None) -> bpy.types.Mesh:
    """The template mesh of a part's topology and rig: faces, UVs and (with ``bone_names``)
    skin weights as vertex groups, built once and kept hidden ('.avatar ...' orphan data:
    a new character copies it in C instead of adding thousands of group weights)."""
    found = next((m for m in bpy.data.meshes if m.get(TEMPLATE_KEY) == key), None)
    if found is not None:
        return found
    data = mesh_bridge.mesh_data(f".avatar {key}", part.mesh)
    if bone_names is not None and part.skin is not None:
        holder = bpy.data.objects.new(".avatar template", data)  # groups are set on objects
        try:
            mesh_bridge.set_vertex_groups(holder, bone_names, *part.skin)
        finally:
            bpy.data.objects.remove(holder)
    data[TEMPLATE_KEY] = key
    return data


# ---------------------------------------------------------------------------- updating


def set_params(root: bpy.types.Object, params: Mapping[str, float], drag: bool = False) -> Geometry:
    """Give the character ``root`` heads these body parameters, in place (real-time fit;
    ``settle`` after). Raises AvatarError for a bad name or value, before changing anything.

    drag: a step of a slider being dragged (what the extension's properties pass): a
    rigged character's new rest is shown through its pose (``show_rest_as_pose``; its
    Armature modifiers off meanwhile, so body and garments show their new rest exactly)
    instead of a trip through edit mode, which makes Blender re-evaluate every object in
    the scene. ``settle``, or any change without ``drag``, writes the true rest bones and
    ends it. A posed or animated character always gets its rest bones written."""
    recipe = recipe_of(root)
    human = Human(params, recipe.rig, recipe=recipe)  # validates: nothing changed yet
    geo = geometry(human.recipe, human.model, dress=False, drag=drag)
    parts = part_objects(root)  # O(objects in the file): once a step
    moved = _follow(root, geo, drag, parts)
    if moved is None and human.recipe.clothes:
        found = garments(human.recipe.clothes, human.model, cached=drag)
        geo.outfit = library.dress(geo.body, found, exact=False)
    write(root, geo, moved, drag=drag, parts=parts)
    root[RECIPE_KEY] = json.dumps(human.to_recipe())
    root[SETTLED_KEY] = int(not human.recipe.clothes and not is_dragging(root))
    return geo


@dataclass
class _Fitted:
    """What a character's garments were last written for: the body (19158, 3), the
    recipe's clothes and rig, and each garment's binding fit on that body (filled lazily)."""

    vertices: np.ndarray
    clothes: tuple[str, ...]
    rig: str
    points: dict[str, np.ndarray]


_LAST: dict[str, _Fitted] = {}  # root name -> what its garments were last written for


def _follow(
    root: bpy.types.Object,
    geo: Geometry,
    drag: bool = False,
    parts: Mapping[str, bpy.types.Object] | None = None,
) -> dict[str, np.ndarray] | None:
    """Garment vertices for a slider step: each garment as it is now, moved by how its
    binding's fit moved between the last body and ``geo``'s (one linear fit a garment,
    ~0.5 ms). The clearance the last fit resolved is carried along; ``settle`` then fits
    exactly. None when there is nothing to follow from (no garments, a new outfit, or the
    body object no longer holds the last body, e.g. after an undo): fit from scratch."""
    last = _LAST.get(root.name_full)
    recipe = geo.recipe
    if last is None or not recipe.clothes or (last.clothes, last.rig) != (recipe.clothes,
                                                                          recipe.rig):  # fmt: skip
        return None
    parts = part_objects(root) if parts is None else parts
    body = parts.get("body")
    skin = last.vertices[_part_index(geo.model, "body")]
    if body is None or not np.array_equal(read_positions(body), skin):
        return None
    out = {}
    for g in garments(recipe.clothes, geo.model, cached=drag):
        obj = parts.get(g.name)
        if obj is None:
            return None
        before = last.points.get(g.name)
        if before is None:
            before = fit(g.binding, last.vertices)
        after = last.points[g.name] = fit(g.binding, geo.vertices)
        current = read_positions(obj)
        delta = after - before
        if len(current) % len(delta):
            return None
        out[g.name] = current + np.tile(delta, (len(current) // len(delta), 1))
    # The fits just made belong to the new body: ``write`` keeps them for the next step.
    last.points = {n: last.points[n] for n in out}
    last.vertices = geo.vertices
    return out


def read_positions(obj: bpy.types.Object) -> np.ndarray:
    """(V, 3) float32 a mesh object's rest positions (its basis), fast where Blender
    keeps them as an attribute."""
    data = obj.data
    out = np.empty(len(data.vertices) * 3, dtype=np.float32)
    positions = data.attributes.get("position")
    if positions is not None and positions.data_type == "FLOAT_VECTOR":
        positions.data.foreach_get("vector", out)
    else:
        data.vertices.foreach_get("co", out)
    return out.reshape(-1, 3)


def settle(root: bpy.types.Object) -> Geometry:
    """Make the character exactly what its recipe realises: garments fitted exactly (no
    vertex inside the body) and the skin material of its current parameters."""
    recipe = recipe_of(root)
    human = Human.from_recipe(recipe)
    geo = geometry(recipe, human.model, exact=True)
    write(root, geo)
    refresh_materials(root, human)
    root[SETTLED_KEY] = 1
    return geo


def refresh_materials(root: bpy.types.Object, human: Human) -> None:
    """Give the body and eyes the materials ``human``'s parameters make (the skin depends
    on ethnicity, age and gender), and the worn built-ins theirs (``worn_looks``: brows,
    facial hair and hair grey with age); the old ones go when nothing else uses them."""
    parts = part_objects(root)
    # Every material is made before any is swapped: a skin file that fails to load leaves
    # the character as it was.
    looks = {name: human.material(name) for name in PART_GROUPS if name in parts}
    looks |= {name: look for name, look in worn_looks(human.recipe, human.model).items()
              if name in parts and parts[name].type == "MESH"}  # fmt: skip
    for name, look in looks.items():
        _swap_material(parts[name], material_bridge.material(look, name))


def _swap_material(obj: bpy.types.Object, new: bpy.types.Material) -> None:
    slots = obj.data.materials
    old = slots[0] if len(slots) else None
    if old == new:
        return
    if len(slots):
        slots[0] = new
    else:
        slots.append(new)
    material_bridge.release([old])


def write(
    root: bpy.types.Object,
    geo: Geometry,
    garments: Mapping[str, np.ndarray] | None = None,
    drag: bool = False,
    parts: Mapping[str, bpy.types.Object] | None = None,
) -> None:
    """Write ``geo`` into the character's objects: body, eyes, garments (``geo.outfit``'s,
    or ``garments``: name -> (M, 3)), rest bones (through the pose with ``drag``: see
    ``set_params``). ``parts``: ``part_objects(root)`` when the caller has it. Raises
    AvatarError, before writing, when the character's parts do not match it."""
    parts = part_objects(root) if parts is None else parts
    if garments is None:
        garments = {g.name: g.mesh.vertices for g in geo.outfit or ()}
    missing = [n for n in [*PART_GROUPS, *garments] if n not in parts]
    if missing:
        raise AvatarError(f"{root.name!r} has no part {missing[0]!r}: rebuild it")
    writes = [(parts[n], geo.part_vertices(n)) for n in PART_GROUPS]
    writes += [(parts[n], vertices) for n, vertices in garments.items()]
    for obj, vertices in writes:
        if len(obj.data.vertices) != len(vertices):
            raise AvatarError(f"{obj.name!r} no longer has the vertices Avatar made it with")
    for obj, vertices in writes:
        write_vertices(obj, vertices)
    if root.type == "ARMATURE":
        _write_rest(root, geo, drag)
    last = _LAST.get(root.name_full)
    points = last.points if last is not None and last.vertices is geo.vertices else {}
    _LAST[root.name_full] = _Fitted(geo.vertices, geo.recipe.clothes, geo.recipe.rig,
                                    points)  # fmt: skip


# ---------------------------------------------------------------------------- drags

DRAG_KEY = "avatar_drag"  # on an armature root: 1 while its pose stands in for its rest
DEFORM_OFF_KEY = "avatar_deform_off"  # on a part: Armature modifiers a drag switched off


def _write_rest(root: bpy.types.Object, geo: Geometry, drag: bool) -> None:
    """The armature's rest bones for ``geo``: shown through the pose during a drag (the
    first drag step switches the parts' Armature modifiers off), else written as rest."""
    skeleton = geo.body.skeleton
    if drag and _can_show_rest_as_pose(root):
        if not is_dragging(root):
            _switch_deform(root, on=False)
            root[DRAG_KEY] = 1
        armature_bridge.show_rest_as_pose(root, skeleton)
        return
    armature_bridge.set_rest(root, skeleton)
    _leave_drag(root)


def _can_show_rest_as_pose(root: bpy.types.Object) -> bool:
    """Whether a drag may show ``root``'s rest through its pose: the pose is the rest (or
    already stands in for it) and nothing else drives it (action, NLA, drivers)."""
    if is_dragging(root):
        return True
    if root.data.pose_position != "POSE":
        return False
    anim = root.animation_data
    if anim is not None and (anim.action is not None or len(anim.nla_tracks) or len(anim.drivers)):
        return False
    return armature_bridge.pose_is_rest(root)


def is_dragging(root: bpy.types.Object) -> bool:
    """Whether ``root``'s pose stands in for its rest (a drag not settled yet)."""
    return bool(root.get(DRAG_KEY, 0))


def end_drag(root: bpy.types.Object) -> None:
    """Write the true rest bones of ``root``'s recipe now if a drag left them shown through
    the pose (one edit-mode trip), the pose back to rest, the Armature modifiers on;
    nothing otherwise. For anything about to pose, export or save the character
    (``settle`` does it too, with the exact garments)."""
    if root.type != "ARMATURE" or not is_dragging(root):
        return
    geo = geometry(recipe_of(root), dress=False)
    armature_bridge.set_rest(root, geo.body.skeleton)
    _leave_drag(root)


def _leave_drag(root: bpy.types.Object) -> None:
    if not is_dragging(root):
        return
    armature_bridge.reset_pose(root)
    _switch_deform(root, on=True)
    del root[DRAG_KEY]


def _switch_deform(root: bpy.types.Object, on: bool) -> None:
    """The Armature modifiers on ``root`` of the meshes under it: off (those showing in
    the viewport, remembered on their object), or back on (those remembered)."""
    for obj in root.children_recursive:
        if obj.type != "MESH":
            continue
        if on:
            names = obj.get(DEFORM_OFF_KEY)
            if names is None:
                continue
            for name in names:
                modifier = obj.modifiers.get(name)
                if modifier is not None:
                    modifier.show_viewport = True
            del obj[DEFORM_OFF_KEY]
            continue
        off = [m for m in obj.modifiers
               if m.type == "ARMATURE" and m.object == root and m.show_viewport]  # fmt: skip
        for modifier in off:
            modifier.show_viewport = False
        if off:
            obj[DEFORM_OFF_KEY] = [m.name for m in off]


def write_vertices(obj: bpy.types.Object, vertices: np.ndarray) -> None:
    """Set a mesh object's rest positions (V, 3) in place; shape keys keep their offsets
    from the basis (e.g. baked garment corrections)."""
    data = obj.data
    flat = np.ascontiguousarray(vertices, dtype=np.float32).ravel()
    keys = data.shape_keys
    if keys is not None:
        old = np.empty_like(flat)
        keys.reference_key.data.foreach_get("co", old)
        delta = flat - old
        buffer = np.empty_like(flat)
        for block in keys.key_blocks:
            block.data.foreach_get("co", buffer)
            block.data.foreach_set("co", buffer + delta)
    positions = data.attributes.get("position")
    if positions is not None and positions.data_type == "FLOAT_VECTOR":
        # Blender 3.5+: one copy into the position attribute's array (~5 us for the body,
        # where ``vertices.foreach_set("co")`` goes through RNA per vertex: ~2.5 ms).
        positions.data.foreach_set("vector", flat)
    else:
        data.vertices.foreach_set("co", flat)
    data.update_tag()
    obj.update_tag()


# ---------------------------------------------------------------------------- queries


def part_objects(root: bpy.types.Object) -> dict[str, bpy.types.Object]:
    """The character's mesh parts by part name (the root too, when it is the body)."""
    objects = [root, *root.children_recursive]
    return {o[PART_KEY]: o for o in objects if o.type == "MESH" and PART_KEY in o.keys()}


def recipe_of(root: bpy.types.Object) -> Recipe:
    if RECIPE_KEY not in root.keys():
        raise AvatarError(f"{root.name!r} is not an Avatar character")
    return Recipe.from_dict(json.loads(root[RECIPE_KEY]))


def root_of(obj: bpy.types.Object | None) -> bpy.types.Object | None:
    """The object holding the recipe: ``obj`` or its nearest ancestor that has one."""
    while obj is not None:
        if RECIPE_KEY in obj.keys():
            return obj
        obj = obj.parent
    return None


def fitted_names(outfit: Outfit | None) -> list[str]:
    return [g.name for g in outfit or ()]


__all__ = ["FittedGarment", "Geometry", "create", "geometry", "set_params", "settle", "write"]

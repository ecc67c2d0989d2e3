"""Whole characters and their stage: body, garments, armature, action, camera, lights, floor.

Input is plain records of arrays (a ``Character`` of ``avatar.part.MeshPart``), so the bridge
does not depend on how the core assembles a human (``avatar.export.character`` makes the
record of a ``Human``).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import bpy
import numpy as np
from mathutils import Matrix, Vector

from avatar.blender import action as action_bridge
from avatar.blender import armature as armature_bridge
from avatar.blender import materials as material_bridge
from avatar.blender import mesh as mesh_bridge
from avatar.blender import morph_action
from avatar.mesh import Mesh
from avatar.part import MeshPart
from avatar.rig.skeleton import Animation, Skeleton


@dataclass(frozen=True)
class Character:
    """Everything needed to stage one character: parts skinned to one optional skeleton.

    parts: MeshParts (body first); their ``skin`` indexes ``skeleton.names``.

    location: (3,) where the armature (or, without one, every part) is placed, metres.
    recipe: JSON-able dict stored on the root object (``avatar_recipe``) so the extension can
    regenerate the character from it.
    morph_weights: part name -> (T, len(part.morphs)) weights of that part's morphs over the
    animation's frames (e.g. the baked garment corrections), keyed on its shape keys.
    """

    name: str
    parts: Sequence[MeshPart]
    skeleton: Skeleton | None = None
    animation: Animation | None = None
    location: tuple[float, float, float] = (0.0, 0.0, 0.0)
    recipe: Mapping[str, object] | None = None
    morph_weights: Mapping[str, np.ndarray] | None = None


@dataclass(frozen=True)
class CharacterObjects:
    """The Blender objects made for a Character. ``root`` is the armature, else the body."""

    root: bpy.types.Object
    armature: bpy.types.Object | None
    parts: list[bpy.types.Object]


def build_character(
    character: Character, collection: bpy.types.Collection | None = None
) -> CharacterObjects:
    """Create a character's objects: armature, skinned parts with materials, action.

    All or nothing: if any step fails, what was already added is removed and the error
    propagates.
    """
    before = set(bpy.data.objects)
    made_collection = collection is None
    collection = collection or new_collection(character.name)
    try:
        return _build(character, collection)
    except Exception:
        for obj in set(bpy.data.objects) - before:
            bpy.data.objects.remove(obj)
        if made_collection:
            bpy.data.collections.remove(collection)
        raise


def _build(character: Character, collection: bpy.types.Collection) -> CharacterObjects:
    armature = None
    if character.skeleton is not None:
        armature = armature_bridge.new_armature_object(
            character.name, character.skeleton, collection
        )
    parts = [_build_part(p, character.skeleton, armature, collection) for p in character.parts]
    root = armature or parts[0]
    for obj in [root] if armature else parts:
        obj.location = character.location
    if armature is not None and character.animation is not None:
        action_bridge.apply_animation(armature, character.animation, f"{character.name} motion")
    _key_morphs(character, parts)
    if character.recipe is not None:
        root["avatar_recipe"] = json.dumps(character.recipe)
    return CharacterObjects(root, armature, parts)


def _build_part(
    part: MeshPart,
    skeleton: Skeleton | None,
    armature: bpy.types.Object | None,
    collection: bpy.types.Collection,
) -> bpy.types.Object:
    obj = mesh_bridge.new_mesh_object(part.name, part.mesh, collection)
    obj["avatar_part"] = part.name  # what the extension's live updates find it by
    obj.data.materials.append(material_bridge.material(part.material, part.name))
    if part.normals is not None and not mesh_bridge.repeats_corners(part.mesh.faces):
        mesh_bridge.set_normals(obj, part.normals)
    if skeleton is not None and part.skin is not None:
        mesh_bridge.set_vertex_groups(obj, skeleton.names, *part.skin)
    if armature is not None:
        armature_bridge.bind(obj, armature)
    mesh_bridge.set_shape_keys(obj, part.morphs)
    return obj


def _key_morphs(character: Character, objects: list[bpy.types.Object]) -> None:
    """Key each part's morph weights on its shape keys, over the animation's frames."""
    for part, obj in zip(character.parts, objects, strict=True):
        weights = (character.morph_weights or {}).get(part.name)
        if weights is not None:
            morph_action.apply_morph_weights(obj, list(part.morphs), weights,
                                             f"{character.name} {part.name} morphs")  # fmt: skip


def new_collection(name: str, scene: bpy.types.Scene | None = None) -> bpy.types.Collection:
    """A new collection linked under the scene's master collection."""
    collection = bpy.data.collections.new(name)
    (scene or bpy.context.scene).collection.children.link(collection)
    return collection


def clear_scene() -> None:
    """Remove every object and the data Avatar creates, keeping the scene and its settings."""
    if bpy.context.object is not None and bpy.context.object.mode != "OBJECT":
        bpy.ops.object.mode_set(mode="OBJECT")
    data = bpy.data
    for pool in (data.objects, data.meshes, data.armatures, data.actions, data.materials,
                 data.images, data.cameras, data.lights, data.collections):  # fmt: skip
        for item in list(pool):
            pool.remove(item)


def world_bounds(objects: Sequence[bpy.types.Object]) -> tuple[np.ndarray, np.ndarray]:
    """(3,), (3,) min and max corners of the objects' evaluated bounding boxes (world)."""
    bpy.context.view_layer.update()
    corners = [
        np.array(obj.matrix_world @ Vector(c))
        for obj in objects
        if obj.type == "MESH"
        for c in obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).bound_box
    ]
    pts = np.array(corners) if corners else np.zeros((1, 3))
    return pts.min(axis=0), pts.max(axis=0)


def frame_camera(
    objects: Sequence[bpy.types.Object],
    direction: Sequence[float] = (0.25, -1.0, 0.12),
    lens_mm: float = 60.0,
    margin: float = 1.08,
    scene: bpy.types.Scene | None = None,
) -> bpy.types.Object:
    """Add (or reuse) the scene camera and aim it so every object fits the frame.

    direction: vector from the subject towards the camera (default: front, slightly right
    and above, since characters face -Y). lens_mm: focal length on a 36 mm sensor.
    """
    scene = scene or bpy.context.scene
    lo, hi = world_bounds(objects)
    camera = _scene_camera(scene, lens_mm)
    back = np.asarray(direction, dtype=np.float64)
    back /= np.linalg.norm(back)
    rotation = _look_rotation(-back)
    distance = _fit_distance(lo, hi, rotation, camera.data, scene, margin)
    centre = (lo + hi) / 2
    camera.matrix_world = Matrix.Translation(Vector(centre + back * distance)) @ rotation
    camera.data.clip_end = max(100.0, distance * 4)
    return camera


def _scene_camera(scene: bpy.types.Scene, lens_mm: float) -> bpy.types.Object:
    camera = scene.camera
    if camera is None:
        camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
        scene.collection.objects.link(camera)
        scene.camera = camera
    camera.data.lens = lens_mm
    camera.data.sensor_fit = "AUTO"
    return camera


def _look_rotation(forward: np.ndarray) -> Matrix:
    """4x4 rotation of a camera (which looks down its -Z, Y up) looking along ``forward``."""
    z = -forward / np.linalg.norm(forward)
    x = np.cross((0.0, 0.0, 1.0), z)
    x = x / np.linalg.norm(x) if np.linalg.norm(x) > 1e-9 else np.array([1.0, 0.0, 0.0])
    y = np.cross(z, x)
    return Matrix(np.column_stack([x, y, z]).tolist()).to_4x4()


def _fit_distance(lo, hi, rotation: Matrix, cam: bpy.types.Camera, scene, margin) -> float:
    """Distance from the box centre at which the box's corners fit the camera's view."""
    render = scene.render
    aspect = render.resolution_x / render.resolution_y
    half_fov = math.atan(cam.sensor_width / 2 / cam.lens)  # along the longer image side
    tan_x = math.tan(half_fov) * (1 if aspect >= 1 else aspect)
    tan_y = math.tan(half_fov) / (aspect if aspect >= 1 else 1)
    centre = (lo + hi) / 2
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                        for z in (lo[2], hi[2])]) - centre  # fmt: skip
    axes = np.array(rotation.to_3x3()).T  # rows: camera x, y, z in world
    local = corners @ axes.T
    # A corner at camera-space (x, y, z) fits when |x| <= tan_x * (d - z), same for y.
    need = np.maximum(np.abs(local[:, 0]) * margin / tan_x, np.abs(local[:, 1]) * margin / tan_y)
    return float(np.max(need + local[:, 2]))


def add_lights(scene: bpy.types.Scene | None = None, strength: float = 3.0) -> list:
    """A warm key sun, a cool fill area light and a soft grey world."""
    scene = scene or bpy.context.scene
    key = _light("Key", "SUN", strength, (math.radians(50), 0.0, math.radians(30)), scene)
    key.data.angle = math.radians(8)
    key.data.color = (1.0, 0.96, 0.9)
    fill = _light("Fill", "SUN", strength * 0.35, (math.radians(70), 0.0, math.radians(-120)),
                  scene)  # fmt: skip
    fill.data.color = (0.85, 0.9, 1.0)
    _world(scene, (0.42, 0.44, 0.48), 0.6)
    return [key, fill]


def _light(name: str, kind: str, energy: float, euler, scene) -> bpy.types.Object:
    light = bpy.data.lights.new(name, kind)
    light.energy = energy
    obj = bpy.data.objects.new(name, light)
    obj.rotation_euler = euler
    scene.collection.objects.link(obj)
    return obj


def _world(scene: bpy.types.Scene, colour, strength: float) -> None:
    world = scene.world or bpy.data.worlds.new("World")
    scene.world = world
    if bpy.app.version < (5, 0):  # always node-based from 5.0 (use_nodes deprecated)
        world.use_nodes = True
    background = world.node_tree.nodes.get("Background") if world.node_tree else None
    if background is not None:
        background.inputs["Color"].default_value = (*colour, 1.0)
        background.inputs["Strength"].default_value = strength
    world.color = colour  # what Workbench shows


def add_floor(size: float = 30.0, scene: bpy.types.Scene | None = None) -> bpy.types.Object:
    """A square floor at z = 0 with a matte light-grey material."""
    half = size / 2
    quad = Mesh(
        np.array([[-half, -half, 0], [half, -half, 0], [half, half, 0], [-half, half, 0]],
                 dtype=np.float32),
        np.array([[0, 1, 2, 3]], dtype=np.int32),
    )  # fmt: skip
    obj = mesh_bridge.new_mesh_object("Floor", quad, (scene or bpy.context.scene).collection)
    obj.data.materials.append(material_bridge.plain("Floor", (0.62, 0.62, 0.6), roughness=0.9))
    return obj

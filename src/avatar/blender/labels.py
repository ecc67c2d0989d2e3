"""Render a dataset sample: the RGB picture and exact per-pixel labels, from static meshes.

Two renders of one staged scene:
1. RGB: the scene's materials, lights and world, Cycles (or EEVEE/Workbench), PNG.
2. Labels: Cycles at 1 sample per pixel with a 0.01 px pixel filter, so every pixel is the
   surface hit at its centre (no anti-aliasing, no blending of ids): planar depth (Z pass,
   metres along the view axis), world normals, the object pass index (instance ids) and a
   shader AOV ``part`` (the body-part id stored on the skin's faces), one material override
   for every object. Written as a multilayer EXR and read back (``read_exr``). Rendered
   without what no label depends on (world, lights, the objects' own materials and their
   textures): Cycles would still prepare them, at up to 3x the pass's own cost.
"""

from __future__ import annotations

import contextlib
import math
import tempfile
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

import bpy
import numpy as np

from avatar.blender import materials as material_bridge
from avatar.blender import mesh as mesh_bridge
from avatar.blender import render as render_bridge
from avatar.blender.camera import add_camera
from avatar.blender.stage_materials import StageMaterials
from avatar.camera import CameraModel
from avatar.io import exr
from avatar.mesh import Mesh
from avatar.part import MeshPart

PART_ATTRIBUTE = "avatar_part"
PART_AOV = "part"
# Uncompressed: the file lives a moment in a temp dir; ZIP spent ~20 ms a pass compressing
# float32 noise (normals) that the reader then inflates again. Lossless either way.
LABEL_EXR_CODEC = "NONE"
NO_HIT = 1e9  # m: Cycles' depth where a ray hits nothing is far beyond this
_FLOOR = Mesh(np.array([[-20, -20, 0], [20, -20, 0], [20, 20, 0], [-20, 20, 0]], np.float32),
              np.array([[0, 1, 2, 3]], np.int32))  # fmt: skip


@dataclass(frozen=True)
class Item:
    """One mesh to stage: its part, its instance id (object pass index, 1..65535) and, for
    a skin, the body-part id of each face (else None)."""

    part: MeshPart
    instance: int
    face_parts: np.ndarray | None = None


@dataclass(frozen=True)
class Labels:
    """Label images, (H, W) each, row 0 at the top.

    depth: float32 planar depth in metres, inf where nothing was hit.
    normals: (H, W, 3) float32 unit world normals, 0 where nothing was hit.
    instance: uint16 object ids (0 background); part: uint8 body-part ids (0 none).
    """

    depth: np.ndarray
    normals: np.ndarray
    instance: np.ndarray
    part: np.ndarray


class Stage:
    """A worker's Blender scene, reused sample after sample: materials and images made once
    per material record with maps sized for the picture and kept while recently used
    (``StageMaterials``), objects replaced every sample."""

    def __init__(self) -> None:
        self.materials = StageMaterials()
        self.label_material = _label_material()
        self.floor_material = material_bridge.plain("Floor", (0.55, 0.55, 0.53), roughness=0.9)
        self.floor_material.use_fake_user = True

    def build(self, items: Sequence[Item], camera: CameraModel, light: dict,
              background: dict) -> None:  # fmt: skip
        """Replace the scene's objects by ``items``, the camera, the light and the world."""
        _clear_objects()
        scene = bpy.context.scene
        self.materials.for_picture(*camera.size)
        used: set[str] = set()
        for item in items:
            obj = mesh_bridge.new_mesh_object(item.part.name, item.part.mesh, scene.collection)
            mat = self.materials.get(item.part)
            obj.data.materials.append(mat)
            used.add(mat.name_full)
            obj.pass_index = int(item.instance)
            values = np.zeros(len(item.part.mesh.faces), np.int32)
            if item.face_parts is not None:
                values[:] = item.face_parts
            attribute = obj.data.attributes.new(PART_ATTRIBUTE, "INT", "FACE")
            attribute.data.foreach_set("value", values)
        self._drop_unused(used)
        if background.get("kind") != "images":  # a photo behind: no floor in front of it
            floor = mesh_bridge.new_mesh_object("Floor", _FLOOR, scene.collection)
            floor.data.materials.append(self.floor_material)
        add_camera(camera, scene=scene)
        _add_light(scene, light)
        _set_world(scene, background, light if light.get("kind") == "sky" else None)

    def _drop_unused(self, used: set[str]) -> None:
        """Keep the stage's recently used materials (``StageMaterials.trim``) and remove any
        other material no object uses, with its images (e.g. from an EEVEE/Workbench run)."""
        self.materials.trim(used)
        kept = self.materials.names()
        for mat in list(bpy.data.materials):
            if mat.users == 0 and mat.name_full not in kept and not mat.use_fake_user:
                images = [n.image for n in mat.node_tree.nodes if getattr(n, "image", None)]
                bpy.data.materials.remove(mat)
                for image in images:
                    if image.users == 0:
                        bpy.data.images.remove(image)

    @staticmethod
    def set_threads(threads: int) -> None:
        """Render on ``threads`` CPU threads (0: Blender's default, one per core)."""
        scene_render = bpy.context.scene.render
        scene_render.threads_mode = "FIXED" if threads > 0 else "AUTO"
        if threads > 0:
            scene_render.threads = threads

    def render_rgb(self, path: Path, engine: str, samples: int, transparent: bool) -> Path:
        """The picture, 8-bit RGBA PNG (alpha 0 where transparent and nothing was hit)."""
        scene = bpy.context.scene
        scene.view_layers[0].material_override = None
        width, height = scene.render.resolution_x, scene.render.resolution_y
        percentage = scene.render.resolution_percentage
        render_bridge.configure(scene, engine, samples, (width, height), transparent)
        scene.render.resolution_percentage = percentage
        if engine == "CYCLES":
            scene.cycles.filter_width = 1.5
        scene.render.filepath = str(path)
        bpy.ops.render.render(write_still=True)
        return path

    def render_labels(self) -> Labels:
        """The label passes (see module docstring)."""
        scene = bpy.context.scene
        layer = scene.view_layers[0]
        layer.material_override = self.label_material
        scene.render.engine = "CYCLES"
        scene.cycles.samples = 1
        scene.cycles.use_denoising = False
        scene.cycles.filter_width = 0.01
        scene.cycles.max_bounces = 0
        scene.render.film_transparent = True
        layer.use_pass_z = layer.use_pass_normal = layer.use_pass_object_index = True
        if PART_AOV not in layer.aovs:
            aov = layer.aovs.add()
            aov.name, aov.type = PART_AOV, "VALUE"
        settings = scene.render.image_settings
        if hasattr(settings, "media_type"):  # Blender 5.0+
            settings.media_type = "MULTI_LAYER_IMAGE"
        settings.file_format = "OPEN_EXR_MULTILAYER"
        settings.color_depth = "32"
        settings.exr_codec = LABEL_EXR_CODEC
        with _unlit(scene), _only_material(scene, self.label_material), \
                tempfile.TemporaryDirectory(prefix="avatar-labels-") as tmp:
            path = Path(tmp) / "labels.exr"
            scene.render.filepath = str(path)
            bpy.ops.render.render(write_still=True)
            channels = exr.read(path)
        layer.material_override = None
        if hasattr(settings, "media_type"):
            settings.media_type = "IMAGE"
        settings.file_format = "PNG"
        return _labels(channels)


@contextlib.contextmanager
def _unlit(scene: bpy.types.Scene) -> Iterator[None]:
    """The scene without its world and lights for the label render, restored after.

    No label depends on light (depth, normals, ids and the AOV are what the camera ray hits,
    and the film is transparent), but Cycles would still prepare it: Blender's sky texture
    precomputes its multiple scattering table on every render (~0.7 s of a 1-sample pass
    at 256x256), the world's importance map, the light tree and one shadow ray per light
    for every pixel."""
    world = scene.world
    lights = [obj for obj in scene.objects if obj.type == "LIGHT" and not obj.hide_render]
    scene.world = None
    for obj in lights:
        obj.hide_render = True
    try:
        yield
    finally:
        scene.world = world
        for obj in lights:
            obj.hide_render = False


@contextlib.contextmanager
def _only_material(scene: bpy.types.Scene, material: bpy.types.Material) -> Iterator[None]:
    """Every mesh's material slots hold ``material`` for the label render, restored after.

    The view layer's material override alone makes Cycles shade with it, but the meshes'
    own materials stay in the depsgraph: Cycles still synced them and loaded every texture
    (skin, garments, hair: ~20-90 ms a pass) for a render that never samples them."""
    slots = [(obj.data, i, mat) for obj in scene.objects if obj.type == "MESH"
             for i, mat in enumerate(obj.data.materials)]  # fmt: skip
    for mesh, i, _ in slots:
        mesh.materials[i] = material
    try:
        yield
    finally:
        for mesh, i, mat in slots:
            mesh.materials[i] = mat


def _clear_objects() -> None:
    """Remove every object and its mesh, light and camera data (materials stay cached)."""
    data = bpy.data
    for obj in list(data.objects):
        data.objects.remove(obj)
    for pool in (data.meshes, data.lights, data.cameras):
        for item in list(pool):
            if item.users == 0:
                pool.remove(item)


def _label_material() -> bpy.types.Material:
    """Every object's material in the label render: a grey diffuse surface that writes the
    face attribute ``avatar_part`` to the ``part`` AOV."""
    mat = bpy.data.materials.get("avatar-labels") or bpy.data.materials.new("avatar-labels")
    if bpy.app.version < (5, 0):
        mat.use_nodes = True
    tree = mat.node_tree
    tree.nodes.clear()
    attribute = tree.nodes.new("ShaderNodeAttribute")
    attribute.attribute_type = "GEOMETRY"
    attribute.attribute_name = PART_ATTRIBUTE
    aov = tree.nodes.new("ShaderNodeOutputAOV")
    if hasattr(aov, "aov_name"):
        aov.aov_name = PART_AOV
    else:  # Blender 3.x/4.0 called it "name"
        aov.name = PART_AOV
    tree.links.new(attribute.outputs["Fac"], aov.inputs["Value"])
    # A plain diffuse surface: it gives the normal pass (an emission-only or black surface
    # would be culled by Cycles as invisible, leaving no depth, ids or normals).
    diffuse = tree.nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (0.5, 0.5, 0.5, 1.0)
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(diffuse.outputs["BSDF"], output.inputs["Surface"])
    mat.use_fake_user = True
    return mat


def _add_light(scene: bpy.types.Scene, light: dict) -> None:
    kind = light.get("kind", "sun")
    strength = float(light.get("strength", 1.0))
    elevation = math.radians(float(light.get("elevation_deg", 50.0)))
    azimuth = math.radians(float(light.get("azimuth_deg", 30.0)))
    warmth = float(light.get("warmth", 0.0))
    colour = (1.0, 1.0 - 0.06 * warmth, 1.0 - 0.12 * warmth) if warmth > 0 else \
        (1.0 + 0.1 * warmth, 1.0 + 0.04 * warmth, 1.0)  # fmt: skip
    if kind == "area":
        data = bpy.data.lights.new("Key", "AREA")
        data.energy, data.size = 900.0 * strength, 2.5
        obj = bpy.data.objects.new("Key", data)
        distance = 4.0
        obj.location = (distance * math.cos(elevation) * math.sin(azimuth),
                        -distance * math.cos(elevation) * math.cos(azimuth),
                        distance * math.sin(elevation) + 1.0)  # fmt: skip
        obj.rotation_euler = (math.pi / 2 - elevation, 0.0, azimuth)
    else:
        data = bpy.data.lights.new("Key", "SUN")
        data.energy = (2.5 if kind == "sun" else 1.0) * strength
        data.angle = math.radians(6.0)
        obj = bpy.data.objects.new("Key", data)
        obj.rotation_euler = (math.pi / 2 - elevation, 0.0, azimuth)
    data.color = colour
    scene.collection.objects.link(obj)


def _set_world(scene: bpy.types.Scene, background: dict, sky: dict | None = None) -> None:
    """World light and backdrop: a plain colour, a procedural gradient of noise, Blender's
    sky texture (light kind "sky"), or an HDRI."""
    world = scene.world or bpy.data.worlds.new("World")
    scene.world = world
    if bpy.app.version < (5, 0):
        world.use_nodes = True
    tree = world.node_tree
    tree.nodes.clear()
    out = tree.nodes.new("ShaderNodeOutputWorld")
    bg = tree.nodes.new("ShaderNodeBackground")
    tree.links.new(bg.outputs["Background"], out.inputs["Surface"])
    colour = tuple(background.get("colour", (0.4, 0.4, 0.45)))
    bg.inputs["Strength"].default_value = 0.8
    kind = background.get("kind", "solid")
    if sky is not None and kind != "hdri":  # Blender's physical sky lights the scene
        texture = tree.nodes.new("ShaderNodeTexSky")
        if hasattr(texture, "sun_elevation"):
            texture.sun_elevation = math.radians(float(sky.get("elevation_deg", 45.0)))
            texture.sun_rotation = math.radians(float(sky.get("azimuth_deg", 0.0)))
        tree.links.new(texture.outputs["Color"], bg.inputs["Color"])
        bg.inputs["Strength"].default_value = 0.07 * float(sky.get("strength", 1.0))
    elif kind == "hdri" and background.get("image"):
        env = tree.nodes.new("ShaderNodeTexEnvironment")
        env.image = bpy.data.images.load(str(background["image"]), check_existing=True)
        tree.links.new(env.outputs["Color"], bg.inputs["Color"])
    elif kind == "procedural":
        noise = tree.nodes.new("ShaderNodeTexNoise")
        noise.inputs["Scale"].default_value = 2.0 + (background.get("seed", 0) % 7)
        ramp = tree.nodes.new("ShaderNodeValToRGB")
        ramp.color_ramp.elements[0].color = (*colour, 1.0)
        ramp.color_ramp.elements[1].color = (*(1.0 - c * 0.8 for c in colour), 1.0)
        tree.links.new(noise.outputs["Fac"], ramp.inputs["Fac"])
        tree.links.new(ramp.outputs["Color"], bg.inputs["Color"])
    else:
        bg.inputs["Color"].default_value = (*colour, 1.0)
    world.color = colour


def _channel(channels: dict[str, np.ndarray], *suffixes: str) -> np.ndarray:
    for suffix in suffixes:
        for name, pixels in channels.items():
            if name.endswith(suffix):
                return pixels
    raise KeyError(f"no channel ending in {suffixes} among {sorted(channels)}")


def _labels(channels: dict[str, np.ndarray]) -> Labels:
    depth = _channel(channels, "Depth.Z")
    hit = depth < NO_HIT
    normals = np.stack([_channel(channels, f"Normal.{a}") for a in "XYZ"], axis=-1)
    instance = np.rint(_channel(channels, "Object Index.X", "IndexOB.X")).astype(np.uint16)
    part = np.rint(_channel(channels, f"{PART_AOV}.X", f"{PART_AOV}.V")).astype(np.uint8)
    return Labels(np.where(hit, depth, np.inf).astype(np.float32),
                  np.where(hit[..., None], normals, 0.0).astype(np.float32),
                  np.where(hit, instance, 0).astype(np.uint16),
                  np.where(hit, part, 0).astype(np.uint8))  # fmt: skip

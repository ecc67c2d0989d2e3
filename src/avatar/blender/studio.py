"""A photo studio around a character: a curved cyclorama backdrop (floor sweeping up into a
wall, no horizon line), a camera framing the character, three-point lighting (key, fill,
rim) and render settings for Cycles or EEVEE.

``setup`` is idempotent: every object it makes carries ``ROLE_KEY`` (its role) and lives in
one collection, and a second call finds and updates those objects (new size, framing,
engine) instead of adding more.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import bpy
import numpy as np
from mathutils import Matrix

from avatar import camera as camera_maths
from avatar.blender import camera as camera_bridge
from avatar.blender import materials as material_bridge
from avatar.blender import render
from avatar.blender.scene import world_bounds

ROLE_KEY = "avatar_studio"  # on each studio object: backdrop, camera, key, fill, rim
COLLECTION = "Avatar Studio"
ENGINES = ("CYCLES", "EEVEE")


@dataclass(frozen=True)
class Studio:
    """The studio's objects (each made once, then updated)."""

    backdrop: bpy.types.Object
    camera: bpy.types.Object
    key: bpy.types.Object
    fill: bpy.types.Object
    rim: bpy.types.Object


def setup(
    subject: Sequence[bpy.types.Object],
    engine: str = "CYCLES",
    samples: int = 64,
    resolution: tuple[int, int] | None = None,
    lens_mm: float = 50.0,
    margin: float = 1.1,
    scene: bpy.types.Scene | None = None,
) -> Studio:
    """Build (or update) the studio around the mesh objects ``subject`` (a character's
    parts) and make its camera the scene's.

    engine: "CYCLES" or "EEVEE" (Blender's id for it is found at run time: 4.2-4.5 call it
    BLENDER_EEVEE_NEXT, 5.x BLENDER_EEVEE). samples: render samples per pixel.
    resolution: (width, height) pixels, None keeps the scene's. margin: the frame is this
    much larger than the character's bounding box (1.1: 5% free on each side).
    """
    scene = scene or bpy.context.scene
    if engine not in ENGINES:
        raise ValueError(f"engine is one of {', '.join(ENGINES)}, not {engine!r}")
    configure(scene, engine, samples, resolution)
    lo, hi = world_bounds(subject)
    collection = _collection(scene)
    camera = _camera(collection, scene, lo, hi, lens_mm, margin)
    distance = float(np.linalg.norm(np.array(camera.matrix_world.translation) - (lo + hi) / 2))
    backdrop = _backdrop(collection, lo, hi, distance)
    key, fill, rim = _lights(collection, lo, hi)
    return Studio(backdrop, camera, key, fill, rim)


def configure(
    scene: bpy.types.Scene, engine: str, samples: int, resolution: tuple[int, int] | None
) -> None:
    """Engine, samples, colour management and (when given) image size for studio renders."""
    if resolution is not None:
        render.set_resolution(scene, resolution)
    scene.render.film_transparent = False
    scene.view_settings.view_transform = "AgX" if bpy.app.version >= (4, 0) else "Filmic"
    if engine == "CYCLES":
        scene.render.engine = "CYCLES"
        scene.cycles.samples = samples
        scene.cycles.use_denoising = samples >= 16  # too few samples for the denoiser
        scene.cycles.device = "GPU" if render.enable_gpu() else "CPU"
    else:
        scene.render.engine = render.engine_id("BLENDER_EEVEE")
        eevee = scene.eevee
        for name in ("taa_render_samples",):
            if hasattr(eevee, name):
                setattr(eevee, name, samples)
        if hasattr(eevee, "use_shadows"):  # EEVEE Next (4.2+): shadows are per light
            eevee.use_shadows = True
    world = scene.world or bpy.data.worlds.new("World")
    scene.world = world
    if bpy.app.version < (5, 0):
        world.use_nodes = True
    background = world.node_tree.nodes.get("Background") if world.node_tree else None
    if background is not None:  # a dim grey room: the lights do the work
        background.inputs["Color"].default_value = (0.05, 0.05, 0.055, 1.0)
        background.inputs["Strength"].default_value = 1.0


def _collection(scene: bpy.types.Scene) -> bpy.types.Collection:
    found = next((c for c in bpy.data.collections if c.get(ROLE_KEY) == "collection"), None)
    if found is None:
        found = bpy.data.collections.new(COLLECTION)
        found[ROLE_KEY] = "collection"
    if found.name not in scene.collection.children:
        scene.collection.children.link(found)
    return found


def _object(collection: bpy.types.Collection, role: str, make) -> bpy.types.Object:
    """The studio's object for ``role``, made by ``make(name)`` the first time."""
    found = next((o for o in collection.objects if o.get(ROLE_KEY) == role), None)
    if found is None:
        found = make(f"Studio {role.capitalize()}")
        found[ROLE_KEY] = role
        collection.objects.link(found)
    return found


def _camera(collection, scene, lo, hi, lens_mm: float, margin: float) -> bpy.types.Object:
    """The studio camera in front of the character (it faces -Y), a little above its middle,
    looking at it from as close as lets its whole bounding box fit with ``margin``."""
    obj = _object(collection, "camera",
                  lambda name: bpy.data.objects.new(name, bpy.data.cameras.new(name)))  # fmt: skip
    cam = obj.data
    cam.type, cam.lens, cam.sensor_fit = "PERSP", lens_mm, "AUTO"
    cam.shift_x = cam.shift_y = 0.0
    centre = (lo + hi) / 2
    height = float(hi[2] - lo[2])
    target = centre + [0.0, 0.0, 0.05 * height]
    direction = np.array([0.0, -1.0, 0.12])
    direction /= np.linalg.norm(direction)
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                        for z in (lo[2], hi[2])])  # fmt: skip
    distance = _fit(obj, scene, corners, target, direction, margin)
    cam.clip_start, cam.clip_end = 0.05, max(100.0, distance * 10)
    scene.camera = obj
    return obj


def _fit(obj, scene, corners, target, direction, margin: float) -> float:
    """Place ``obj`` at ``target + direction * d`` looking at ``target``, with the smallest
    d (bisection) at which every corner projects inside the image shrunk by ``margin``
    (Blender's own projection rules: sensor fit, pixel aspect, resolution)."""

    def fits(distance: float) -> bool:
        obj.matrix_world = Matrix(camera_maths.look_at(target + direction * distance, target))
        model = camera_bridge.camera_model(obj, scene)
        K, w2c = camera_maths.intrinsics(model), camera_maths.world_to_camera(model)
        uvz = camera_maths.project(corners, K, w2c)
        width, height = model.size
        half = np.array([width, height]) / 2
        centred = np.abs(uvz[:, :2] + 0.5 - half) * margin
        return bool(np.all(uvz[:, 2] > 0.1) and np.all(centred <= half))

    near, far = 0.1, 1.0
    while not fits(far):
        near, far = far, far * 2
        if far > 1e4:
            raise ValueError("cannot frame the character")
    for _ in range(40):
        mid = (near + far) / 2
        near, far = (near, mid) if fits(mid) else (mid, far)
    fits(far)
    return far


def _backdrop(collection, lo, hi, distance: float) -> bpy.types.Object:
    """The cyclorama: a floor just under the feet from behind the camera to a wall behind
    the character, joined by a quarter-circle cove (no visible horizon), as wide as the
    camera can see. Its mesh is rebuilt in place on every call."""
    height = float(hi[2] - lo[2])
    radius = 0.6 * height
    floor_z = float(lo[2]) - 0.002  # just under the soles: no z-fighting
    wall_y = float(hi[1]) + max(0.8, 0.5 * height) + radius  # the wall's plane
    front_y = float(lo[1]) - distance - 1.0  # behind the camera
    wall_top = floor_z + 3.0 * height
    width = 2.0 * (distance + wall_y - float(lo[1])) + 2.0
    angles = np.linspace(0.0, math.pi / 2, 12)
    profile = [(front_y, floor_z)]
    profile += [(wall_y - radius + radius * math.sin(a), floor_z + radius - radius * math.cos(a))
                for a in angles]  # fmt: skip
    profile += [(wall_y, wall_top)]
    x0, x1 = float((lo[0] + hi[0]) / 2 - width / 2), float((lo[0] + hi[0]) / 2 + width / 2)
    vertices = [(x, y, z) for y, z in profile for x in (x0, x1)]
    faces = [(2 * i, 2 * i + 1, 2 * i + 3, 2 * i + 2) for i in range(len(profile) - 1)]

    def make(name):
        return bpy.data.objects.new(name, bpy.data.meshes.new(name))

    obj = _object(collection, "backdrop", make)
    data = obj.data
    data.clear_geometry()
    data.from_pydata(vertices, [], faces)
    data.polygons.foreach_set("use_smooth", [True] * len(faces))
    data.update()
    if not data.materials:
        data.materials.append(material_bridge.plain("Studio Backdrop", (0.3, 0.3, 0.3), 0.85))
    return obj


# (role, azimuth degrees from the camera's side (0 = straight in front, +: to the
# character's left as the camera sees it), elevation degrees, W per (m of distance)^2, size
# as a share of the height, colour): the classic three-point setup.
_LIGHTS = (
    ("key", -40.0, 35.0, 10.0, 0.6, (1.0, 0.96, 0.9)),  # main light, camera left, above
    ("fill", 45.0, 10.0, 3.5, 1.0, (0.9, 0.94, 1.0)),  # softer, opposite side, lower
    ("rim", 155.0, 45.0, 14.0, 0.4, (1.0, 1.0, 1.0)),  # behind: an outline on the edges
)


def _lights(collection, lo, hi) -> list[bpy.types.Object]:
    """Key, fill and rim area lights aimed at the character's chest."""
    height = float(hi[2] - lo[2])
    target = (lo + hi) / 2 + [0.0, 0.0, 0.15 * height]
    distance = 1.6 * height
    out = []
    for role, azimuth, elevation, power, size, colour in _LIGHTS:

        def make(name):
            return bpy.data.objects.new(name, bpy.data.lights.new(name, "AREA"))

        obj = _object(collection, role, make)
        a, e = math.radians(azimuth), math.radians(elevation)
        # Azimuth 0 is the camera's side (-Y); positive turns towards +X.
        offset = np.array([math.sin(a) * math.cos(e), -math.cos(a) * math.cos(e), math.sin(e)])
        obj.matrix_world = Matrix(camera_maths.look_at(target + offset * distance, target))
        light = obj.data
        light.energy = power * distance**2
        light.size = size * height
        light.color = colour
        out.append(obj)
    return out

"""The label render of a dataset stage (``avatar.blender.labels``): what it renders with and
that its labels do not depend on the scene's light, on a small real scene (pip bpy, Cycles)."""

from __future__ import annotations

import contextlib
import importlib.util

import numpy as np
import pytest

pytestmark = pytest.mark.skipif(
    importlib.util.find_spec("bpy") is None or importlib.util.find_spec("OpenEXR") is None,
    reason="needs bpy and OpenEXR (the dataset extra)",
)  # fmt: skip


def _box(centre, size) -> np.ndarray:
    corners = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], np.float32)
    return (corners - 0.5) * np.asarray(size, np.float32) + np.asarray(centre, np.float32)


_BOX_FACES = np.array([[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2],
                       [1, 3, 7, 5]], np.int32)  # fmt: skip


def _staged(light: dict, background: dict):
    """A stage with two boxes (instances 3 and 7, the first with body-part ids per face) on
    the floor, seen from 4 m, lit by ``light``."""
    from avatar.blender.labels import Item, Stage
    from avatar.camera import CameraModel, look_at
    from avatar.mesh import Mesh
    from avatar.part import MeshPart

    items = [Item(MeshPart("torso", Mesh(_box((-0.4, 0, 0.9), (0.5, 0.4, 1.8)), _BOX_FACES)), 3,
                  np.array([1, 2, 3, 4, 5, 6])),
             Item(MeshPart("crate", Mesh(_box((0.5, -0.3, 0.4), (0.6, 0.6, 0.8)), _BOX_FACES)), 7)]
    camera = CameraModel(50.0, 36.0, 24.0, "AUTO", 0.0, 0.0, (64, 48), 100, (1.0, 1.0),
                         look_at(np.array([1.0, -4.0, 1.6]), np.array([0.0, 0.0, 0.8])))
    stage = Stage()
    stage.build(items, camera, light, background)
    return stage


@pytest.mark.parametrize("light", [{"kind": "sky", "elevation_deg": 30.0}, {"kind": "area"}])
def test_labels_render_without_world_or_lights_and_equal_a_lit_render(light, monkeypatch):
    """Nothing the label render writes depends on light or the scene's own materials, so it
    renders without the world (Blender's sky texture rebuilt its scattering table on every
    label render: ~0.7 s) and lights, and with the label material in every slot (with the
    override alone Cycles still loaded every texture); the scene gets all of it back, and its
    labels equal those of the same render with the world, lights and materials in."""
    from avatar.blender import labels

    bpy = labels.bpy  # Blender through the bridge (tests do not import it themselves)
    stage = _staged(light, {"kind": "procedural", "colour": (0.3, 0.4, 0.5)})
    scene = bpy.context.scene
    world = scene.world
    lamps = [obj for obj in scene.objects if obj.type == "LIGHT"]
    assert world is not None and len(lamps) == 1
    meshes = [obj.data for obj in scene.objects if obj.type == "MESH"]
    own = [list(mesh.materials) for mesh in meshes]
    assert len(meshes) == 3 and stage.label_material not in sum(own, [])  # boxes and floor
    seen = []

    def during(*_args) -> None:
        s = bpy.context.scene
        seen.append((s.world, [o.hide_render for o in lamps], s.render.image_settings.exr_codec,
                     {m.name for mesh in meshes for m in mesh.materials}))

    bpy.app.handlers.render_pre.append(during)
    try:
        unlit = stage.render_labels()
    finally:
        bpy.app.handlers.render_pre.remove(during)
    assert seen == [(None, [True], "NONE", {stage.label_material.name})]
    assert scene.world == world and not lamps[0].hide_render
    assert [list(mesh.materials) for mesh in meshes] == own

    monkeypatch.setattr(labels, "_unlit", lambda scene: contextlib.nullcontext())
    monkeypatch.setattr(labels, "_only_material", lambda scene, mat: contextlib.nullcontext())
    lit = stage.render_labels()
    for name in ("depth", "normals", "instance", "part"):
        assert np.array_equal(getattr(unlit, name), getattr(lit, name)), name
    # ... and they are labels of this scene: both boxes, the torso's faces' part ids
    assert {0, 3, 7} <= set(np.unique(unlit.instance).tolist())
    torso = unlit.instance == 3
    assert set(np.unique(unlit.part[torso]).tolist()) <= {1, 2, 3, 4, 5, 6}
    assert len(np.unique(unlit.part[torso])) >= 2  # two faces of the box seen at least
    assert np.all(unlit.part[unlit.instance == 7] == 0)
    assert np.all((unlit.depth[torso] > 3.0) & (unlit.depth[torso] < 4.5))

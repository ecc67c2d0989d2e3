"""Hair cards pass light through to their far side in Cycles (issue 14: long hair hanging
below the ears rendered darker than short hair of the same colour, its inner layers in
each other's shadow), while exporters still find the Principled BSDF."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest


def _hair_record(alpha: int = 255):
    from avatar.material import Material

    texture = np.full((8, 8, 4), 200, np.uint8)
    texture[..., 3] = alpha
    return Material("hair test", base_color_texture=texture, alpha_mode="MASK",
                    extras={"fabric": "hair"})  # fmt: skip


def _backlit_card(tmp_path, record, front: bool = False) -> float:
    """Mean linear brightness of a hair card seen from the side away from a sun behind
    it (a black world: only light through the card reaches the camera); ``front``: the
    sun behind the camera instead (only light the card reflects)."""
    import bpy

    from avatar.blender import materials, render

    mesh = bpy.data.meshes.new("card")
    mesh.from_pydata([(-1, 0, -1), (1, 0, -1), (1, 0, 1), (-1, 0, 1)], [], [(0, 1, 2, 3)])
    mesh.uv_layers.new(name="UVMap")
    mesh.uv_layers["UVMap"].data.foreach_set("uv", [0, 0.5, 1, 0.5, 1, 0.9, 0, 0.9])
    card = bpy.data.objects.new("card", mesh)
    card.data.materials.append(materials.material(record))
    scene = bpy.context.scene
    scene.collection.objects.link(card)
    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
    sun.data.energy = 3.0
    sun.rotation_euler = (math.pi / 2 if front else -math.pi / 2, 0, 0)  # towards -y: its back
    scene.collection.objects.link(sun)
    cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
    cam.location, cam.rotation_euler = (0, -4, 0), (math.pi / 2, 0, 0)
    scene.collection.objects.link(cam)
    scene.camera = cam
    if scene.world is None:
        scene.world = bpy.data.worlds.new("world")
    scene.world.color = (0, 0, 0)
    if scene.world.node_tree is not None:
        background = scene.world.node_tree.nodes.get("Background")
        if background is not None:
            background.inputs["Color"].default_value = (0, 0, 0, 1)
    path = render.render(tmp_path / "card.png", samples=4, resolution=16)
    image = bpy.data.images.load(str(path))
    pixels = np.array(image.pixels[:], np.float32).reshape(16, 16, 4)
    return float(pixels[6:10, 6:10, :3].mean())


def test_hair_card_lets_light_through(empty_scene, tmp_path):
    """A card lit from behind glows on the camera's side (an opaque Principled card is
    black there), and a cut-out card's gaps stay clear (nothing drawn)."""
    from avatar.blender import scene

    assert _backlit_card(tmp_path / "opaque", _hair_record()) > 0.1  # was 0.0005
    scene.clear_scene()
    assert _backlit_card(tmp_path / "clear", _hair_record(alpha=0)) < 0.01


def test_blond_hair_lit_from_the_front_reflects_its_colour(empty_scene, tmp_path):
    """A blond card lit from the front is as light as the same card without light
    through it (within 10 %): 0.7 times when the Translucent BSDF was mixed in, taking
    its share from the reflection (blond long hair rendered darker than before)."""
    from avatar.blender import scene
    from avatar.looks import fabrics

    record = _hair_record()
    record.base_color_texture[..., :3] = fabrics.srgb(fabrics.rgb("blond hair"))
    lit = _backlit_card(tmp_path / "translucent", record, front=True)
    scene.clear_scene()
    record = replace(record, extras={**record.extras, "translucency": 0.0})
    opaque = _backlit_card(tmp_path / "opaque", record, front=True)
    assert lit > 0.9 * opaque, lit / opaque


def test_hair_translucency_keeps_the_cut_out_and_the_exporters_view(empty_scene):
    from bpy_extras.node_shader_utils import PrincipledBSDFWrapper

    from avatar.blender import materials

    mat = materials.material(_hair_record())
    nodes = mat.node_tree.nodes
    bsdf = nodes["Principled BSDF"]
    outputs = {n.target: n for n in nodes if n.type == "OUTPUT_MATERIAL"}
    assert set(outputs) == {"ALL", "CYCLES"}
    assert outputs["ALL"].inputs["Surface"].links[0].from_node == bsdf
    cut = outputs["CYCLES"].inputs["Surface"].links[0].from_node
    assert cut.type == "MIX_SHADER"
    assert cut.inputs["Fac"].links[0].from_socket == bsdf.inputs["Alpha"].links[0].from_socket
    assert cut.inputs[1].links[0].from_node.type == "BSDF_TRANSPARENT"
    fibre = cut.inputs[2].links[0].from_node  # added: a share of the unreflected light
    assert fibre.type == "ADD_SHADER" and fibre.inputs[0].links[0].from_node == bsdf
    through = fibre.inputs[1].links[0].from_node
    assert through.type == "BSDF_TRANSLUCENT"
    scaled = through.inputs["Color"].links[0].from_node
    product = scaled.inputs[0].links[0].from_node
    tint, unreflected = (product.inputs[i].links[0].from_node for i in (0, 1))
    assert tint.inputs["Color"].links[0].from_node.type == "TEX_IMAGE"
    assert unreflected.operation == "SUBTRACT"
    assert tuple(unreflected.inputs[0].default_value) == (1, 1, 1)
    assert unreflected.inputs[1].links[0].from_node.type == "TEX_IMAGE"
    # The translucent colour stays within 0..1 (the hair's own to a power at most 1,
    # times what it does not reflect, times a share at most 1).
    share = scaled.inputs["Scale"].default_value
    assert not scaled.inputs["Scale"].links and 0 < share <= 1.0
    assert tint.type == "GAMMA" and 0 < tint.inputs["Gamma"].default_value <= 1.0
    assert PrincipledBSDFWrapper(mat, is_readonly=True).node_principled_bsdf == bsdf
    cloth = materials.material(_cloth())
    assert all(n.target == "ALL" for n in cloth.node_tree.nodes if n.type == "OUTPUT_MATERIAL")


def test_white_hair_sends_on_no_more_light_than_it_receives(empty_scene, tmp_path):
    """A white hair card in a white furnace (a uniform world of brightness 1 lights both
    sides, no other light) is at most as bright as the world: 1.29 when the Translucent
    BSDF in the hair's colour was added to the Principled BSDF (light reflected and passed
    through at once), 0.80 mixed, and added as a share of the light not reflected."""
    import bpy

    from avatar.blender import materials, render

    record = _hair_record()
    record.base_color_texture[..., :3] = 255
    furnace = bpy.data.scenes.new("furnace")  # a scene of its own: later tests keep theirs
    try:
        mesh = bpy.data.meshes.new("card")
        mesh.from_pydata([(-1, 0, -1), (1, 0, -1), (1, 0, 1), (-1, 0, 1)], [], [(0, 1, 2, 3)])
        mesh.uv_layers.new(name="UVMap")
        mesh.uv_layers["UVMap"].data.foreach_set("uv", [0, 0.5, 1, 0.5, 1, 0.9, 0, 0.9])
        card = bpy.data.objects.new("card", mesh)
        card.data.materials.append(materials.material(record))
        furnace.collection.objects.link(card)
        cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
        cam.location, cam.rotation_euler = (0, -4, 0), (math.pi / 2, 0, 0)
        furnace.collection.objects.link(cam)
        furnace.camera = cam
        furnace.world = bpy.data.worlds.new("white")
        if furnace.world.node_tree is None:  # Blender < 5: worlds start without nodes
            furnace.world.use_nodes = True
        background = furnace.world.node_tree.nodes["Background"]
        background.inputs["Color"].default_value = (1, 1, 1, 1)
        background.inputs["Strength"].default_value = 1.0
        render.configure(furnace, "CYCLES", 16, 16)
        furnace.view_settings.view_transform = "Standard"  # linear radiance, unclipped
        furnace.render.image_settings.file_format = "OPEN_EXR"
        tmp_path.mkdir(parents=True, exist_ok=True)
        furnace.render.filepath = str(tmp_path / "card.exr")
        bpy.ops.render.render(write_still=True, scene=furnace.name)
        image = bpy.data.images.load(str(tmp_path / "card.exr"))
        pixels = np.array(image.pixels[:], np.float32).reshape(16, 16, 4)
    finally:
        bpy.data.scenes.remove(furnace)
    brightness = float(pixels[6:10, 6:10, :3].mean())
    assert brightness <= 1.02, brightness


def _cloth():
    from avatar.material import Material

    return Material("cloth test", base_color_texture=np.full((8, 8, 3), 90, np.uint8))


@pytest.mark.slow
def test_long_hair_below_the_ears_is_not_dark(empty_scene, tmp_path):
    """Blond long hair hanging below the ears (below the lowest row of short hair of the
    same colour, seen from the side under the studio's lights) at least half as light as
    the short hair (L*): 0.44 when its cards were opaque and textured from the strands'
    dark roots, 0.53 with light through the cards and lighter inner layers."""
    from test_hair_lightness import _render

    short, short_hair = _render("hair-short", tmp_path)
    long_, long_hair = _render("hair-long", tmp_path)
    below = long_hair.copy()
    below[: np.nonzero(short_hair.any(axis=1))[0].max() + 1] = False
    assert below.sum() > 500
    ratio = long_[below].mean() / short[short_hair].mean()
    assert ratio > 0.49, ratio


def test_beard_passes_less_light_than_scalp_hair(empty_scene):
    """A beard's cards lie on the skin in one layer: little light through them (a grey
    beard's clumps lit from behind glowed white at scalp hair's translucency)."""
    from avatar.blender import materials
    from avatar.clothes.library import load_garment

    def amount(name):
        mat = materials.material(load_garment(name, texture_size=64).material)
        return mat.node_tree.nodes["Hair Translucency"].inputs["Scale"].default_value

    assert amount("beard-short") < 0.5 * amount("hair-short")

"""Dress > Variants & Outfits on the installed zip: a garment's colour/fabric swaps its
material only (geometry untouched, no orphan growth), round-trips through the recipe and a
fresh Human; outfits save, apply, delete, and bad ones change nothing."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest
from test_extension import _assert_matches_fresh_human, _assert_same_state, _state


def _part(root, name):
    from avatar.blender import live

    return live.part_objects(root)[name]


def _base_colour(obj) -> np.ndarray:
    """Mean RGB (0..1, as stored) of the base colour image of ``obj``'s material."""
    mat = obj.data.materials[0]
    bsdf = next(n for n in mat.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
    link = bsdf.inputs["Base Color"].links[0]
    node = link.from_node
    while node.type != "TEX_IMAGE":  # through any mix/tint node to the texture
        node = next(i.links[0].from_node for i in node.inputs if i.is_linked)
    image = node.image
    pixels = np.empty(len(image.pixels), np.float32)
    image.pixels.foreach_get(pixels)
    return pixels.reshape(-1, image.channels)[:, :3].mean(0)


def _counts():
    import bpy

    return len(bpy.data.materials), len(bpy.data.images), len(bpy.data.meshes)


def _outfit_folder():
    import bpy

    return bpy.utils.user_resource("CONFIG", path=os.path.join("avatar", "outfits"))


def test_the_sub_panel_and_operators_register(installed):  # noqa: F811
    import bpy

    assert bpy.types.AVATAR_PT_outfits.bl_parent_id == "AVATAR_PT_dress"
    for op in ("set_garment_colour", "save_outfit", "apply_outfit", "delete_outfit"):
        assert hasattr(bpy.ops.avatar, op)
    assert hasattr(bpy.types.Scene, "avatar_outfits")


def test_a_colour_swaps_the_material_only_and_round_trips(human):  # noqa: F811
    import bpy

    from avatar.blender import materials, mesh
    from avatar.human import Human

    assert bpy.ops.avatar.wear(name="tshirt") == {"FINISHED"}
    tshirt = _part(human, "tshirt")
    data, vertices = tshirt.data, mesh.read_vertices(tshirt).copy()
    white = _base_colour(tshirt)
    assert bpy.ops.avatar.set_garment_colour(name="tshirt", colour="navy") == {"FINISHED"}
    assert _part(human, "tshirt") is tshirt and tshirt.data is data  # no new object or mesh
    np.testing.assert_array_equal(mesh.read_vertices(tshirt), vertices)
    navy = _base_colour(tshirt)
    assert white.mean() > 0.8 and navy.mean() < 0.35 and navy[2] > navy[0]  # dark blue
    recipe = json.loads(human["avatar_recipe"])
    assert recipe["garment_options"] == {"tshirt": {"colour": "navy"}}
    fresh = Human.from_recipe(recipe)
    want = next(g for g in fresh.outfit.garments if g.name == "tshirt").material
    assert want.extras["colour"] == "navy"
    assert tshirt.data.materials[0]["avatar_key"] == materials.digest(want)  # the same look
    _assert_matches_fresh_human(human)
    # a custom colour and a fabric
    assert bpy.ops.avatar.set_garment_colour(name="tshirt", colour="#c04020",
                                             fabric="linen") == {"FINISHED"}  # fmt: skip
    rgb = _base_colour(tshirt)
    assert rgb[0] > rgb[1] > rgb[2]
    assert tshirt.data.materials[0].node_tree is not None
    assert json.loads(human["avatar_recipe"])["garment_options"]["tshirt"] == {
        "colour": "#c04020", "fabric": "linen"}  # fmt: skip
    # the look survives a body change and a rebuild (a rig change)
    human.avatar.weight = 0.7
    bpy.ops.avatar.settle()
    assert np.abs(_base_colour(_part(human, "tshirt")) - rgb).max() < 1e-6
    name = human.name
    human.avatar.rig = "game_engine"  # a new armature: the character is rebuilt
    human = bpy.data.objects[name]
    assert np.abs(_base_colour(_part(human, "tshirt")) - rgb).max() < 1e-6
    bpy.context.view_layer.objects.active = human
    # back to its own look
    bpy.ops.avatar.set_garment_colour(name="tshirt", colour="default", fabric="default")
    assert np.abs(_base_colour(_part(human, "tshirt")) - white).max() < 0.02
    assert "tshirt" not in json.loads(human["avatar_recipe"])["garment_options"]


def test_repeated_changes_grow_no_data(human):  # noqa: F811
    import bpy

    bpy.ops.avatar.wear(name="jeans")
    for colour in ("light indigo", "dark indigo"):  # the first cycle makes what it needs
        bpy.ops.avatar.set_garment_colour(name="jeans", colour=colour)
    before = _counts()
    for _ in range(5):
        for colour in ("light indigo", "dark indigo"):
            assert bpy.ops.avatar.set_garment_colour(name="jeans", colour=colour) == {"FINISHED"}
    assert _counts() == before
    orphans = [m.name for m in bpy.data.materials if m.users == 0 and "avatar_key" in m.keys()]
    assert orphans == []


def test_two_characters_share_one_material_per_variant(installed, assets, empty_scene):  # noqa: F811
    import bpy

    roots = []
    for x in (0.0, 1.5):
        bpy.context.scene.cursor.location = (x, 0, 0)
        bpy.ops.avatar.create_human(default_look=False)
        roots.append(bpy.context.view_layer.objects.active)
        bpy.ops.avatar.wear(name="tanktop")
        bpy.ops.avatar.set_garment_colour(name="tanktop", colour="red")
    a, b = (_part(r, "tanktop").data.materials[0] for r in roots)
    assert a == b


def test_bad_colours_are_reports_and_change_nothing(human):  # noqa: F811
    import bpy

    bpy.ops.avatar.wear(name="tshirt")
    before = _state(human)
    material = _part(human, "tshirt").data.materials[0]
    for kwargs, words in [({"name": "tshirt", "colour": "navvy"}, "navy"),
                          ({"name": "tshirt", "fabric": "leather"}, "cannot be made of"),
                          ({"name": "jeans", "colour": "red"}, "does not wear"),
                          ({"name": "tshirt"}, "choose a colour"),
                          ({"name": "tshirt", "colour": "#12345"}, "colour")]:  # fmt: skip
        with pytest.raises(RuntimeError, match=words):
            bpy.ops.avatar.set_garment_colour(**kwargs)
    _assert_same_state(before, _state(human))
    assert _part(human, "tshirt").data.materials[0] == material


def test_outfits_save_list_apply_delete(human):  # noqa: F811
    import bpy

    from avatar.blender import live

    panel = bpy.context.scene.avatar_outfits
    assert bpy.ops.avatar.apply_outfit(name="business") == {"FINISHED"}
    worn = json.loads(human["avatar_recipe"])["clothes"]
    assert worn == ["hair-short", "eyebrows", "eyelashes", "longsleeve", "trousers", "socks",
                    "shoes-black"]  # own looks kept, the outfit exactly  # fmt: skip
    assert set(live.part_objects(human)) >= set(worn)
    # (geometry vs a fresh Human is not compared here: worn shoes raise the body by their
    # sole in a fresh Human but not on a restyled character, a known gap of avatar.wear)
    bpy.ops.avatar.set_garment_colour(name="longsleeve", colour="sky")
    assert bpy.ops.avatar.save_outfit(name="Office Day") == {"FINISHED"}
    path = os.path.join(_outfit_folder(), "office_day.json")
    saved = json.loads(open(path).read())
    assert saved["options"]["longsleeve"] == {"colour": "sky", "fabric": "cotton"}
    assert "office_day" in _outfits().outfit_names()
    panel.outfit = "office_day"  # the panel's list offers it
    assert bpy.ops.avatar.apply_outfit(name="sport") == {"FINISHED"}
    assert "longsleeve" not in live.part_objects(human)
    assert bpy.ops.avatar.apply_outfit() == {"FINISHED"}  # the panel's choice: office_day
    recipe = json.loads(human["avatar_recipe"])
    assert recipe["clothes"] == worn
    assert recipe["garment_options"]["longsleeve"]["colour"] == "sky"
    assert set(live.part_objects(human)) - {"body", "eyes", "teeth", "tongue"} <= set(worn)
    rgb = _base_colour(_part(human, "longsleeve"))
    assert rgb[2] > rgb[0]  # sky blue, as saved
    # (geometry vs a fresh Human is not compared here: worn shoes raise the body by their
    # sole in a fresh Human but not on a restyled character, a known gap of avatar.wear)
    assert bpy.ops.avatar.delete_outfit(name="office_day") == {"FINISHED"}
    assert not os.path.exists(path) and "office_day" not in _outfits().outfit_names()


def test_bad_outfits_are_reports_and_change_nothing(human):  # noqa: F811
    import bpy

    folder = _outfit_folder()
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, "odd.json"), "w") as f:
        json.dump({"clothes": ["tshirt", "tshrt"]}, f)
    with open(os.path.join(folder, "red_shoes.json"), "w") as f:
        json.dump({"clothes": ["shoes"], "options": {"shoes": {"colour": "red"}}}, f)
    with open(os.path.join(folder, "broken.json"), "w") as f:
        f.write('{"clothes": ["tshirt",\n')
    with open(os.path.join(folder, "shape.json"), "w") as f:
        json.dump(["tshirt"], f)
    before = _state(human)
    for name, words in [("odd", "odd.json.*tshrt.*tshirt"), ("red_shoes", "no colour"),
                        ("broken", "broken.json:2: not JSON"), ("shape", "not an outfit"),
                        ("nobody", "no outfit 'nobody'")]:  # fmt: skip
        with pytest.raises(RuntimeError, match=words):
            bpy.ops.avatar.apply_outfit(name=name)
    with pytest.raises(RuntimeError, match="built-in"):
        bpy.ops.avatar.delete_outfit(name="casual")
    with pytest.raises(RuntimeError, match="no saved outfit"):
        bpy.ops.avatar.delete_outfit(name="nobody")
    with pytest.raises(RuntimeError, match="another outfit name"):
        bpy.ops.avatar.save_outfit(name="casual")
    _assert_same_state(before, _state(human))
    for name in ("odd", "red_shoes", "broken", "shape"):
        os.remove(os.path.join(folder, f"{name}.json"))


def test_every_builtin_outfit_dresses_a_character(human):  # noqa: F811
    import bpy

    from avatar.clothes import wardrobe

    for name, outfit in wardrobe.BUILTIN.items():
        assert bpy.ops.avatar.apply_outfit(name=name) == {"FINISHED"}
        worn = json.loads(human["avatar_recipe"])["clothes"]
        assert worn[3:] == list(outfit.clothes)
    # (geometry vs a fresh Human is not compared here: worn shoes raise the body by their
    # sole in a fresh Human but not on a restyled character, a known gap of avatar.wear)


def _outfits():
    """The installed add-on's panel_outfits module."""
    import sys

    return next(m for n, m in sys.modules.items() if n.endswith("avatar_addon.panel_outfits"))

"""Material records become node trees with the right pixels; exporters write files."""

from __future__ import annotations

import numpy as np
import pytest
from bridge_fixtures import figure


def test_material_node_tree_and_texture_pixels(empty_scene, rng):
    from avatar.blender import materials
    from avatar.material import Material

    colour = rng.integers(0, 256, size=(8, 4, 3), dtype=np.uint8)
    normal = np.full((4, 4, 3), 128, np.uint8)
    rough = rng.integers(0, 256, size=(4, 4), dtype=np.uint8)
    record = Material(
        "skin",
        base_color=(1.0, 1.0, 1.0, 1.0),  # white: the texture feeds the BSDF directly
        base_color_texture=colour,
        normal_texture=normal,
        roughness_texture=rough,
        extras={"subsurface": 0.2},
    )
    mat = materials.material(record)
    nodes = mat.node_tree.nodes
    bsdf = nodes["Principled BSDF"]
    assert bsdf.inputs["Base Color"].links[0].from_node.image.name == "skin colour"
    assert bsdf.inputs["Normal"].links[0].from_node.type == "NORMAL_MAP"
    assert bsdf.inputs["Roughness"].is_linked
    assert bsdf.inputs["Subsurface Weight"].default_value == pytest.approx(0.2)
    image = bsdf.inputs["Base Color"].links[0].from_node.image
    assert tuple(image.size) == (4, 8)
    pixels = np.empty(8 * 4 * 4, np.float32)
    image.pixels.foreach_get(pixels)
    top_row_first = pixels.reshape(8, 4, 4)[::-1, :, :3]
    np.testing.assert_allclose(top_row_first, colour / 255.0, atol=1 / 255)
    assert image.packed_file is not None
    multiply = bsdf.inputs["Roughness"].links[0].from_node  # texture x roughness factor 0.5
    assert multiply.inputs[1].default_value == pytest.approx(0.5)
    assert multiply.inputs[0].links[0].from_node.image.colorspace_settings.name == "Non-Color"


def test_scalar_material_and_none(empty_scene):
    from avatar.blender import materials
    from avatar.material import Material

    mat = materials.material(Material("cloth", base_color=(0.8, 0.5, 0.4, 1.0), roughness=0.45))
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    assert bsdf.inputs["Roughness"].default_value == pytest.approx(0.45)
    assert tuple(bsdf.inputs["Base Color"].default_value)[:3] == pytest.approx((0.8, 0.5, 0.4))
    assert materials.material(None, "grey").name == "grey"


def test_masked_alpha_and_tint(empty_scene):
    from avatar.blender import materials
    from avatar.material import Material

    cards = np.full((4, 4, 4), 200, np.uint8)
    record = Material("hair", base_color=(0.5, 0.4, 0.3, 1.0), base_color_texture=cards,
                      alpha_mode="MASK", double_sided=True)  # fmt: skip
    mat = materials.material(record)
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    assert bsdf.inputs["Alpha"].links[0].from_node.operation == "GREATER_THAN"
    # The tint is baked into the pixels: the image feeds Base Color directly (FBX keeps it).
    image_node = bsdf.inputs["Base Color"].links[0].from_node
    assert image_node.type == "TEX_IMAGE"
    pixels = np.empty(4 * 4 * 4, np.float32)
    image_node.image.pixels.foreach_get(pixels)
    srgb = 200 / 255
    linear = ((srgb + 0.055) / 1.055) ** 2.4 * np.array([0.5, 0.4, 0.3])
    expected = 1.055 * linear ** (1 / 2.4) - 0.055
    np.testing.assert_allclose(pixels.reshape(-1, 4)[:, :3], np.tile(expected, (16, 1)),
                               atol=1 / 255)  # fmt: skip
    assert pixels.reshape(-1, 4)[0, 3] == pytest.approx(200 / 255, abs=1e-6)  # alpha kept
    assert not mat.use_backface_culling


def test_equal_records_share_one_material_and_release_frees_it(empty_scene, rng):
    import bpy

    from avatar.blender import materials
    from avatar.material import Material

    texture = rng.integers(0, 256, size=(8, 8, 3), dtype=np.uint8)
    first = materials.material(Material("cloth", base_color_texture=texture))
    again = materials.material(Material("cloth", base_color_texture=texture.copy()))
    other = materials.material(Material("cloth", base_color_texture=255 - texture))
    assert again == first and other != first  # equal content: the same datablock
    assert len(bpy.data.images) == 2
    materials.release([first, other])  # nothing uses them: both go, with their images
    assert len(bpy.data.materials) == 0 and len(bpy.data.images) == 0


@pytest.mark.parametrize("suffix", [".fbx", ".usdc", ".blend"])
def test_export_writes_a_file(empty_scene, rng, tmp_path, suffix):
    from avatar.blender import export
    from avatar.blender.scene import build_character

    built = build_character(figure(rng))
    path = export.export(tmp_path / f"figure{suffix}", [built.root])
    assert path.stat().st_size > 1000


def test_export_rejects_unknown_suffix(empty_scene, tmp_path):
    from avatar.blender import export
    from avatar.errors import AvatarError

    with pytest.raises(AvatarError, match="cannot export"):
        export.export(tmp_path / "x.dae")

"""Hair materials become anisotropic fibre shaders in Blender: highlight stretched across
the strands (tangent along the cards' v), alpha cut from the card texture, roots duller."""

from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture(scope="module")
def hair_record():
    from avatar.clothes.library import load_garment

    return load_garment("hair-short", texture_size=64).material


def test_hair_material_is_anisotropic_along_the_strands(empty_scene, hair_record):
    from avatar.blender import materials

    mat = materials.material(hair_record)
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    assert bsdf.inputs["Anisotropic"].default_value > 0.5
    # u is across the strands: a quarter turn puts the tangent along them.
    assert bsdf.inputs["Anisotropic Rotation"].default_value == pytest.approx(0.25)
    tangent = bsdf.inputs["Tangent"].links[0].from_node
    assert tangent.type == "TANGENT" and tangent.direction_type == "UV_MAP"
    assert tangent.uv_map == "UVMap"
    # Alpha cut out from the texture's alpha (MASK: a threshold node in between).
    alpha = bsdf.inputs["Alpha"].links[0].from_node
    assert alpha.type == "MATH" and alpha.operation == "GREATER_THAN"
    assert alpha.inputs[0].links[0].from_node.image is not None
    # Base colour straight from the image (FBX/USD follow only that link), specular tinted.
    colour = bsdf.inputs["Base Color"].links[0].from_node
    assert colour.type == "TEX_IMAGE"
    # The highlight tinted by a light version of the colour (a power under one): tinted
    # by the colour itself, dark hair had no highlight at all.
    tint = bsdf.inputs["Specular Tint"].links[0].from_node
    assert tint.type == "GAMMA" and tint.inputs["Color"].links[0].from_node == colour
    assert 0.03 ** tint.inputs["Gamma"].default_value > 0.3
    assert bsdf.inputs["Sheen Weight"].default_value > 0
    # Duller at the roots (v = 0.5) than at the tips (v = 0).
    fade = bsdf.inputs["Specular IOR Level"].links[0].from_node
    assert fade.type == "MAP_RANGE"
    assert fade.inputs["To Max"].default_value < fade.inputs["To Min"].default_value


def test_only_hair_gets_fibre_shading(empty_scene, hair_record):
    from avatar.blender import materials
    from avatar.clothes.library import load_garment
    from avatar.material import Material

    cloth = materials.material(load_garment("tshirt", texture_size=64).material)
    brows = materials.material(load_garment("eyebrows", texture_size=64).material)
    for mat in (cloth, brows):
        bsdf = mat.node_tree.nodes["Principled BSDF"]
        assert bsdf.inputs["Anisotropic"].default_value == 0
        assert not bsdf.inputs["Tangent"].is_linked
    hinted = Material("fur", base_color_texture=np.zeros((4, 4, 4), np.uint8),
                      alpha_mode="MASK", extras={"anisotropy": 0.4})  # fmt: skip
    bsdf = materials.material(hinted).node_tree.nodes["Principled BSDF"]
    assert bsdf.inputs["Anisotropic"].default_value == pytest.approx(0.4)
    assert materials.is_hair(hair_record)
    assert materials.is_hair(load_garment("eyelashes", texture_size=64).material)

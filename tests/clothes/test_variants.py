"""Fabric and colour variants of built-in garments: a material of their own, the same geometry,
kept in recipes (JSON and .mhm) so a fresh Human looks the same."""

from __future__ import annotations

import json

import numpy as np
import pytest

from avatar.clothes import library, variants
from avatar.errors import AvatarError, ParameterError
from avatar.human import Human, Recipe
from avatar.io import mhm
from avatar.looks import fabrics

SIZE = 64  # small textures: these tests check colours, not detail


def _mean_rgb(material) -> np.ndarray:
    tex = material.base_color_texture
    return tex[..., :3].reshape(-1, 3).mean(0)


def _srgb_byte(linear) -> np.ndarray:
    return fabrics.srgb(np.asarray(linear, np.float32)).astype(np.float64)


def test_a_colour_variant_shares_the_geometry_and_has_its_own_colour():
    plain = library.load_garment("tshirt", texture_size=SIZE)
    navy = library.load_garment("tshirt", texture_size=SIZE, options={"colour": "navy"})
    assert navy.mesh is plain.mesh and navy.binding is plain.binding  # no geometry rebuilt
    assert navy.material is not plain.material
    assert navy.material.extras["colour"] == "navy"
    assert np.abs(_mean_rgb(navy.material) - _srgb_byte(fabrics.COLOURS["navy"])).max() < 12
    assert np.abs(_mean_rgb(plain.material) - _srgb_byte(fabrics.COLOURS["white"])).max() < 12
    again = library.load_garment("tshirt", texture_size=SIZE, options={"colour": "navy"})
    assert again.material is navy.material  # made once per (garment, variant)


def test_a_custom_colour_is_an_srgb_hex_code():
    g = library.load_garment("tanktop", texture_size=SIZE, options={"colour": "#C04020"})
    mean = _mean_rgb(g.material)
    assert np.abs(mean - np.array([0xC0, 0x40, 0x20])).max() < 15
    assert variants.check("tanktop", {"colour": "#C04020"}) == {"colour": "#c04020"}


def test_default_options_give_the_garment_itself():
    plain = library.load_garment("tshirt", texture_size=SIZE)
    same = library.load_garment("tshirt", texture_size=SIZE, options={"colour": "white"})
    assert same is plain


def test_fabric_variants_change_the_weave():
    plain = library.load_garment("tshirt", texture_size=SIZE)
    linen = library.load_garment("tshirt", texture_size=SIZE, options={"fabric": "linen"})
    assert linen.material.extras["fabric"] == "linen" and linen.mesh is plain.mesh
    assert not np.array_equal(linen.material.normal_texture, plain.material.normal_texture)
    assert "linen" in variants.fabric_choices("tshirt")
    assert variants.fabric_choices("jeans")[0] == "denim"


def test_light_and_dark_denim_jeans_keep_their_tailoring():
    light = library.load_garment("jeans", texture_size=SIZE, options={"colour": "light indigo"})
    dark = library.load_garment("jeans", texture_size=SIZE, options={"colour": "dark indigo"})
    assert light.mesh is dark.mesh
    assert _mean_rgb(light.material).mean() > _mean_rgb(dark.material).mean() + 20


def test_hair_colour_variants():
    blond = library.load_garment("hair-short", texture_size=SIZE, options={"colour": "blond hair"})
    plain = library.load_garment("hair-short", texture_size=SIZE)
    assert blond.material.alpha_mode == plain.material.alpha_mode
    assert _mean_rgb(blond.material).mean() > _mean_rgb(plain.material).mean()
    assert "blond hair" in variants.colours("hair-short")


@pytest.mark.parametrize("name, options, words", [
    ("tshirt", {"colour": "navvy"}, "navy"),
    ("tshirt", {"fabric": "leather"}, "linen"),
    ("tshirt", {"pattern": "stripes"}, "unknown garment option"),
    ("tshirt", {"colour": 3}, "must be a text"),
    ("shoes", {"colour": "red"}, "no colour or fabric variants"),
])  # fmt: skip
def test_bad_options_are_parameter_errors(name, options, words):
    with pytest.raises(ParameterError, match=words):
        library.load_garment(name, texture_size=SIZE, options=options)


def test_recipes_keep_options_and_old_recipes_still_load():
    old = {"version": 2, "params": {}, "rig": "default", "clothes": ["tshirt"]}
    assert Recipe.from_dict(old).garment_options == {}
    recipe = Recipe(clothes=("tshirt", "jeans"),
                    garment_options={"tshirt": {"colour": "navy"}, "cap": {"colour": "red"}})
    data = json.loads(json.dumps(recipe.to_dict()))
    assert data["garment_options"] == {"tshirt": {"colour": "navy"}}  # only what is worn
    assert Recipe.from_dict(data).garment_options == {"tshirt": {"colour": "navy"}}
    with pytest.raises(ParameterError):
        Recipe.from_dict({**data, "garment_options": ["tshirt"]})


def test_a_human_checks_its_options_up_front():
    with pytest.raises(AvatarError, match="colour"):
        Human.from_recipe({"clothes": ["tshirt"], "garment_options": {"tshirt": {"colour": "x"}}})


def test_a_fresh_human_and_an_mhm_round_trip_give_the_same_look(tmp_path):
    recipe = {"clothes": ["tshirt", "jeans"],
              "garment_options": {"tshirt": {"colour": "#204060", "fabric": "linen"}}}
    human = Human.from_recipe(recipe)
    again = Human.from_recipe(json.loads(json.dumps(human.to_recipe())))
    path = tmp_path / "navy.mhm"
    mhm.write(path, human.to_mhm())
    assert "avatar-garment tshirt" in path.read_text()
    loaded = Human.from_mhm(path)
    assert loaded.recipe.garment_options == {"tshirt": {"colour": "#204060", "fabric": "linen"}}
    assert all(k != "avatar-garment" for k, _ in loaded.recipe.mhm)  # read, not kept twice
    want = library.load_garment("tshirt", options={"colour": "#204060", "fabric": "linen"})
    for h in (human, again, loaded):
        tshirt = next(g for g in h.outfit.garments if g.name == "tshirt")
        assert tshirt.material.extras == want.material.extras
        assert np.array_equal(tshirt.material.base_color_texture,
                              want.material.base_color_texture)

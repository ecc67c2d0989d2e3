"""MakeHuman 1.1 ``.mhm`` files: every statement MakeHuman writes survives read -> write, line
for line, through the format alone and through a Human (its recipe and looks)."""

from __future__ import annotations

import json

import pytest

import avatar
from avatar.clothes import library
from avatar.errors import FormatError, ParameterError
from avatar.human import Human, Recipe
from avatar.io import mhm

# A MakeHuman 1.1 character wearing the CC0 fixture assets by MakeHuman's uuids, with eyes,
# eye and skin materials, a pose and an expression, in the order MakeHuman 1.1 writes them.
MAKEHUMAN_FILE = """\
# Written by MakeHuman 1.1.1
version v1.1.1
name Ada
tags ada female casual
camera 0.0 0.0 0.0 0.0 0.0 1.0
modifier breast/BreastSize 0.620000
modifier breast/BreastFirmness 0.500000
modifier macrodetails/Gender 0.000000
modifier macrodetails/Age 0.500000
modifier macrodetails/African 0.000000
modifier macrodetails/Asian 0.000000
modifier macrodetails/Caucasian 1.000000
modifier macrodetails-universal/Muscle 0.500000
modifier macrodetails-universal/Weight 0.500000
modifier macrodetails-height/Height 0.500000
modifier macrodetails-proportions/BodyProportions 0.500000
modifier nose/nose-scale-horiz-decr|incr -0.200000
skeleton game_engine.mhskel
eyebrows eyebrow001 9c81ec3a-faa5-4c94-9cdb-992300ba3084
eyes HighPolyEyes 2c12f43b-1303-432c-b7ce-d78346baf2e6
hair short02 c104cd4a-1edc-43f9-8b94-f63345a44638
eyelashes Eyelashes01 d533836f-13ad-4836-8b65-051108253cd2
clothesHideFaces True
clothes female_casualsuit01 a8b0e841-144b-4f03-8b9e-ea8fdce8c863
pose standing01.bvh
expression expressions/smile01.mhpose
skinMaterial skins/young_caucasian_female/young_caucasian_female.mhmat
material HighPolyEyes 2c12f43b-1303-432c-b7ce-d78346baf2e6 eyes/materials/lightblue.mhmat
material eyebrow001 9c81ec3a-faa5-4c94-9cdb-992300ba3084 eyebrow001.mhmat
subdivide False
"""


def _statements(text: str) -> list[str]:
    return [s.strip() for s in text.splitlines() if s.strip() and not s.startswith("#")]


def test_format_round_trips_every_makehuman_line():
    character = mhm.loads(MAKEHUMAN_FILE)
    assert _statements(mhm.dumps(character)) == _statements(MAKEHUMAN_FILE)
    assert character.rig == "game_engine" and character.name == "Ada"
    assert [p.kind for p in character.proxies] == ["eyebrows", "eyes", "hair", "eyelashes",
                                                   "clothes"]  # fmt: skip
    hair = mhm.ProxyRef("hair", "short02", "c104cd4a-1edc-43f9-8b94-f63345a44638")
    assert character.proxy("hair") == hair
    assert character.flags == {"clothesHideFaces": True, "subdivide": False}
    assert character.text["pose"] == "standing01.bvh"


@pytest.fixture
def assets(fixtures, monkeypatch):
    """The MakeHuman fixture assets as the user's clothes folder."""
    folder = fixtures / "makehuman"
    monkeypatch.setenv(library.ENV_PATH, str(folder))
    return folder


def test_human_round_trips_a_makehuman_file_line_for_line(assets, tmp_path, model):
    source = tmp_path / "ada.mhm"
    source.write_text(MAKEHUMAN_FILE)
    human = avatar.load(source)
    r = human.recipe
    # The looks are understood, not only kept: worn assets by uuid, eyes, skin, pose.
    worn = [library.entry_of(c).name for c in r.clothes]
    assert worn == ["eyebrow001", "short02", "Eyelashes01", "female_casualsuit01"]
    assert r.eye_material == "eyes/materials/lightblue.mhmat" and human.eye_colour == "blue"
    assert r.skin_material.endswith("young_caucasian_female.mhmat")
    assert (r.pose, r.expression) == ("standing01.bvh", "expressions/smile01.mhpose")
    assert r.hide_covered is True and r.rig == "game_engine" and r.name == "Ada"
    out = avatar.save(human, tmp_path / "again.mhm")
    assert _statements(out.read_text()) == _statements(MAKEHUMAN_FILE)
    # Through the recipe's JSON (the Blender extension's store) too.
    again = Human.from_recipe(json.loads(json.dumps(human.to_recipe())), model)
    assert _statements(mhm.dumps(again.to_mhm())) == _statements(MAKEHUMAN_FILE)


def test_assets_resolve_by_uuid_before_name_and_from_folders(fixtures, monkeypatch, tmp_path):
    monkeypatch.delenv(library.ENV_PATH, raising=False)
    folder = fixtures / "makehuman"
    by_uuid = library.find_reference("renamed", "c104cd4a-1edc-43f9-8b94-f63345a44638", [folder])
    assert by_uuid is not None and by_uuid.endswith("short02.mhclo")
    by_name = library.find_reference("short02", "", [folder])
    assert by_name == by_uuid
    assert library.find_reference("short02", "") is None  # not without the folder
    # Built-ins have fixed uuids and are written and found as MakeHuman assets are.
    hair = library.entry_of("hair-long")
    assert library.mhm_kind(hair) == "hair" and hair.uuid == library.builtin_uuid("hair-long")
    assert library.find_reference("anything", hair.uuid) == "hair-long"
    assert library.mhm_kind(library.entry_of("eyebrows-blond")) == "eyebrows"
    assert library.mhm_kind(library.entry_of("eyelashes")) == "eyelashes"
    assert library.mhm_kind(library.entry_of("jeans")) == "clothes"
    source = tmp_path / "c.mhm"
    source.write_text(MAKEHUMAN_FILE)
    recipe = Recipe.from_mhm(source, folders=[folder])
    assert len(recipe.clothes) == 4 and recipe.folders == (str(folder),)


def test_assets_not_found_are_kept_in_the_file_not_worn(tmp_path, monkeypatch, model, caplog):
    monkeypatch.delenv(library.ENV_PATH, raising=False)
    source = tmp_path / "c.mhm"
    source.write_text(MAKEHUMAN_FILE)
    human = Human.from_mhm(source, model)
    assert human.recipe.clothes == ()
    assert "short02" in caplog.text and "not worn" in caplog.text
    out = avatar.save(human, tmp_path / "again.mhm")
    assert sorted(_statements(out.read_text())) == sorted(_statements(MAKEHUMAN_FILE))


def test_avatar_humans_write_makehuman_lines(model):
    human = Human({"gender": 1.0}, model=model).dressed("hair-long", "eyebrows", "tshirt",
                                                         "eyelashes")  # fmt: skip
    lines = _statements(mhm.dumps(human.to_mhm("me")))
    assert f"hair hair-long {library.builtin_uuid('hair-long')}" in lines
    assert f"eyebrows eyebrows {library.builtin_uuid('eyebrows')}" in lines
    assert f"clothes tshirt {library.builtin_uuid('tshirt')}" in lines
    assert "eyes HighPolyEyes 2c12f43b-1303-432c-b7ce-d78346baf2e6" in lines
    assert "skinMaterial skins/default.mhmat" in lines and lines[-1] == "subdivide False"
    assert not any(line.startswith("clothesHideFaces") for line in lines)  # Avatar's default
    back = mhm.loads("\n".join(lines))
    assert [p.name for p in back.clothes] == ["tshirt"]


def test_two_hairs_write_the_second_as_clothes(model):
    human = Human(model=model).dressed("hair-long", "hair-short")
    kinds = [p.kind for p in human.to_mhm().proxies if p.kind != "eyes"]
    assert kinds == ["hair", "clothes"]


@pytest.mark.parametrize("line,message", [
    ("clothesHideFaces maybe", "True or False"),
    ("hair", "<name> <uuid>"),
    ("clothes a b c", "<name> <uuid>"),
    ("material HighPolyEyes 2c12", "material"),
    ("hair a 1\nhair b 2", "second 'hair'"),
])  # fmt: skip
def test_bad_statements_name_the_line(line, message):
    with pytest.raises(FormatError, match=message) as info:
        mhm.loads(f"version v1.1.1\n{line}\n", "c.mhm")
    assert info.value.line >= 2 and "c.mhm" in str(info.value)


def test_recipe_dict_is_versioned():
    old = {"version": 1, "params": {"gender": 1.0}, "rig": "default", "pose": None,
           "clothes": ["tshirt"], "motion": None}  # fmt: skip
    recipe = Recipe.from_dict(old)  # version 1 dicts (stored in .blend files) still load
    assert recipe.clothes == ("tshirt",) and recipe.hide_covered is None
    assert Recipe.from_dict(json.loads(json.dumps(recipe.to_dict()))) == recipe
    with pytest.raises(ParameterError, match="version"):
        Recipe.from_dict({"version": 99})
    with pytest.raises(ParameterError, match="unknown recipe fields"):
        Recipe.from_dict({"colour": 1})

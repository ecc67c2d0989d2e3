"""Outfits as files: built-ins are valid, files round-trip, bad files name the problem,
wearing one keeps the character's own looks unless the outfit replaces them."""

from __future__ import annotations

import json

import pytest

from avatar.clothes import wardrobe
from avatar.errors import AvatarError, FormatError

LOOKS = ["hair-short", "eyebrows", "eyelashes"]


@pytest.mark.parametrize("name", sorted(wardrobe.BUILTIN))
def test_builtin_outfits_are_valid(name):
    outfit = wardrobe.BUILTIN[name]
    assert wardrobe.check(outfit, where=name) == outfit
    assert set(wardrobe.BUILTIN) >= {"casual", "business", "sport", "winter"}


def test_save_and_load_round_trip(tmp_path):
    outfit = wardrobe.Outfit(("tshirt", "jeans"), {"tshirt": {"colour": "#AABBCC"}})
    path = wardrobe.save(tmp_path / "sub" / "mine.json", outfit)
    loaded = wardrobe.load(path)
    assert loaded.clothes == ("tshirt", "jeans")
    assert loaded.options == {"tshirt": {"colour": "#aabbcc"}}
    assert not list(tmp_path.glob("sub/*.tmp"))


@pytest.mark.parametrize("content, error, words", [
    ('{"clothes": ["tshirt", "tshrt"]}', AvatarError, "bad.json: .*tshrt.*tshirt"),
    ('{"clothes": ["tshirt"], "options": {"jeans": {"colour": "red"}}}', AvatarError,
     "does not list: jeans"),
    ('{"clothes": ["tshirt"], "options": {"tshirt": {"colour": "plaid"}}}', AvatarError,
     "colour"),
    ('{"clothes": ["tshirt",\n', FormatError, "bad.json:2: not JSON"),
    ('["tshirt"]', FormatError, "not an outfit"),
    ('{"clothes": [1]}', FormatError, "garment names"),
    ('{"clothes": [], "hats": []}', FormatError, "unknown outfit fields: hats"),
])  # fmt: skip
def test_bad_files_are_one_line_errors(tmp_path, content, error, words):
    path = tmp_path / "bad.json"
    path.write_text(content)
    with pytest.raises(error, match=words) as caught:
        wardrobe.load(path)
    assert "\n" not in str(caught.value)


def test_wearing_an_outfit_takes_off_the_rest_but_keeps_own_looks():
    clothes, options = wardrobe.wear(LOOKS + ["hoodie", "cap"],
                                     {"hair-short": {"colour": "blond hair"},
                                      "hoodie": {"colour": "red"}},
                                     wardrobe.BUILTIN["casual"])  # fmt: skip
    assert clothes == LOOKS + ["tshirt", "jeans", "socks", "sneakers"]
    assert options == {"hair-short": {"colour": "blond hair"}, "tshirt": {"colour": "navy"}}


def test_an_outfit_with_hair_replaces_the_hair():
    outfit = wardrobe.Outfit(("hair-long", "dress"), {"hair-long": {"colour": "black hair"}})
    clothes, options = wardrobe.wear(LOOKS, {}, outfit)
    assert clothes == ["eyebrows", "eyelashes", "hair-long", "dress"]
    assert options == {"hair-long": {"colour": "black hair"}}


def test_names_are_made_file_safe():
    assert wardrobe.clean_name(" Office Day! ") == "office_day"
    assert wardrobe.clean_name("../..") == ""
    assert json.loads(json.dumps(wardrobe.BUILTIN["sport"].to_dict()))["clothes"][0] == "tanktop"

"""The user's MakeHuman/MPFB skins (``looks.skin_library``): textured ones listed with
their thumbnails, untextured and broken ones left out."""

from __future__ import annotations

import numpy as np

from avatar.io import png
from avatar.looks.skin_library import list_skins


def _skin(folder, name, texture=True, text=None):
    folder.mkdir(parents=True)
    if texture:
        png.write(folder / f"{name}_diffuse.png", np.zeros((8, 8, 3), np.uint8))
    (folder / f"{name}.mhmat").write_text(
        text if text is not None else f"name {name}\ndiffuseTexture {name}_diffuse.png\n")
    return folder / f"{name}.mhmat"


def test_textured_skins_are_listed_with_thumbnails_and_the_rest_left_out(tmp_path):
    data = tmp_path / "makehuman" / "data"
    young = _skin(data / "skins" / "young", "young")
    png.write(young.with_suffix(".thumb"), np.zeros((8, 8, 3), np.uint8))
    old = _skin(data / "skins" / "old", "old")
    (data / "skins" / "default.mhmat").write_text("name default\ndiffuseColor 1 1 1\n")
    _skin(data / "skins" / "lost", "lost", texture=False)  # its texture is missing
    _skin(data / "skins" / "bad", "bad", text="diffuseColor not a colour\n")
    _skin(data / "clothes" / "shirt", "shirt")  # a garment's material, not a skin
    skins = list_skins([data, data / "skins"])  # each found once
    assert [(s.name, s.path) for s in skins] == [("old", str(old)), ("young", str(young))]
    assert skins[1].thumbnail == str(young.with_suffix(".thumb")) and skins[0].thumbnail is None


def test_a_clothes_folder_finds_its_sibling_skins(tmp_path):
    data = tmp_path / "data"
    (data / "clothes").mkdir(parents=True)
    young = _skin(data / "skins" / "young", "young")
    assert [s.path for s in list_skins([data / "clothes"])] == [str(young)]
    assert list_skins([tmp_path / "missing"]) == []

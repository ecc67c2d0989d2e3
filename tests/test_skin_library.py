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
    assert skins[1].thumbnail == str(young.with_suffix(".thumb"))
    assert skins[0].thumbnail == str(old.parent / "old_diffuse.png")  # no picture: its texture


def test_a_clothes_folder_finds_its_sibling_skins(tmp_path):
    data = tmp_path / "data"
    (data / "clothes").mkdir(parents=True)
    young = _skin(data / "skins" / "young", "young")
    assert [s.path for s in list_skins([data / "clothes"])] == [str(young)]
    assert list_skins([tmp_path / "missing"]) == []


def test_create_wears_a_skin_by_name_and_eyes_and_refuses_an_unknown_one(tmp_path, capsys):
    """``avatar create --skin NAME --eyes blue``: the recipe (and its .mhm) names the skin
    found in the asset folders; an unknown name or an untextured file is one line naming
    close matches or the file, and nothing is written."""
    from avatar import cli
    from avatar.io import mhm

    young = _skin(tmp_path / "assets" / "skins" / "young", "young")
    out = tmp_path / "a.mhm"
    folder = str(tmp_path / "assets")
    assert cli.main(["create", "--skin", "young", "--eyes", "blue", "--folder", folder,
                     "-o", str(out)]) == 0  # fmt: skip
    text = mhm.read(out).text
    assert text["skinMaterial"] == str(young), text
    assert "blue" in out.read_text()
    lost = _skin(tmp_path / "lost", "lost", texture=False)
    for bad, named in (("yong", "young"), (str(lost), "lost_diffuse.png"),
                       (str(tmp_path / "none.mhmat"), "none.mhmat")):  # fmt: skip
        bad_out = tmp_path / "b.mhm"
        assert cli.main(["create", "--skin", bad, "--folder", folder, "-o", str(bad_out)]) == 1
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and named in err[0] and "Traceback" not in err[0], err
        assert not bad_out.exists()

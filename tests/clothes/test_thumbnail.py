"""Library pictures (``clothes.thumbnail``): each item drawn as worn, in its own colours and
cut-outs, framed on itself; what a fabric swatch could not show (sleeves, a shoe's profile)
is measured on the picture."""

from __future__ import annotations

import numpy as np
import pytest

from avatar.body.model import BodyModel
from avatar.body.shaped import default_body
from avatar.clothes import thumbnail


@pytest.fixture(scope="module")
def human():
    """The default body (the pictures' wearer)."""
    return default_body(BodyModel.shared())


@pytest.fixture(scope="module")
def pictures(human):
    names = ("tshirt", "tanktop", "jeans", "skirt", "shoes", "eyelashes")
    return {name: thumbnail.garment_picture(name, 96, human) for name in names}


def _cloth(image: np.ndarray) -> np.ndarray:
    """The item's own pixels: opaque (the body is a half-transparent ghost)."""
    return image[..., 3] == 255


def _extent(mask: np.ndarray) -> tuple[int, int]:
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    return cols[-1] - cols[0] + 1, rows[-1] - rows[0] + 1


def test_pictures_are_rgba_with_a_clear_background_and_a_ghost_body(pictures):
    for name, image in pictures.items():
        assert image.shape == (96, 96, 4) and image.dtype == np.uint8, name
        assert _cloth(image).sum() > 40, name
    for name in ("tshirt", "jeans", "shoes"):
        assert (pictures[name][..., 3] == 0).sum() > 500, name  # a clear background
    ghost = (pictures["tshirt"][..., 3] > 90) & (pictures["tshirt"][..., 3] < 160)
    assert ghost.sum() > 200  # the neck and arms, half transparent


def test_a_tshirt_shows_its_sleeves_and_a_tank_top_none(pictures):
    wide = [w / h for w, h in map(_extent, (_cloth(pictures[n]) for n in ("tshirt", "tanktop")))]
    assert wide[0] > 1.25 * wide[1], wide


def test_pictures_take_the_items_colours_from_its_textures(pictures):
    jeans = pictures["jeans"][_cloth(pictures["jeans"])][:, :3].astype(float).mean(axis=0)
    skirt = pictures["skirt"][_cloth(pictures["skirt"])][:, :3].astype(float).mean(axis=0)
    assert jeans[2] > 1.3 * jeans[0], jeans  # denim blue
    assert skirt[0] > 2 * skirt[2], skirt  # red


def test_shoes_are_drawn_in_profile(pictures):
    """One shoe from the side: one run of columns, longer than high (seen from the front
    the two shoes were two blobs with floor between them)."""
    mask = _cloth(pictures["shoes"])
    columns = np.flatnonzero(mask.sum(axis=0) >= 2)
    assert np.all(np.diff(columns) == 1), columns
    width, height = _extent(mask)
    assert width > 1.6 * height, (width, height)


def test_alpha_cut_items_show_their_strands_not_their_cards(human, monkeypatch, pictures):
    cut = _cloth(pictures["eyelashes"]).sum()
    monkeypatch.setattr(thumbnail, "_cutoff", lambda material: -1.0)
    cards = _cloth(thumbnail.garment_picture("eyelashes", 96, human)).sum()
    assert cut < 0.8 * cards, (cut, cards)


def test_pictures_are_written_atomically_where_the_extension_looks(tmp_path, monkeypatch, human):
    monkeypatch.setenv("AVATAR_CACHE", str(tmp_path))
    (tmp_path / "thumbnails").mkdir()
    older = tmp_path / "thumbnails" / "cap-32-0123456789ab.png"  # another version's picture
    older.write_bytes(b"old")
    path = thumbnail.write_picture("cap", 32, body=human)
    assert path == thumbnail.picture_path("cap", 32) and path.parent == tmp_path / "thumbnails"
    from PIL import Image

    with Image.open(path) as image:
        assert image.size == (32, 32) and image.mode == "RGBA"
    assert [p.name for p in path.parent.iterdir()] == [path.name]  # no temporary, no old


def test_cli_writes_pictures_and_a_bad_name_writes_none(tmp_path, capsys):
    from avatar import cli

    out = tmp_path / "pictures"
    assert cli.main(["clothes", "thumbnails", "cap", "sneakers", "--out", str(out),
                     "--size", "48"]) == 0  # fmt: skip
    assert sorted(p.name for p in out.iterdir()) == ["cap.png", "sneakers.png"]
    bad = tmp_path / "bad"
    assert cli.main(["clothes", "thumbnails", "cap", "sneakrs", "--out", str(bad)]) == 1
    assert cli.main(["clothes", "thumbnails", "cap", "--size", "4", "--out", str(bad)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert "sneakers" in err[-2] and "--size" in err[-1] and len(err) == 2  # one line each
    assert not bad.exists()


def test_missing_draws_only_what_is_not_cached(tmp_path, monkeypatch, capsys):
    from avatar import cli

    monkeypatch.setenv("AVATAR_CACHE", str(tmp_path))
    thumbnail.write_picture("cap")
    assert cli.main(["clothes", "thumbnails", "cap", "socks", "--missing"]) == 0
    wrote = capsys.readouterr().out
    assert "socks" in wrote and "cap" not in wrote


def test_large_faces_are_covered_without_pinholes(human):
    """An opaque garment's picture at the grid's size has no single-pixel holes: a face is
    sampled densely enough for the frame (sampled more sparsely, shorts and a skirt drew
    as dotted grids)."""
    for name in ("skirt", "shorts"):
        cloth = _cloth(thumbnail.garment_picture(name, thumbnail.SIZE, human))
        inner = cloth[:-2, 1:-1] & cloth[2:, 1:-1] & cloth[1:-1, :-2] & cloth[1:-1, 2:]
        holes = inner & ~cloth[1:-1, 1:-1]
        assert holes.sum() <= 0.002 * cloth.sum(), (name, int(holes.sum()))


@pytest.fixture
def user_suit(fixtures, tmp_path):
    """A MakeHuman CC0 garment copied without its ``.thumb`` (a user's own garment)."""
    import shutil

    source = fixtures / "makehuman" / "clothes" / "female_casualsuit01"
    folder = tmp_path / "assets" / "suit"
    shutil.copytree(source, folder, ignore=shutil.ignore_patterns("*.thumb"))
    return folder / "female_casualsuit01.mhclo"


def test_a_user_garment_without_a_thumb_is_drawn_in_its_own_texture(user_suit, human):
    """A MakeHuman garment with no ``.thumb`` showed a plain button in the Dress grid; it is
    now drawn as worn, like a built-in, in the colours of its own diffuse texture."""
    from PIL import Image

    image = thumbnail.garment_picture(str(user_suit), 96, human)
    cloth = _cloth(image)
    width, height = _extent(cloth)
    assert cloth.sum() > 800 and height > 1.8 * width, (cloth.sum(), width, height)  # a suit
    with Image.open(user_suit.parent / "female_casualsuit01_diffuse.png") as texture:
        texels = np.asarray(texture.convert("RGB"), dtype=float).reshape(-1, 3)
    drawn = image[cloth][:, :3].astype(float).mean(axis=0)
    own = texels.mean(axis=0)
    assert own[2] > 1.3 * own[0] and drawn[2] > 1.3 * drawn[0], (drawn, own)  # blue shirt, jeans


def test_a_user_garments_picture_is_named_for_its_file_and_its_state(user_suit, tmp_path,
                                                                     monkeypatch):  # fmt: skip
    """Two folders' garments of one name get two pictures; editing the asset (its mesh,
    material or textures) draws a new one; a built-in's name is unchanged."""
    import os
    import shutil

    monkeypatch.setenv("AVATAR_CACHE", str(tmp_path / "cache"))
    other = tmp_path / "other" / "suit"
    shutil.copytree(user_suit.parent, other)
    first = thumbnail.picture_path(str(user_suit))
    assert first.name.startswith("user-female_casualsuit01-") and first.parent.name == "thumbnails"
    assert thumbnail.picture_path(str(other / user_suit.name)) != first
    texture = user_suit.parent / "female_casualsuit01_diffuse.png"
    os.utime(texture, ns=(texture.stat().st_atime_ns, texture.stat().st_mtime_ns + 10**9))
    assert thumbnail.picture_path(str(user_suit)) != first
    assert thumbnail.picture_path("tshirt").name.startswith("tshirt-128-")


def test_the_drawing_process_draws_user_garments_and_skips_a_broken_one(user_suit, tmp_path):
    """``python -m avatar.clothes.thumbnail ITEM...`` (what the Blender extension starts):
    a broken garment file costs only its own picture, named on one line of stderr."""
    import os
    import subprocess
    import sys

    broken = tmp_path / "broken" / "broken.mhclo"
    broken.parent.mkdir()
    broken.write_text("name broken\nobj_file missing.obj\n")
    env = dict(os.environ, AVATAR_CACHE=str(tmp_path / "cache"),
               PYTHONPATH=os.pathsep.join(sys.path))  # fmt: skip
    run = subprocess.run([sys.executable, "-m", "avatar.clothes.thumbnail", str(broken),
                          str(user_suit)], env=env, capture_output=True, text=True,
                         timeout=600)  # fmt: skip
    assert run.returncode == 1, run.stderr
    errors = run.stderr.strip().splitlines()
    assert len(errors) == 1 and str(broken) in errors[0] and "Traceback" not in run.stderr
    pictures = list((tmp_path / "cache" / "thumbnails").glob("user-*.png"))
    assert [p.name.split("-")[1] for p in pictures] == ["female_casualsuit01"]


def test_cli_draws_a_user_garment_found_by_name_in_a_folder(user_suit, tmp_path, capsys):
    from avatar import cli

    out = tmp_path / "pictures"
    folder = str(user_suit.parent.parent)
    assert cli.main(["clothes", "thumbnails", "female_casualsuit01", "--folder", folder,
                     "--out", str(out), "--size", "32"]) == 0  # fmt: skip
    assert [p.name for p in out.iterdir()] == ["female_casualsuit01.png"]


def test_makehuman_shoes_are_drawn_in_profile_by_their_tags(fixtures, human):
    """A MakeHuman garment's category is only "clothes" and its shoes come with socks up
    the calf: its tags tell footwear, drawn in profile like the built-ins."""
    shoes = fixtures / "makehuman" / "clothes" / "shoes02" / "shoes02.mhclo"
    mask = _cloth(thumbnail.garment_picture(str(shoes), 96, human))
    sole = mask[np.flatnonzero(mask.any(axis=1))[-1] - 3]  # a row just above the sole
    columns = np.flatnonzero(sole)
    assert np.all(np.diff(columns) == 1), columns  # one shoe, not two with floor between
    assert len(columns) > 0.6 * _extent(mask)[0], len(columns)  # its length, heel to toe

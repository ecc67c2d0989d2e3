"""Clothes: MakeHuman garments refit their authored OBJs; built-ins stay outside every body."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from avatar.clothes import binding, library
from avatar.errors import FormatError
from avatar.geometry import collision
from avatar.human import Human
from avatar.io import mhclo, obj

# Authoring bodies of the fixture garments (fixtures README).
FEMALE = {"gender": 0.0, "caucasian": 1.0, "african": 0.0, "asian": 0.0}
MALE = {"gender": 1.0, "caucasian": 1.0, "african": 0.0, "asian": 0.0}
GARMENTS = {
    "clothes/female_casualsuit01": FEMALE,
    "clothes/female_elegantsuit01": FEMALE,
    "clothes/female_sportsuit01": FEMALE,
    "clothes/male_casualsuit06": MALE,
    "clothes/shoes01": MALE,
    "clothes/shoes02": MALE,
    "hair/short02": MALE,
}


def _proxy(fixtures: Path, folder: str) -> tuple[mhclo.ProxyFile, Path]:
    path = next((fixtures / "makehuman" / folder).glob("*.mhclo"))
    return mhclo.read(path), path


@pytest.mark.parametrize("folder", sorted(GARMENTS))
def test_fixture_garment_refits_its_obj(model, fixtures, folder):
    if not (fixtures / "makehuman" / folder).is_dir():
        pytest.skip(f"{folder} not in fixtures")
    proxy, path = _proxy(fixtures, folder)
    authored = obj.read(path.parent / proxy.obj_file, axes=obj.MAKEHUMAN).vertices
    fitted = binding.fit(proxy.binding, model.shape(GARMENTS[folder]))
    error_dm = np.linalg.norm(fitted - authored, axis=1).mean() * 10
    assert error_dm < 0.03, error_dm


def test_eyelashes_refit_on_the_raw_base_mesh(model, fixtures):
    proxy, path = _proxy(fixtures, "eyelashes/eyelashes01")
    authored = obj.read(path.parent / proxy.obj_file, axes=obj.MAKEHUMAN).vertices
    fitted = binding.fit(proxy.binding, model.base.vertices)
    assert np.linalg.norm(fitted - authored, axis=1).mean() * 10 < 0.03


def test_mhclo_write_read_is_lossless(fixtures, tmp_path):
    proxy, _ = _proxy(fixtures, "clothes/female_casualsuit01")
    mhclo.write(tmp_path / "g.mhclo", proxy)
    assert mhclo.read(tmp_path / "g.mhclo") == proxy


def test_broken_mhclo_names_the_file(fixtures, tmp_path):
    _, path = _proxy(fixtures, "clothes/female_casualsuit01")
    lines = path.read_text().splitlines()
    bad = tmp_path / "bad.mhclo"
    verts = next(i for i, line in enumerate(lines) if line.startswith("verts"))
    lines[verts + 3] = "1 2 999999 0.3 0.3 0.4 0 0 0"
    bad.write_text("\n".join(lines))
    with pytest.raises(FormatError) as info:
        mhclo.read(bad)
    assert "bad.mhclo" in str(info.value) and info.value.line == verts + 4


def test_every_builtin_garment_stays_outside_varied_bodies(model):
    rng = np.random.default_rng(7)
    names = [e.name for e in library.list_garments() if e.category not in ("hair", "face")]
    faces = model.base.faces[model.base.face_groups["body"]]
    worst = 0.0
    for i in range(3):
        params = {"gender": rng.uniform(), "age": rng.uniform(0.3, 1.0),
                  "weight": [0.0, 1.0, 0.5][i], "muscle": rng.uniform()}  # fmt: skip
        human = Human(params, model=model).dressed(*names)
        for part in library.parts(human.outfit):
            _, depth = collision.penetration(human.vertices[:13380], faces, part.mesh.vertices)
            worst = max(worst, float(depth.max()))
    assert worst <= 0.001, f"a garment vertex is {worst * 1000:.2f} mm inside the body"


def test_dressed_human_exports_garments(model, tmp_path):
    from avatar.io import gltf

    human = Human({}, model=model).dressed("tshirt", "jeans", "hair-short")
    names = [p.name for p in human.parts()]
    assert names[:4] == ["body", "eyes", "teeth", "tongue"]
    assert {"tshirt", "jeans", "hair-short"} <= set(names)
    from avatar.export import save

    back = gltf.read(save(human, tmp_path / "d.glb"))
    assert {"tshirt", "jeans"} <= {p.name for p in back.parts}


def test_unknown_garment_lists_close_matches():
    from avatar.errors import ParameterError

    with pytest.raises(ParameterError, match="tshirt"):
        library.load_garment("tshrt")


def test_covered_skin_is_kept_unless_hidden(model):
    human = Human({}, model=model).dressed("tshirt", "jeans")
    kept = human.parts()[0]
    hidden = human.parts(hide_covered=True)[0]
    assert len(kept.mesh.vertices) == 13380
    assert 0 < len(hidden.mesh.vertices) < 13380
    assert hidden.skin[0].shape[0] == len(hidden.mesh.vertices)


def test_a_garment_fits_a_body_the_same_whatever_it_met_before(model):
    """Anchors come from the default body, not from the first body a garment meets, so
    a dataset's garments do not depend on the order its bodies were made in."""
    from dataclasses import replace

    shorts = library.load_garment("shorts")
    heavy = Human({"gender": 0.7, "weight": 1.0}, model=model)
    thin = Human({"gender": 0.2, "weight": 0.0, "age": 0.2}, model=model)
    fresh = replace(shorts)
    direct = library.dress(heavy.body, [fresh]).garments[0].mesh.vertices
    fresh = replace(shorts)
    library.dress(thin.body, [fresh])
    after = library.dress(heavy.body, [fresh]).garments[0].mesh.vertices
    np.testing.assert_array_equal(direct, after)


def _turn(axis: int, degrees: float) -> np.ndarray:
    q = np.zeros(4)
    q[0], q[1 + axis] = np.cos(np.radians(degrees) / 2), np.sin(np.radians(degrees) / 2)
    return q


def test_exact_frames_leave_no_garment_vertex_inside_a_body_pressed_into_itself(model):
    """A heavy body with thighs raised, knees bent, back bent and arms pressed to its sides:
    skinning drives body parts into each other, yet ``Outfit.frame(exact=True)`` leaves
    every garment vertex outside (winding number, right even where the body passes into
    itself), moving only a few."""
    from avatar.rig import kinematics, skinning

    human = Human({"gender": 0.7, "weight": 1.0, "age": 0.7}, model=model)
    names = list(human.skeleton.names)
    rotations = np.tile([1.0, 0.0, 0.0, 0.0], (1, len(names), 1))
    for side, sign in (("L", 1), ("R", -1)):
        rotations[0, names.index(f"upperleg01.{side}")] = _turn(0, 95)
        rotations[0, names.index(f"lowerleg01.{side}")] = _turn(0, -110)
        rotations[0, names.index(f"upperarm01.{side}")] = _turn(2, 30 * sign)
    rotations[0, names.index("spine03")] = _turn(0, 25)
    world = kinematics.forward(human.skeleton, rotations, np.zeros((1, 3)))
    matrices = kinematics.skinning_matrices(human.skeleton, world)[0]
    body = skinning.linear_blend(human.vertices, human.weights, matrices)[:13380]
    triangles = collision.skin_surface(model.base.faces).triangles

    def inside(points, skin=body):
        return collision.winding_number(points, skin, triangles) > 0

    def pressed(skin):  # skin vertices inside the body: one part driven into another
        return inside(skin + 5e-4 * collision.skin_surface(model.base.faces).normals(skin), skin)

    assert pressed(body).sum() > 2 * pressed(human.vertices[:13380]).sum()
    outfit = human.dressed("longsleeve", "hoodie", "trousers").outfit
    fast = outfit.frame(body, matrices)
    exact = outfit.frame(body, matrices, exact=True)
    for g, before, after in zip(outfit.garments, fast, exact, strict=True):
        assert not inside(after).any(), g.name
        assert np.any(before != after, axis=1).mean() < 0.01, g.name

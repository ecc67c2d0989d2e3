"""Clothes building blocks: binding maths, collision, weights, shells, fabrics, binder, assets."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from avatar.clothes import binding, weights
from avatar.clothes.binder import bind, save
from avatar.clothes.scan import scan
from avatar.errors import AvatarError, FormatError
from avatar.geometry import collision, nearest, shell
from avatar.looks import fabrics
from avatar.mesh import Mesh
from avatar.rig.skinning import SkinWeights

CUBE = Mesh(
    vertices=np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], np.float32),
    faces=np.array(
        [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]],
        np.int32,
    ),
)


def test_fit_is_barycentric_plus_scaled_offset():
    body = np.array([[0, 0, 0], [2, 0, 0], [0, 4, 0], [0, 0, 6]], np.float64)
    b = binding.make_binding(
        [[0, 1, 2]], [[0.25, 0.25, 0.5]], [[0.1, 0.1, 0.1]],
        scale_refs=[[0, 1], [0, 2], [0, 3]], scale_lengths=[1.0, 2.0, 3.0],
    )  # fmt: skip
    # anchor = (0.5, 2, 0); S = (2/1, 4/2, 6/3) = 2 on every axis.
    assert np.allclose(binding.fit(b, body), [[0.7, 2.2, 0.2]])
    batch = binding.fit(b, np.stack([body, body * 2]))
    assert batch.shape == (2, 1, 3) and np.allclose(batch[1], [[1.4, 4.4, 0.4]])


def test_signed_distance_and_push_out_on_a_cube():
    points = np.array([[0, 0, 0.5], [0, 0, 1.5], [0.9, 0.2, 0.1]], np.float32)
    count, depth = collision.penetration(CUBE.vertices, CUBE.faces, points)
    assert count == 2 and np.allclose(depth, [0.5, 0, 0.1], atol=1e-5)
    surface = collision.body_surface(CUBE.faces)
    q = collision.query(CUBE.vertices, surface, points, k=8)
    assert np.allclose(q.distance, [-0.5, 0.5, -0.1], atol=1e-5)
    moved = collision.push_out(points, q, 0.01)
    assert collision.penetration(CUBE.vertices, CUBE.faces, moved)[0] == 0


def _solid_angle_winding(points, vertices, triangles):
    """Exact winding number by summed solid angles (Van Oosterom and Strackee)."""
    a, b, c = (vertices[triangles[:, i]][None] - points[:, None] for i in range(3))
    la, lb, lc = (np.linalg.norm(v, axis=2) for v in (a, b, c))
    det = np.einsum("ptd,ptd->pt", a, np.cross(b, c))
    dots = (np.einsum("ptd,ptd->pt", a, b) * lc + np.einsum("ptd,ptd->pt", b, c) * la
            + np.einsum("ptd,ptd->pt", c, a) * lb)  # fmt: skip
    omega = 2 * np.arctan2(det, la * lb * lc + dots)
    return np.rint(omega.sum(axis=1) / (4 * np.pi)).astype(int)


def test_winding_number_counts_overlapping_solids():
    """Two overlapping cubes (as a skinned body passing into itself): 2 in the overlap,
    1 in either alone, 0 outside; agrees with the solid-angle formula everywhere."""
    tris = np.concatenate([CUBE.faces[:, [0, 1, 2]], CUBE.faces[:, [0, 2, 3]]])
    vertices = np.concatenate([CUBE.vertices, CUBE.vertices + [1.0, 0.5, 0.25]])
    triangles = np.concatenate([tris, tris + 8])
    points = np.random.default_rng(0).uniform(-1.5, 2.5, (2000, 3)).astype(np.float32)
    got = collision.winding_number(points, vertices, triangles, cell=0.3)
    assert np.array_equal(got, _solid_angle_winding(points, vertices, triangles))
    assert set(np.unique(got)) == {0, 1, 2}
    known = collision.winding_number(np.array([[1.5, 1, 0.75], [0.5, 0.5, 0.5], [-0.5] * 3,
                                               [2.2, 0, 0]]), vertices, triangles)  # fmt: skip
    assert known.tolist() == [1, 2, 1, 0]


def test_a_point_as_near_another_sheet_of_skin_that_it_is_inside_is_inside():
    """Skin passing into itself (cube B's face runs inside cube A, as an arm pressed into
    the chest): a point inside A is as near A's face (inside it) as B's (outside it).
    Whichever one float rounding makes the nearest, the query says inside, as the winding
    number does (it said outside by 0.2 whenever B's face won: CMU 01_01 frame 1320 left a
    T-shirt vertex 4.2 mm inside the baked file for that reason)."""
    tris = np.concatenate([CUBE.faces[:, [0, 1, 2]], CUBE.faces[:, [0, 2, 3]]])
    vertices = np.concatenate([CUBE.vertices, CUBE.vertices + [1.5, 0.0, 0.0]])
    faces = np.concatenate([CUBE.faces, CUBE.faces + 8])
    surface = collision.body_surface(faces)
    # 0.2 from A's face y = 1 (inside A) and from B's face x = 0.5 (outside B)
    points = np.array([[0.3, 0.8 + e, z] for e in (-2e-6, 0.0, 2e-6) for z in (-0.3, 0.0, 0.4)],
                      np.float32)  # fmt: skip
    q = collision.query(vertices, surface, points, k=16, sheets=True)
    assert np.allclose(q.distance, -0.2, atol=1e-5), q.distance
    assert collision.penetration(vertices, faces, points)[0] == len(points)
    assert np.all(q.normal[:, 1] > 0.85)  # out through A's face y = 1 (normals blended)
    winding = collision.winding_number(points, vertices, np.concatenate([tris, tris + 8]))
    assert np.all(winding >= 1)
    # Clearly nearer B's face (outside B by 0.1, inside A by 0.3 beyond the tie): the
    # nearest skin decides, as before.
    q = collision.query(vertices, surface, np.array([[0.4, 0.7, 0.0]], np.float32), k=16,
                        sheets=True)  # fmt: skip
    assert np.isclose(q.distance[0], 0.1, atol=1e-5)


def test_closest_points_on_triangles_match_dense_sampling():
    """The closest point found on each random triangle is as close as the best of 5,151
    points sampled over it, and no sample is closer (within the sampling step)."""
    rng = np.random.default_rng(1)
    a, b, c, p = (rng.normal(size=(300, 3)) for _ in range(4))
    c[:20] = a[:20] + 0.5 * (b[:20] - a[:20])  # degenerate: all three on one line
    bary = collision.closest_on_triangles(p, a, b, c)
    assert np.all(bary >= -1e-9) and np.allclose(bary.sum(axis=1), 1)
    got = np.linalg.norm(p - (bary[:, :1] * a + bary[:, 1:2] * b + bary[:, 2:] * c), axis=1)
    u, v = (w.ravel() for w in np.meshgrid(np.linspace(0, 1, 101), np.linspace(0, 1, 101)))
    u, v = u[u + v <= 1], v[u + v <= 1]
    samples = (a[:, None] + u[None, :, None] * (b - a)[:, None]
               + v[None, :, None] * (c - a)[:, None])  # fmt: skip
    sampled = np.linalg.norm(samples - p[:, None], axis=2).min(axis=1)
    edge = np.maximum.reduce([np.linalg.norm(x - y, axis=1) for x, y in ((a, b), (b, c), (c, a))])
    assert np.all(got <= sampled + 1e-9)
    assert np.all(sampled - got <= edge * 0.02 + 1e-9)  # a sample lies within 0.02 edge


@pytest.mark.parametrize("engine", ["pykdtree", "scipy"])
def test_point_tree_finds_the_nearest_points_within_reach(engine, monkeypatch):
    if engine == "scipy":  # the fallback where pykdtree is missing
        monkeypatch.setattr(nearest, "KDTree", None)
    rng = np.random.default_rng(3)
    data, points = rng.random((500, 3)), rng.random((200, 3))
    tree = nearest.PointTree(data)
    dist, index = tree.query(points, k=3, reach=0.08)
    brute = np.linalg.norm(points[:, None] - data[None], axis=2)
    order = np.sort(brute, axis=1)[:, :3]
    found = np.isfinite(dist)
    assert np.array_equal(found, order < 0.08)
    assert np.allclose(dist[found], order[found], atol=1e-6)
    assert np.all(index[~found] == len(tree))
    one, _ = tree.query(points)
    assert one.shape == (200,) and np.allclose(one, order[:, 0], atol=1e-6)


def test_searches_threads_sleep_between_searches_unless_the_user_says_otherwise():
    """pykdtree's OpenMP threads spinning after each search took the cores from other work
    (posed frames 10-17 frames/s instead of 52-64 at load 10): Avatar asks for sleeping
    threads before OpenMP loads, in a fresh process; a user's own setting is kept."""
    import os
    import subprocess
    import sys

    code = "import os, avatar.geometry.nearest; print(os.environ['OMP_WAIT_POLICY'])"
    env = {k: v for k, v in os.environ.items() if k != "OMP_WAIT_POLICY"}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                         text=True, check=True).stdout  # fmt: skip
    assert out.strip() == "PASSIVE"
    env["OMP_WAIT_POLICY"] = "ACTIVE"
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                         text=True, check=True).stdout  # fmt: skip
    assert out.strip() == "ACTIVE"


def test_a_winding_grid_serves_many_queries_of_one_surface():
    tris = np.concatenate([CUBE.faces[:, [0, 1, 2]], CUBE.faces[:, [0, 2, 3]]])
    grid = collision.WindingGrid(CUBE.vertices, tris, cell=0.25)
    rng = np.random.default_rng(2)
    for _ in range(3):
        points = rng.uniform(-1.5, 1.5, (500, 3))
        inside = np.all(np.abs(points) < 1, axis=1)
        assert np.array_equal(grid.winding(points), inside.astype(int))


def test_surface_distance_is_exact_on_a_cube():
    tris = np.concatenate([CUBE.faces[:, [0, 1, 2]], CUBE.faces[:, [0, 2, 3]]])
    points = np.array([[0, 0, 0.5], [0, 0, 3], [2, 2, 2], [0.9, 0.2, 0.1]], np.float32)
    got = collision.surface_distance(points, CUBE.vertices, tris)
    assert np.allclose(got, [0.5, 2, np.sqrt(3), 0.1], atol=1e-5)


def test_transferred_weights_follow_the_references():
    body = SkinWeights(np.array([[0, 1], [1, 2], [2, 0]], np.int32),
                       np.array([[0.5, 0.5], [1.0, 0], [1.0, 0]], np.float32))  # fmt: skip
    b = binding.make_binding([[0, 1, 2], [2, 2, 2]], [[0.5, 0.5, 0.0], [1, 0, 0]], np.zeros((2, 3)))
    w = weights.transfer(b, body)
    dense = np.zeros((2, 3))
    np.add.at(dense, (np.arange(2)[:, None], w.indices), w.weights)
    assert np.allclose(dense, [[0.25, 0.75, 0], [0, 0, 1]])


def test_shell_is_closed_and_keeps_uvs():
    sheet = Mesh(
        np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [2, 1, 0]], np.float32),
        np.array([[0, 1, 2, 3], [1, 4, 5, 2]], np.int32),
        np.zeros((8, 2), np.float32),
        np.arange(8, dtype=np.int32).reshape(2, 4),
    )
    s = shell.solidify(sheet)
    assert len(s.mesh.faces) == 2 + 2 + 6 and s.count == 6
    edges, _ = shell.boundary_edges(s.mesh.faces)
    assert len(edges) == 0  # watertight
    verts = shell.extrude(sheet.vertices, np.tile([0, 0, 1.0], (6, 1)), 0.01)
    assert verts.shape == (12, 3) and np.allclose(verts[6:, 2], 0.01)


def test_fabrics_tile_seamlessly():
    for name in ("cotton", "denim", "knit", "leather"):
        h, normal, rough = fabrics.maps(name, 128)
        assert normal.shape == (128, 128, 3) and rough.dtype == np.uint8
        # Wrapping across the tile edge is no rougher than inside it.
        seam = np.abs(h[0] - h[-1]).mean()
        inner = np.abs(np.diff(h, axis=0)).mean()
        assert seam < 3 * inner + 1e-6
    m = fabrics.material("denim", "indigo", 64)
    assert m.base_color_texture.shape == (64, 64, 3) and m.extras["fabric"] == "denim"


def test_binder_reproduces_the_authored_garment_and_refuses_far_vertices():
    garment = CUBE.vertices * 1.1
    b = bind(garment, CUBE.vertices * 1.0, CUBE.faces)
    assert np.allclose(binding.fit(b, CUBE.vertices), garment, atol=1e-6)
    with pytest.raises(AvatarError, match="vertex 0"):
        bind(np.array([[9.0, 0, 0]]), CUBE.vertices, CUBE.faces)


def test_avatar2020_garments_bind_and_follow_new_bodies(model, fixtures):
    from avatar.clothes.fitting import Garment, dress
    from avatar.human import Human
    from avatar.io import obj
    from avatar.io.obj import to_avatar_frame

    folder = fixtures / "avatar2020"
    mean = to_avatar_frame(np.loadtxt(folder / "shape" / "StandardModel.txt").reshape(-1, 3))
    faces = model.base.faces[model.base.face_groups["body"]]
    garments = []
    for name in ("shirt03", "pants01"):
        mesh = obj.read(folder / "clothes" / f"{name}.obj", axes=obj.MAKEHUMAN)
        b = bind(mesh.vertices, mean, faces)
        assert np.abs(binding.fit(b, mean) - mesh.vertices).max() < 1e-5
        garments.append(Garment(name, mesh, b, z_depth=40 + len(garments)))
    human = Human({"weight": 1.0, "gender": 0.2, "age": 0.8}, model=model)
    for fitted in dress(human.body, garments):
        count, depth = collision.penetration(human.vertices[:13380], faces, fitted.mesh.vertices)
        assert depth.max() <= 0.001, (fitted.name, count, depth.max())


def test_saved_garment_loads_back(model, fixtures, tmp_path):
    from avatar.clothes.asset import read_garment
    from avatar.human import Human
    from avatar.io import obj

    body = Human({}, model=model).vertices  # the 2020 mean body is the default, grounded
    mesh = obj.read(fixtures / "avatar2020" / "clothes" / "hat01.obj", axes=obj.MAKEHUMAN)
    faces = model.base.faces[model.base.face_groups["body"]]
    b = bind(mesh.vertices, body, faces)
    path = save(tmp_path, "hat", mesh, b, tags=("Hat",))
    g = read_garment(path)
    assert g.name == "hat" and g.tags == ("hat",)
    assert np.allclose(binding.fit(g.binding, body), mesh.vertices, atol=1e-5)


@pytest.fixture
def shoes(fixtures, tmp_path):
    src = fixtures / "makehuman" / "clothes" / "shoes01"
    dst = tmp_path / "shoes01"
    shutil.copytree(src, dst)
    return dst


def test_fixture_garment_loads_with_its_weights_and_textures(shoes):
    from avatar.clothes.asset import read_garment

    g = read_garment(shoes / "shoes01.mhclo")
    assert g.bone_weights is not None and g.material.base_color_texture is not None
    assert g.licence == "CC0" and len(g.delete_verts) > 0


@pytest.mark.parametrize("broken", ["missing obj", "missing texture", "wrong count"])
def test_broken_garment_is_refused_naming_the_file(shoes, broken):
    from avatar.clothes.asset import read_garment

    if broken == "missing obj":
        (shoes / "shoes01.obj").unlink()
        culprit = "shoes01.mhclo"
    elif broken == "missing texture":
        (shoes / "shoes01_diffuse.png").unlink()
        culprit = "shoes01.mhmat"
    else:
        text = (shoes / "shoes01.mhclo").read_text().splitlines()
        start = next(i for i, line in enumerate(text) if line.startswith("verts"))
        del text[start + 1]
        (shoes / "shoes01.mhclo").write_text("\n".join(text))
        culprit = "shoes01.mhclo"
    with pytest.raises(FormatError) as info:
        read_garment(shoes / "shoes01.mhclo")
    assert culprit in str(info.value)


def test_scanner_lists_makehuman_assets(fixtures):
    entries = scan(fixtures / "makehuman")
    names = {e.name for e in entries}
    assert {"shoes01", "short02", "eyebrow001"} <= names
    short = next(e for e in entries if e.name == "short02")
    assert short.category == "hair" and short.licence == "CC0" and short.thumbnail
    assert "short" in short.tags


def test_clothes_bind_cli_binds_an_obj_in_any_frame_and_refuses_a_stray_one(
    model, tmp_path, capsys
):
    """A garment exported Y-up (Blender's OBJ default) from a body made with --set binds to
    that body, refits it exactly, and fits another body; a mesh off the body is refused
    and nothing is written."""
    from avatar.cli import main
    from avatar.clothes import library
    from avatar.human import Human
    from avatar.io import obj

    body = Human({"weight": 0.8, "gender": 0.3}, model=model)
    worn = library.dress(body.body, ["tshirt"]).garments[0].mesh
    v = worn.vertices
    exported = worn.with_vertices(np.stack([v[:, 0], v[:, 2], -v[:, 1]], axis=1))  # Y-up
    obj.write(tmp_path / "shirt.obj", exported)
    out = tmp_path / "mine"
    assert main(["clothes", "bind", str(tmp_path / "shirt.obj"), "--set", "weight=0.8",
                 "--set", "gender=0.3", "--tag", "Top", "-o", str(out)]) == 0  # fmt: skip
    garment = library.load_garment(str(out / "shirt.mhclo"))
    assert np.abs(binding.fit(garment.binding, body.vertices) - v).max() < 1e-5
    assert "top" in garment.tags
    other = Human({"weight": 0.1, "gender": 0.9, "age": 0.2}, model=model).dressed(
        str(out / "shirt.mhclo"))  # fmt: skip
    faces = model.base.faces[model.base.face_groups["body"]]
    for g in other.outfit.garments:
        assert collision.penetration(other.vertices[:13380], faces, g.mesh.vertices)[0] == 0
    obj.write(tmp_path / "stray.obj", exported.with_vertices(exported.vertices + 3.0))
    assert main(["clothes", "bind", str(tmp_path / "stray.obj"), "--frame", "avatar", "-o",
                 str(tmp_path / "none")]) != 0  # fmt: skip
    assert "garment vertex 0" in capsys.readouterr().err
    assert not (tmp_path / "none").exists()


def test_escape_moves_every_point_out_of_overlapping_solids():
    """Two overlapping cubes stand for a skinned body passing into itself: points inside
    either (or both) end outside both with the clearance; points outside stay put."""
    tris = np.concatenate([CUBE.faces[:, [0, 1, 2]], CUBE.faces[:, [0, 2, 3]]])
    faces = np.concatenate([CUBE.faces, CUBE.faces + 8])
    vertices = np.concatenate([CUBE.vertices, CUBE.vertices + [1.0, 0.5, 0.25]])
    surface = collision.body_surface(faces)
    triangles = np.concatenate([tris, tris + 8])
    points = np.random.default_rng(1).uniform(-1.5, 2.5, (500, 3)).astype(np.float32)
    before = collision.winding_number(points, vertices, triangles, cell=0.3)
    assert {1, 2} <= set(before.tolist())
    moved = collision.escape(points, vertices, surface, 0.05)
    assert not np.any(collision.winding_number(moved, vertices, triangles, cell=0.3))
    np.testing.assert_array_equal(moved[before == 0], points[before == 0])
    # Each moved point is outside by the clearance along the interpolated vertex normal
    # (at a cube's corner that normal is diagonal: 1/sqrt(3) of it from the faces).
    gap = collision.surface_distance(moved[before > 0], vertices, triangles)
    assert gap.min() > 0.05 / np.sqrt(3) - 1e-4

"""Built-in hair, brows, lashes and tank top: properties that make them look right in renders."""

from __future__ import annotations

import numpy as np
import pytest

from avatar.clothes import builtin, face, hair, library
from avatar.geometry import collision
from avatar.geometry.shell import boundary_edges
from avatar.human import Human
from avatar.looks import textures


@pytest.fixture(scope="module")
def body():
    return library.authoring_body()


@pytest.mark.parametrize("paint", [textures.lash_alpha, textures.brow_alpha, textures.strand_alpha])
def test_strand_alphas_have_see_through_gaps_opaque_cores_and_soft_edges(paint):
    alpha = paint(256)
    assert alpha.dtype == np.uint8 and alpha.shape == (256, 256)
    assert (alpha == 0).mean() > 0.05  # gaps between strands
    assert (alpha >= 200).mean() > 0.02  # strand cores
    assert ((alpha > 20) & (alpha < 200)).any()  # anti-aliased edges, not a stripe pattern
    assert np.array_equal(alpha, paint(256))  # deterministic


def test_lashes_are_many_thin_strands_rooted_on_the_lid_line():
    alpha = textures.lash_alpha(512).astype(np.float32) / 255
    upper = alpha[:256]  # v in [0.5, 1]: root at the bottom row of this half
    assert upper[-3:].mean() > 0.8  # the lash line
    row = upper[128] > 0.5  # half way to the tips: separate strands
    starts = np.count_nonzero(row[1:] & ~row[:-1])
    assert starts > 40
    assert upper[:20].mean() < upper[200:230].mean() / 3  # thinning towards the tips


def test_eyebrow_is_thick_at_the_head_and_thin_at_the_tail():
    alpha = textures.brow_alpha(512) > 128
    head = alpha[:, 48:112].sum(axis=0).mean()
    tail = alpha[:, 432:464].sum(axis=0).mean()
    assert head > 2 * tail > 0
    assert not alpha[:, :5].any() and not alpha[:, -5:].any()  # room around the ends


def test_face_and_hair_materials_cut_out_or_blend():
    for name, mode in (("eyelashes", "BLEND"), ("eyebrows", "BLEND"), ("hair-short", "MASK")):
        m = textures.hair_material(builtin.BY_NAME[name], 128)
        assert m.alpha_mode == mode and m.double_sided
        assert m.base_color_texture.shape == (128, 128, 4)
    roots, tips = textures.strand_shade(128)[[70, 126]].mean(axis=1)
    assert roots < 0.8 * tips  # darker roots


def test_lash_strip_uvs_run_from_the_lid_to_the_tips(body):
    piece = face.eyelashes(body, builtin.EYELASH_GROUPS)
    uv = piece.mesh.uvs
    assert uv[:, 0].min() == 0 and uv[:, 0].max() == 1
    assert uv[:, 1].min() == 0 and uv[:, 1].max() == 1
    eye = body.centre("helper-l-eye")
    upper = face.eyelashes(body, ("helper-l-eyelashes-2",)).mesh
    roots = upper.vertices[upper.uvs[:, 1] == 0.5]
    tips = upper.vertices[upper.uvs[:, 1] == 1.0]
    assert np.linalg.norm(roots - eye, axis=1).mean() < np.linalg.norm(tips - eye, axis=1).mean()


def _turning_degrees(points: np.ndarray, loop: list[int]) -> np.ndarray:
    p = points[loop].astype(np.float64)
    a, b = np.roll(p, -1, 0) - p, p - np.roll(p, 1, 0)
    cos = np.einsum("nd,nd->n", a, b) / np.linalg.norm(a, axis=1) / np.linalg.norm(b, axis=1)
    return np.degrees(np.arccos(np.clip(cos, -1, 1)))


def _loops(faces: np.ndarray) -> list[list[int]]:
    edges, _ = boundary_edges(faces)
    following = dict(zip(edges[:, 0].tolist(), edges[:, 1].tolist(), strict=True))
    loops, seen = [], set()
    for start in following:
        if start in seen:
            continue
        loop = [start]
        while following[loop[-1]] != start and following[loop[-1]] not in seen:
            loop.append(following[loop[-1]])
            seen.add(loop[-1])
        loops.append(loop)
    return loops


def test_tank_top_armholes_are_smooth_curves(body, monkeypatch):
    relaxed = builtin.RELAX

    def armholes(relax):
        monkeypatch.setattr(builtin, "RELAX", relax)
        mesh = builtin.BY_NAME["tanktop"].make(body).mesh
        loops = [p for p in _loops(mesh.faces) if abs(mesh.vertices[p, 0].mean()) > 0.08]
        assert len(loops) == 2  # one armhole each side, apart from neckline and hem
        return np.concatenate([_turning_degrees(mesh.vertices, p) for p in loops])

    assert armholes(0).max() >= 80  # the raw cut is a staircase of face edges
    smooth = armholes(relaxed)
    assert smooth.max() < 50 and smooth.mean() < 20


def test_tank_top_has_straps_over_the_shoulders(body):
    mesh = builtin.BY_NAME["tanktop"].make(body).mesh
    top = mesh.vertices[mesh.vertices[:, 2] > body.marks.neck[2] - 0.02]
    assert (top[:, 0] > 0.05).any() and (top[:, 0] < -0.05).any()
    assert not (np.abs(top[:, 0]) < 0.03).any()  # the neckline is open


def test_short_hair_has_volume_and_a_hairline(body):
    mesh = builtin.BY_NAME["hair-short"].make(body).mesh
    centre, eye_z = hair.head_frame(body)
    height, _ = body.skin_tree.query(mesh.vertices)
    crown = mesh.vertices[:, 2] > eye_z + 0.07
    assert np.percentile(height[crown], 90) > 0.012  # stands off the scalp, not a cap
    cap = hair.base_cap(body).mesh.vertices
    forehead = (hair.around(cap, centre) < 20) & (cap[:, 1] < centre[1])
    assert cap[forehead, 2].min() > eye_z + 0.055  # a bare forehead under the hairline
    assert cap[:, 2].min() < eye_z - 0.04  # down to the nape


def test_long_hair_falls_behind_the_shoulders(body):
    mesh = builtin.BY_NAME["hair-long"].make(body).mesh
    low = mesh.vertices[mesh.vertices[:, 2] < body.marks.neck[2] - 0.1]
    assert len(low) and low[:, 1].min() > body.marks.neck[1] - 0.05


def test_hair_stays_outside_varied_bodies():
    names = [s.name for s in builtin.SPECS if s.category == "hair"]
    worst = 0.0
    for params in ({"gender": 0.0, "age": 0.1}, {"gender": 1.0, "weight": 1.0, "age": 1.0}):
        human = Human(params).dressed(*names)
        faces = human.model.base.faces[human.model.base.face_groups["body"]]
        for part in library.parts(human.outfit):
            _, depth = collision.penetration(human.vertices[:13380], faces, part.mesh.vertices)
            worst = max(worst, float(depth.max()))
    assert worst <= 0.001, f"a hair vertex is {worst * 1000:.2f} mm inside the body"


# ---------------------------------------------------------------------------- shoes


def _rows_of(mesh) -> np.ndarray:
    """(V,) the atlas row (shoes.ROWS name) each vertex's UVs fall in."""
    from avatar.clothes import shoes

    v = np.zeros(len(mesh.vertices))
    v[mesh.faces.ravel()] = mesh.uvs[mesh.face_uvs.ravel(), 1]
    names = list(shoes.ROWS)
    return np.array([next(n for n in names if shoes.ROWS[n][0] <= x <= shoes.ROWS[n][1])
                     for x in v])  # fmt: skip


def test_shoes_have_sole_heel_toe_cap_and_laces(body):
    from avatar.clothes import shoes

    mesh = builtin.BY_NAME["shoes"].make(body).mesh
    rows = _rows_of(mesh)
    assert set(rows) == {"upper", "vamp", "trim", "cap", "sole", "laces"}  # trim: the eyelets
    left = mesh.vertices[:, 0] > 0
    foot = shoes.Foot(body, 0)
    v = mesh.vertices[left]
    r = rows[left]
    sole, t = v[r == "sole"], foot.along(v[r == "sole"])
    # A flat tread under heel and ball, below the foot; lifted under the arch (heel block).
    heel, ball, arch = sole[t < 0.2], sole[(t > 0.7) & (t < 0.85)], sole[np.abs(t - 0.45) < 0.05]
    tread = sole[:, 2].min()
    assert tread < foot.ground - 0.005
    assert heel[:, 2].min() - tread < 0.001 and ball[:, 2].min() - tread < 0.001
    assert arch[:, 2].min() > tread + 0.004
    # The sole stands out of the upper (a welt) all round.
    upper = v[r == "upper"]
    low = upper[upper[:, 2] < foot.ground + 0.03]
    assert np.ptp(sole[:, 0]) > np.ptp(low[:, 0]) + 0.004
    # Toe cap over the front, laces over the instep, above the upper.
    cap, laces = v[r == "cap"], v[r == "laces"]
    assert foot.along(cap).min() > 0.7
    assert 0.4 < foot.along(laces).mean() < 0.8
    assert laces[:, 2].min() > np.median(upper[:, 2])
    # The shoe is longer than the foot: a toe box.
    assert v[:, 1].min() < foot.toe_y - 0.008


def test_shoe_material_is_an_atlas_of_leather_sole_and_cord():
    m = builtin.build(builtin.BY_NAME["shoes"], library.authoring_body(), 256).material
    assert m.base_color_texture.shape == (256, 256, 3) and m.normal_texture is not None
    assert [row[2] for row in m.extras["rows"]] == ["calf", "calf", "calf", "calf", "sole", "cord"]
    image = m.base_color_texture.astype(float)
    upper = image[int(256 * 0.25)].mean(0)
    sole, laces = image[int(256 * 0.75)].mean(0), image[int(256 * 0.95)].mean(0)
    # Brown laces (red over blue) darker than the brown upper; an inked sole edge darker
    # still (a charcoal rubber's grey read as a plastic clog's sole).
    assert laces[0] > laces[2] + 15 and laces.mean() < upper.mean() - 15
    assert sole.mean() < laces.mean() and sole.max() < 60


@pytest.mark.parametrize("name", ["leggings", "swimsuit"])
def test_stretch_knit_has_a_satin_sheen_not_a_latex_gloss(name):
    """Lycra's roughness map (what every renderer reads) sits between a gloss and cotton:
    at 0.35 black leggings rendered as latex, with mirror streaks down the shins."""
    def roughness(spec_name: str) -> float:
        m = builtin.build(builtin.BY_NAME[spec_name], library.authoring_body(), 256).material
        return float(np.asarray(m.roughness_texture, dtype=float).mean() / 255.0)

    assert 0.5 <= roughness(name) < roughness("tshirt") - 0.1


def _bumpiness(mesh, keep: np.ndarray) -> float:
    """Mean distance of the kept vertices from the average of their mesh neighbours."""
    a, b = mesh.faces.ravel(), np.roll(mesh.faces, -1, axis=1).ravel()
    total = np.zeros_like(mesh.vertices, dtype=np.float64)
    np.add.at(total, a, mesh.vertices[b])
    np.add.at(total, b, mesh.vertices[a])
    count = np.bincount(a, minlength=len(mesh.vertices)) + np.bincount(b, minlength=len(
        mesh.vertices))
    off = np.linalg.norm(mesh.vertices - total / np.maximum(count, 1)[:, None], axis=1)
    return float(off[keep].mean())


def test_shoe_upper_is_smooth_not_toes(body, monkeypatch):
    """The toe box is smoothed: the bumps of the toes do not show through the leather."""
    from avatar.clothes import shoes

    foot = shoes.Foot(body, 0)
    smooth = shoes.upper(body, foot).mesh
    monkeypatch.setattr(shoes, "_toe_box", lambda body, foot, mesh, ease: mesh)
    raw = shoes.upper(body, foot).mesh
    front = []
    for m in (smooth, raw):  # the forefoot, not the edges the sole and opening keep
        rim = np.zeros(len(m.vertices), bool)
        rim[boundary_edges(m.faces)[0].ravel()] = True
        front.append((foot.along(m.vertices) > 0.75) & ~rim)
    assert _bumpiness(smooth, front[0]) < 0.75 * _bumpiness(raw, front[1])


# ---------------------------------------------------------------------------- hair styles


def test_there_are_at_least_six_hair_styles():
    names = {s.name for s in builtin.SPECS if s.category == "hair"}
    assert {"hair-short", "hair-long", "hair-ponytail", "hair-buzz", "hair-bob",
            "hair-bun"} <= names  # fmt: skip


def test_buzz_cut_is_close_to_the_scalp(body):
    """Over the crown a buzz cut's hair stands millimetres off the scalp, short hair's
    upper layers about a centimetre (heights above the skin's surface, so the count of
    vertices along a card does not weigh in)."""
    from avatar.geometry import collision

    _, eye_z = hair.head_frame(body)
    surface = collision.skin_surface(body.base.faces[body.base.face_groups["body"]])

    def height(name):
        v = builtin.BY_NAME[name].make(body).mesh.vertices
        v = v[v[:, 2] > eye_z + 0.06]
        return np.percentile(collision.query(body.vertices[:13380], surface, v).distance, 90)

    assert height("hair-buzz") < 0.005 < 0.008 < height("hair-short")  # not a mop


def test_bob_falls_to_the_jaw_with_a_fringe_above_the_eyes(body):
    mesh = builtin.BY_NAME["hair-bob"].make(body).mesh
    centre, eye_z = hair.head_frame(body)
    v = mesh.vertices
    assert eye_z - 0.125 < v[:, 2].min() < eye_z - 0.06  # a blunt line at the jaw
    sides = np.abs(v[:, 0]) > 0.07
    assert (v[sides, 2] < eye_z - 0.05).sum() > 500  # hangs down both sides
    face = (hair.around(v, centre) < 30) & (v[:, 1] < centre[1] - 0.05)
    assert v[face, 2].min() > eye_z + 0.02  # the fringe stops above the eyes


def test_bun_sits_high_on_the_back_of_the_head(body):
    mesh = builtin.BY_NAME["hair-bun"].make(body).mesh
    centre, eye_z = hair.head_frame(body)
    back = body.vertices[:13380][body.part[:13380] == "head"][:, 1].max()
    behind = mesh.vertices[mesh.vertices[:, 1] > back + 0.02]
    assert len(behind) > 200
    assert behind[:, 2].mean() > eye_z + 0.04
    assert np.ptp(behind[:, 0]) < 0.1  # a knot, not a curtain


def test_brows_are_dense_and_lashes_full():
    """Brows: the core of the shape is mostly covered by hairs (a brow, not a pencil line);
    lashes: many separate strands half way to the tips, most of the row covered."""
    alpha = textures.brow_alpha(512) / 255
    u = (np.arange(512) + 0.5) / 512
    centre, half = textures.brow_shape(np.clip((u - 0.03) / 0.85, 0, 1))
    core = np.zeros_like(alpha, bool)
    for j in range(60, 400):
        core[int((1 - centre[j] - 0.6 * half[j]) * 512):int((1 - centre[j] + 0.6 * half[j]) * 512),
             j] = True  # fmt: skip
    assert alpha[core].mean() > 0.75
    lashes = textures.lash_alpha(512) / 255
    row = lashes[128] > 0.5
    assert np.count_nonzero(row[1:] & ~row[:-1]) > 50 and lashes[128].mean() > 0.5
    blond = textures.hair_material(builtin.BY_NAME["eyebrows-blond"], 64).base_color_texture
    hair_blond = textures.hair_material(builtin.BY_NAME["hair-long"], 64).base_color_texture
    shown = [t[t[..., 3] > 128][:, :3].mean() for t in (blond, hair_blond)]
    assert shown[0] < 0.85 * shown[1]  # a shade deeper than the hair: brows read on fair skin


# ---------------------------------------------------------------------------- bands, cuffs


def test_banded_adds_a_raised_band_and_a_lip_along_open_edges():
    from avatar.clothes.authoring import banded, with_box_uvs
    from avatar.mesh import Mesh

    x, y = np.meshgrid(np.linspace(0, 0.1, 11), np.linspace(0, 0.1, 11))
    points = np.stack([x.ravel(), y.ravel(), np.zeros(x.size)], 1).astype(np.float32)
    ij = np.arange(121).reshape(11, 11)
    faces = np.stack([ij[:-1, :-1], ij[:-1, 1:], ij[1:, 1:], ij[1:, :-1]], -1).reshape(-1, 4)
    flat = with_box_uvs(Mesh(points, faces.astype(np.int32)))
    out = banded(flat, width=0.015, lift=0.002)
    assert out.face_uvs.shape == out.faces.shape and out.uvs.shape[0] > flat.uvs.shape[0]
    lifted = out.vertices[121:]
    assert np.allclose(np.abs(lifted[:, 2]), 0.002, atol=1e-6)  # a layer 2 mm off the cloth
    band_faces = 100 - 64  # faces within 1.5 cm (one face and a half) of the edge
    assert len(out.faces) == 100 + band_faces + 40  # + one lip quad per open edge
    # The original edge is closed by the lip: the only open edges are the band's inner edge.
    edges, _ = boundary_edges(out.faces)
    assert (np.unique(edges) >= 121).all()


def test_tshirt_neckline_and_hem_have_bands_and_long_sleeves_end_at_the_wrist(body):
    from avatar.clothes import regions

    tshirt = builtin.BY_NAME["tshirt"].make(body).mesh
    edges, _ = boundary_edges(tshirt.faces)
    rim = tshirt.vertices[np.unique(edges)]
    # The open edges lie on the raised band: each has cloth 1-2 mm beneath it.
    d, _ = body.skin_tree.query(rim)
    plain = builtin._tights(body, builtin.top(0.3), builtin.sleeve_ease(0.007, 0.02)).mesh
    d_plain, _ = body.skin_tree.query(plain.vertices[np.unique(boundary_edges(plain.faces)[0])])
    assert np.median(d) > np.median(d_plain) + 0.001
    sleeve = builtin.BY_NAME["longsleeve"].make(body).mesh
    arm, _ = regions.limb_coordinates(sleeve.vertices.astype(np.float64), body.marks)
    assert 0.9 < np.nanmax(arm) <= 1.0  # to the wrist, not over the hand


# ---------------------------------------------------------------------------- dress


def _aureola_vertices(model) -> np.ndarray:
    """Skin vertices inside MakeHuman's aureolae mask (by their UVs)."""
    from avatar.looks import skin

    mask = skin.region_masks(256)["aureolae"]
    base = model.base
    rows = base.face_groups["body"]
    corners, uv = base.faces[rows].ravel(), base.uvs[base.face_uvs[rows].ravel()]
    r = np.clip(((1 - uv[:, 1]) * 256).astype(int), 0, 255)
    c = np.clip((uv[:, 0] * 256).astype(int), 0, 255)
    return np.unique(corners[mask[r, c] > 0.5])


def _forward_hits(origins: np.ndarray, mesh) -> np.ndarray:
    """(N,) bool: a ray from each origin towards the front (-Y) crosses the mesh."""
    quads = mesh.faces
    tris = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    t = mesh.vertices[tris].astype(np.float64)
    p = origins.astype(np.float64)
    # Project on the XZ plane: a forward ray hits a triangle in front that covers it in 2D.
    a, b, c = t[:, 0, [0, 2]], t[:, 1, [0, 2]], t[:, 2, [0, 2]]
    q = p[:, None, [0, 2]]
    d = (b[:, 1] - c[:, 1]) * (a[:, 0] - c[:, 0]) + (c[:, 0] - b[:, 0]) * (a[:, 1] - c[:, 1])
    d = np.where(np.abs(d) < 1e-12, 1e-12, d)
    dx, dz = q[..., 0] - c[:, 0], q[..., 1] - c[:, 1]
    w0 = ((b[:, 1] - c[:, 1]) * dx + (c[:, 0] - b[:, 0]) * dz) / d
    w1 = ((c[:, 1] - a[:, 1]) * dx + (a[:, 0] - c[:, 0]) * dz) / d
    w2 = 1 - w0 - w1
    y = w0 * t[:, 0, 1] + w1 * t[:, 1, 1] + w2 * t[:, 2, 1]
    inside = (w0 >= 0) & (w1 >= 0) & (w2 >= 0) & (y < p[:, None, 1])
    return inside.any(axis=1)


def test_dress_has_straps_and_covers_the_chest_at_every_size(model):
    nipples = _aureola_vertices(model)
    assert len(nipples) > 10
    for params in ({"gender": 0.0}, {"gender": 0.0, "cupsize": 1.0, "weight": 1.0},
                   {"gender": 0.0, "age": 0.2}, {"gender": 0.0, "cupsize": 1.0, "firmness": 0.0},
                   {"gender": 0.3, "muscle": 1.0, "weight": 0.0}):  # fmt: skip
        human = Human(params, model=model).dressed("dress")
        dress = library.parts(human.outfit)[0].mesh
        covered = _forward_hits(human.vertices[nipples], dress)
        assert covered.all(), params
    mesh = builtin.BY_NAME["dress"].make(library.authoring_body()).mesh
    marks = library.authoring_body().marks
    top = mesh.vertices[mesh.vertices[:, 2] > marks.neck[2] - 0.03]
    assert (top[:, 0] > 0.05).any() and (top[:, 0] < -0.05).any()  # straps over both shoulders


# ---------------------------------------------------------------------------- hood, openings


def test_hoodie_has_a_hood_lying_on_the_back(body):
    mesh = builtin.BY_NAME["hoodie"].make(body).mesh
    plain = builtin._tights(body, builtin.top(0.95, neck=-0.02, hem=-0.02),
                            builtin.sleeve_ease(0.013, 0.012)).mesh  # fmt: skip
    m = body.marks

    def off_body(v):
        back = (v[:, 1] > m.neck[1] + 0.02) & (v[:, 2] > m.neck[2] - 0.15) & (v[:, 2] < m.neck[2])
        return np.percentile(body.skin_tree.query(v[back])[0], 95)

    assert off_body(mesh.vertices) > off_body(plain.vertices) + 0.02  # a roll, not a shirt
    front = mesh.vertices[(mesh.vertices[:, 1] < m.neck[1] - 0.06)]
    assert np.percentile(body.skin_tree.query(front)[0], 95) < 0.04  # nothing bulky in front


@pytest.mark.parametrize("name", ["jacket", "cardigan"])
def test_jackets_and_cardigans_open_down_the_front(body, name):
    mesh = builtin.BY_NAME[name].make(body).mesh
    m = body.marks
    v = mesh.vertices
    corners = v[mesh.faces]
    across = (corners[..., 0].min(axis=1) < 0) & (corners[..., 0].max(axis=1) > 0)
    assert not (across & (corners[..., 1].mean(axis=1) < m.neck[1] - 0.03)).any()  # open
    middle = (np.abs(v[:, 0]) < 0.008) & (v[:, 1] < m.neck[1] - 0.04)
    assert not middle.any()  # from the collar to the hem, no cloth on the front midline
    sides = (np.abs(v[:, 0]) > 0.03) & (v[:, 1] < m.neck[1] - 0.04)
    assert sides.sum() > 100


def test_thirty_items_across_categories_with_variants():
    specs = builtin.SPECS
    assert len(specs) >= 30
    footwear = {s.name for s in specs if s.category == "footwear"}
    assert {"shoes", "shoes-black", "sneakers", "boots"} <= footwear
    tags = {t for s in specs for t in s.tags}
    assert {"children", "elderly"} <= tags
    boots = builtin.BY_NAME["boots"].make(library.authoring_body()).mesh
    shoes_mesh = builtin.BY_NAME["shoes"].make(library.authoring_body()).mesh
    assert boots.vertices[:, 2].max() > shoes_mesh.vertices[:, 2].max() + 0.03  # above the ankle

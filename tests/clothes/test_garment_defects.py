"""Defects a render sheet showed on the built-in garments (issue 14), measured on the built
meshes and maps: trouser legs belling out in a stride, laces reading as white dashes on
brown shoes, a bucket brim on the cap, knit rows changing direction across a seam."""

from __future__ import annotations

import numpy as np
import pytest

from avatar.clothes.regions import limb_coordinates
from avatar.human import Human
from avatar.rig import kinematics, skinning

ELDERLY_MAN = {"gender": 1.0, "age": 1.0, "weight": 0.6}
WOMAN = {"gender": 0.0, "age": 0.5}


def _mid_stride(human: Human, frame: int = 6):
    """(world (J, 4, 4), skinning matrices (J, 4, 4)) ``frame`` of 24 into the walk (the
    built-in walk, one second at 24 fps)."""
    walk = human.walk(seconds=1.0, fps=24)
    world = kinematics.forward(human.skeleton, walk.rotations[frame:frame + 1],
                               walk.translations[frame:frame + 1])  # fmt: skip
    return world[0], kinematics.skinning_matrices(human.skeleton, world)[0]


def _radius(points: np.ndarray, knee: np.ndarray, ankle: np.ndarray) -> np.ndarray:
    """(N,) m of points (N, 3) from the line through the knee and ankle joints."""
    d = (ankle - knee) / np.linalg.norm(ankle - knee)
    rel = points - knee
    return np.linalg.norm(rel - (rel @ d)[:, None] * d, axis=1)


@pytest.mark.parametrize("name", ["trousers", "jeans"])
@pytest.mark.parametrize("params", [ELDERLY_MAN, WOMAN])
def test_trouser_legs_fall_straight_and_do_not_bell_mid_stride(name, params):
    """A tailored leg is a tube from the knee, a little narrower at the hem. The hem
    stood 9.1 cm round the elderly man's shin axis against 7.4 cm at the knee (ease grown
    down the leg): a bootcut bell, swinging away from the calf in a stride. Measured at
    rest and a quarter into the walk, round each leg's posed knee-ankle axis."""
    from avatar.clothes.authoring import AuthoringBody

    human = Human(params).dressed(name)
    fitted = human.outfit.garments[0]
    count = len(fitted.garment.mesh.vertices)  # the inner layer
    rest = fitted.mesh.vertices[:count].astype(np.float64)
    marks = AuthoringBody(human.body).marks
    _, leg = limb_coordinates(rest, marks)
    world, matrices = _mid_stride(human)
    body = skinning.linear_blend(human.vertices, human.weights, matrices)
    posed = human.outfit.frame(body, matrices, exact=True)[0][:count].astype(np.float64)
    names = human.skeleton.names
    for s, tag in ((0, "L"), (1, "R")):
        mine = np.sign(rest[:, 0]) == (1 if s == 0 else -1)
        knee_ring = mine & (np.abs(leg - 0.5) < 0.03)
        hem = mine & (rest[:, 2] < rest[mine, 2].min() + 0.03)
        knee_r = np.median(_radius(rest[knee_ring], marks.knee[s], marks.ankle[s]))
        hem_rest = np.median(_radius(rest[hem], marks.knee[s], marks.ankle[s]))
        knee = world[names.index(f"lowerleg01.{tag}"), :3, 3]
        ankle = world[names.index(f"foot.{tag}"), :3, 3]
        hem_walk = _radius(posed[hem], knee, ankle)
        assert hem_rest < 1.08 * knee_r, (tag, hem_rest, knee_r)
        assert np.median(hem_walk) < 1.08 * knee_r, (tag, np.median(hem_walk), knee_r)
        assert np.percentile(hem_walk, 95) < 1.25 * knee_r, (tag, hem_walk.max(), knee_r)
        # Still a trouser leg, not a legging: well clear of the ankle.
        assert hem_rest > 0.85 * knee_r


@pytest.mark.parametrize("params", [WOMAN, {"gender": 0.0, "age": 0.6, "weight": 0.9},
                                    {"gender": 1.0, "age": 0.5}])  # fmt: skip
def test_jeans_rise_to_the_waist_not_below_it(params):
    """Jeans rode low on a woman: their waistband's top stood 30% of the way from her hip
    joints to her chest, front and back (the small of the back and the top of the seat
    showed). A mid rise reaches 40% or more of that, a little higher at the back."""
    from avatar.clothes.authoring import AuthoringBody

    human = Human(params).dressed("jeans")
    marks = AuthoringBody(human.body).marks
    fitted = human.outfit.garments[0]
    v = fitted.mesh.vertices[: len(fitted.garment.mesh.vertices)]
    hip = marks.hip[:, 2].mean()
    span = marks.chest_z - hip
    front = v[v[:, 1] < marks.hip[0, 1] - 0.03, 2].max()
    back = v[v[:, 1] > marks.hip[0, 1] + 0.03, 2].max()
    assert (front - hip) / span > 0.4 and (back - hip) / span > 0.4, (front - hip, back - hip)
    assert back >= front - 0.005


def _front_depth(v: np.ndarray, faces: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(P,) y of the front-most cloth (least y) a ray along +y from each (x, z) of points
    (P, 2) meets: what a camera in front sees there (inf where it meets none)."""
    tris = np.concatenate([faces[:, [0, 1, 2]], faces[:, [0, 2, 3]]])
    a, b, c = (v[tris[:, k]] for k in range(3))
    p = points[:, None, :]  # (P, 1, 2) against (T,) triangles in the x-z plane
    ax, az, bx, bz, cx, cz = a[:, 0], a[:, 2], b[:, 0], b[:, 2], c[:, 0], c[:, 2]
    d = (bz - cz) * (ax - cx) + (cx - bx) * (az - cz)
    d = np.where(np.abs(d) < 1e-12, np.nan, d)
    w0 = ((bz - cz) * (p[..., 0] - cx) + (cx - bx) * (p[..., 1] - cz)) / d
    w1 = ((cz - az) * (p[..., 0] - cx) + (ax - cx) * (p[..., 1] - cz)) / d
    w2 = 1 - w0 - w1
    inside = (w0 >= 0) & (w1 >= 0) & (w2 >= 0)
    y = w0 * a[:, 1] + w1 * b[:, 1] + w2 * c[:, 1]
    return np.where(inside, y, np.inf).min(axis=1)


def _fly_setbacks(human: Human, name: str) -> np.ndarray:
    """(R,) m the cloth seen from the front at the midline stands behind the front-most
    cloth between the hip joints' x, in 1 cm rows from 3 to 8 cm above the crotch point:
    how deep a V the cloth makes over the groin, seen from the front."""
    from avatar.clothes.authoring import AuthoringBody

    fitted = human.outfit.garments[0]
    count = len(fitted.garment.mesh.vertices)
    v = fitted.mesh.vertices[:count].astype(np.float64)
    hip = AuthoringBody(human.body).marks.hip
    front = v[:, 1] < hip[0, 1]
    faces = fitted.garment.mesh.faces
    crotch = v[front & (np.abs(v[:, 0]) < 0.015), 2].min()
    reach = abs(hip[0, 0])
    xs = np.concatenate([[-0.005, 0.005], np.linspace(-reach, reach, 19)])  # the middle first
    out = []
    for z in crotch + np.arange(0.03, 0.085, 0.01):
        depth = _front_depth(v, faces, np.stack([xs, np.full_like(xs, z)], axis=1))
        out.append(depth[:2].max() - depth.min())
    return np.array(out)


def _front_faces_turned_back(human: Human) -> int:
    """How many faces of the first garment over the front of the groin (within 6 cm of
    the midline, 4 cm in front of the hip joints, down to 25 cm below them) face back:
    the cloth folded through itself."""
    from avatar.clothes.authoring import AuthoringBody

    fitted = human.outfit.garments[0]
    v = fitted.mesh.vertices[: len(fitted.garment.mesh.vertices)].astype(np.float64)
    faces = fitted.garment.mesh.faces
    hip = AuthoringBody(human.body).marks.hip
    centre = v[faces].mean(axis=1)
    normal = np.cross(v[faces[:, 2]] - v[faces[:, 0]], v[faces[:, 3]] - v[faces[:, 1]])
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-12)
    below = hip[0, 2] - centre[:, 2]
    groin = (np.abs(centre[:, 0]) < 0.06) & (centre[:, 1] < hip[0, 1] - 0.04)
    groin &= (below > 0) & (below < 0.25)
    facing = -np.sign(np.median(normal[groin, 1]))  # most of them face forward (-y)
    return int((groin & (normal[:, 1] * facing > 0.2)).sum())


WOMAN_45, CHILD = {"gender": 0.0, "age": 0.45}, {"age": 0.15}


@pytest.mark.parametrize(("name", "params"), [
    ("sweatpants", WOMAN_45), ("trousers", WOMAN_45), ("shorts", WOMAN_45), ("jeans", WOMAN_45),
    ("sweatpants", CHILD), ("trousers", CHILD), ("shorts", CHILD)])  # fmt: skip
def test_loose_bottoms_span_the_front_of_the_crotch(name, params):
    """Cut from the tights shell, loose trousers followed the groin: seen from the front,
    5-8 cm above the crotch their cloth at the midline stood 44-70 mm (mean of the rows)
    behind the cloth over the thighs, a deep V (a camel toe) on the woman and the child.
    Spanning from thigh to thigh (``builtin.across_the_fly``) it stands less than 3 cm
    behind, and no face over the groin is turned back (2 were on the woman's sweatpants:
    laid flat, the small faces round the crotch seam folded over)."""
    human = Human(params).dressed(name)
    setbacks = _fly_setbacks(human, name)[2:]
    assert np.isfinite(setbacks).all()
    assert setbacks.mean() < 0.03, np.round(setbacks * 1000)
    assert _front_faces_turned_back(human) == 0



def test_childs_sweatpants_cover_the_crotch_point_from_the_front():
    """Just above the crotch point the child's sweatpants left a V open at the midline:
    seen from the front, 3 and 4 cm above it no cloth crossed the midline at all (the
    thighs' cloth, eased for the body's size, not the child's thin thighs, stood apart).
    Eased for the thighs (``limb_ease``) the cloth at the midline there stands less than
    3 cm behind the cloth over the thighs."""
    human = Human(CHILD).dressed("sweatpants")
    setbacks = _fly_setbacks(human, "sweatpants")[:3]  # 3, 4 and 5 cm above the crotch point
    assert np.isfinite(setbacks).all(), np.round(setbacks * 1000)
    assert setbacks.max() < 0.03, np.round(setbacks * 1000)


def _fly_turns(human: Human, frames=range(2, 12, 2)) -> np.ndarray:
    """(frames,) degrees: the most any two neighbouring faces of the first garment over
    the fly (facing forward at rest, between the hip joints' x, from the crotch point up
    10 cm) turned further against each other than at rest, in each of the walk's
    ``frames`` (of 24): the cloth creased or folded over there."""
    from avatar.clothes.authoring import AuthoringBody, face_pairs

    fitted = human.outfit.garments[0]
    count = len(fitted.garment.mesh.vertices)
    faces = fitted.garment.mesh.faces
    rest = fitted.mesh.vertices[:count].astype(np.float64)
    hip = AuthoringBody(human.body).marks.hip
    centre = rest[faces].mean(axis=1)
    crotch = rest[(rest[:, 1] < hip[0, 1]) & (np.abs(rest[:, 0]) < 0.015), 2].min()

    def normals(v):
        n = np.cross(v[faces[:, 2]] - v[faces[:, 0]], v[faces[:, 3]] - v[faces[:, 1]])
        return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)

    def angles(n):
        return np.degrees(np.arccos(np.clip(np.einsum("nd,nd->n", n[first], n[second]), -1, 1)))

    n0 = normals(rest)
    outward = np.sign(np.einsum("nd,nd->", n0, centre - rest.mean(axis=0)))
    fly = (np.abs(centre[:, 0]) < abs(hip[0, 0])) & (n0[:, 1] * outward < -0.3)
    fly &= (centre[:, 2] > crotch) & (centre[:, 2] < crotch + 0.10)
    first, second = face_pairs(faces)
    first, second = first[fly[first] & fly[second]], second[fly[first] & fly[second]]
    at_rest = angles(n0)
    out = []
    for frame in frames:
        _, matrices = _mid_stride(human, frame)
        body = skinning.linear_blend(human.vertices, human.weights, matrices)
        posed = human.outfit.frame(body, matrices, exact=True)[0][:count].astype(np.float64)
        out.append((angles(normals(posed)) - at_rest).max())
    return np.array(out)


HEAVY_MAN = {"gender": 1.0, "weight": 0.9, "age": 0.6}


@pytest.mark.parametrize(("name", "params"), [
    ("shorts", HEAVY_MAN), ("sweatpants", HEAVY_MAN), ("trousers", HEAVY_MAN),
    ("shorts", CHILD), ("sweatpants", WOMAN_45)])  # fmt: skip
def test_the_fly_moves_as_one_piece_mid_stride(name, params):
    """Laid across the front of the crotch (``across_the_fly``), the bridge kept the skin
    weights of the groin under it: its left half followed the left thigh, its right half
    the right, a few cm off the skin. Mid-stride the legs swung them apart and together
    and the heavy man's shorts crumpled into a pinch at the top of the crotch: two faces
    there turned 101-110 degrees further against each other than at rest (heavy man's
    shorts, sweatpants, trousers; the child's shorts). Its halves sharing their weights
    (``builtin.fly_share``, all of them in frames), no two turn more than 60 (20-37)."""
    turns = _fly_turns(Human(params).dressed(name))
    assert turns.max() < 60, np.round(turns)


def _on_surface(mesh, uv_points: np.ndarray) -> np.ndarray:
    """(N, 3) points of a quad mesh with per-corner UVs under texture points (N, 2) (NaN
    where no face covers one)."""
    tri = np.concatenate([mesh.faces[:, [0, 1, 2]], mesh.faces[:, [0, 2, 3]]])
    corners = np.concatenate([mesh.face_uvs[:, [0, 1, 2]], mesh.face_uvs[:, [0, 2, 3]]])
    a, b, c = (mesh.uvs[corners[:, k]].astype(np.float64) for k in range(3))
    e1, e2 = b - a, c - a
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    usable = np.abs(det) > 1e-12
    out = np.full((len(uv_points), 3), np.nan)
    for i, p in enumerate(uv_points):
        d = p - a
        with np.errstate(divide="ignore", invalid="ignore"):
            s = (d[:, 0] * e2[:, 1] - d[:, 1] * e2[:, 0]) / det
            t = (e1[:, 0] * d[:, 1] - e1[:, 1] * d[:, 0]) / det
            inside = usable & (s >= -1e-6) & (t >= -1e-6) & (s + t <= 1 + 1e-6)
        if inside.any():
            j = np.flatnonzero(inside)[0]
            x = mesh.vertices[tri[j]].astype(np.float64)
            out[i] = x[0] + s[j] * (x[1] - x[0]) + t[j] * (x[2] - x[0])
    return out


def test_trouser_creases_run_in_one_sweep_past_the_knee():
    """A pressed crease is one straight sweep down the leg. Painted midway between its
    panel's edges, which step with the helper mesh's faces, it jogged sideways 8-10 mm
    at the knee. Found on the built trousers' surface under the crease marks' UVs: within
    15 cm of the knee it strays under 2 mm sideways from a smooth (quadratic) line."""
    from avatar.clothes import builtin, library

    body = library.authoring_body()
    piece = builtin.BY_NAME["trousers"].make(body)
    creases = [m for m in piece.layout.marks if m.kind == "crease"]
    assert len(creases) == 4
    knee = body.marks.knee[0, 2]
    for mark in creases:
        p = _on_surface(piece.mesh, np.asarray(mark.points, np.float64))
        p = p[np.isfinite(p[:, 0]) & (np.abs(p[:, 2] - knee) < 0.15)]
        assert len(p) > 10
        sideways = p[:, 0] - np.polyval(np.polyfit(p[:, 2], p[:, 0], 2), p[:, 2])
        assert np.abs(sideways).max() < 0.002, np.abs(sideways).max()


# ---------------------------------------------------------------------------- shoes


def _luminance(srgb: np.ndarray) -> np.ndarray:
    c = srgb[..., :3].astype(np.float64) / 255
    c = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    return c @ [0.2126, 0.7152, 0.0722]


def _texels(material, mesh, corners: np.ndarray) -> np.ndarray:
    """(N, 3) base colour texels under the UVs of mesh corners (N,) (face_uvs entries)."""
    image = material.base_color_texture
    size = image.shape[0]
    uv = mesh.uvs[corners]
    rows = np.clip(((1 - uv[:, 1]) * size).astype(int), 0, size - 1)
    cols = np.clip((uv[:, 0] * size).astype(int), 0, size - 1)
    return image[rows, cols]


def _lightness(luminance: np.ndarray) -> np.ndarray:
    """CIE L* (0-100) of linear luminance."""
    return np.where(luminance > 216 / 24389, 116 * np.cbrt(luminance) - 16,
                    luminance * 24389 / 27)  # fmt: skip


def _row_texels(garment, row: str) -> np.ndarray:
    """(N, 3) base colour texels under the UVs of the corners in one shoe atlas row."""
    from avatar.clothes import shoes

    mesh = garment.mesh
    v0, v1 = shoes.ROWS[row]
    corner_v = mesh.uvs[mesh.face_uvs.ravel(), 1]
    corners = mesh.face_uvs.ravel()[(corner_v >= v0) & (corner_v < v1)]
    return _texels(garment.material, mesh, corners)


@pytest.mark.parametrize("name", ["shoes", "shoes-black", "boots", "sneakers"])
def test_laces_read_against_the_upper_but_are_not_white_dashes(name):
    """Laces and the welt/cap stitching: black laces on a black upper vanished (no
    contrast), cream laces and near-white stitches on brown read as white dashes. Laces
    stand 12-30 L* off the upper, leather shoes' laces stay below L* 60, and no leather
    texel is near-white. Sampled from the built material under the pieces' own UVs."""
    from avatar.clothes import builtin, library, shoes

    garment = builtin.build(builtin.BY_NAME[name], library.authoring_body(), 256)
    lace = np.median(_lightness(_luminance(_row_texels(garment, "laces"))))
    upper = np.median(_lightness(_luminance(_row_texels(garment, "upper"))))
    assert 12 < abs(lace - upper) < 30, (lace, upper)
    if name != "sneakers":
        assert lace < 60, lace
        image = garment.material.base_color_texture
        leather = image[: int(round((1 - shoes.ROWS["cap"][0]) * image.shape[0]))]
        assert np.percentile(_luminance(leather), 99.9) < 0.45


SHOD = [{"gender": 0.3, "age": 0.12}, {"gender": 1.0, "age": 0.5},
        {"gender": 0.0, "age": 0.7, "weight": 1.0},
        {"gender": 1.0, "age": 1.0, "muscle": 0.9}]  # fmt: skip


@pytest.mark.parametrize("params", SHOD)
def test_soles_are_thin_with_a_heel_block_and_toe_spring(params):
    """The sole's edge as worn, on a child to a heavy woman: 2-3 cm tall all round
    before (8 mm of tread under the foot plus the upper's ragged edge up to 1.5 cm above
    the ground; 2.6 cm at the ball), a clog's slab. Now under 1.8 cm at the ball, taller at the
    heel (a heel block), the tread curling up at the toe's tip, the edge an inked dark
    leather, not grey rubber."""
    from avatar.clothes import shoes
    from avatar.clothes.authoring import AuthoringBody

    human = Human(params).dressed("shoes")
    fitted = human.outfit.garments[0]
    mesh = fitted.garment.mesh
    v = fitted.mesh.vertices[: len(mesh.vertices)].astype(np.float64)
    corner_v = mesh.uvs[mesh.face_uvs, 1]
    sole_faces = np.all((corner_v >= shoes.ROWS["sole"][0]) & (corner_v < shoes.ROWS["sole"][1]),
                        axis=1)  # fmt: skip
    body = AuthoringBody(human.body)
    for side in (0, 1):
        foot = shoes.Foot(body, side)
        mine = np.zeros(len(v), bool)
        mine[np.unique(mesh.faces[sole_faces])] = True
        mine &= np.sign(v[:, 0]) == (1 if side == 0 else -1)
        p, t = v[mine], foot.along(v[mine])
        tread = p[:, 2].min()
        ball = p[(t > 0.65) & (t < 0.82)]
        heel = p[t < 0.15]
        tip = p[t > t.max() - 0.015]  # the front of the toe box
        # (the heights include the sole's lip tucked 1 mm up inside the upper)
        assert np.ptp(ball[:, 2]) < 0.018, np.ptp(ball[:, 2])
        assert np.ptp(heel[:, 2]) > np.ptp(ball[:, 2]) + 0.003
        # Toe spring: 1.5% of the foot's length (4 mm on a man's foot) off the ground.
        assert tip[:, 2].min() > tread + 0.015 * (foot.heel_y - foot.toe_y), tip[:, 2] - tread
    sole = _lightness(_luminance(_row_texels(fitted.garment, "sole")))
    assert np.median(sole) < 20, np.median(sole)


@pytest.mark.parametrize("params", [{"gender": 1.0, "age": 0.5}, {"gender": 1.0, "age": 1.0}])
def test_socks_stay_inside_the_shoe(params):
    """Smoothing the toe box pulled the upper in over the little toe's joint, where the
    tights shell (and a sock cut from it) stands well off the skin: the sock's outer
    surface stood 6.2 mm outside the upper's inner layer (a white patch behind the toe
    cap). Below the shoe's opening every sock point stays within the shoe's cloth (its
    2.5 mm) of the upper's inner layer."""
    from avatar.clothes import library, shoes
    from avatar.geometry import collision

    body = library.authoring_body()
    foot = shoes.Foot(body, 0)
    # The upper as worn (without its faces under the toe cap) and the cap: the sock's cover.
    worn_upper = shoes.capped(body, foot, shoes.upper(body, foot))
    upper_count = sum(len(p.mesh.vertices) for p in worn_upper)
    human = Human(params).dressed("socks", "shoes")
    worn = {g.name: g for g in human.outfit.garments}
    shoe, sock = worn["shoes"], worn["socks"]
    faces = shoe.garment.mesh.faces
    upper = faces[np.all(faces < upper_count, axis=1)]  # the left upper and cap come first
    v = shoe.mesh.vertices[:upper_count].astype(np.float64)
    outer = sock.mesh.vertices[len(sock.garment.mesh.vertices):].astype(np.float64)
    ground = human.vertices[:13380, 2].min()
    low = outer[(outer[:, 0] > 0) & (outer[:, 2] < ground + 0.035)]
    out = collision.query(v, collision.skin_surface(upper), low, k=4).distance
    assert out.max() < shoe.garment.thickness, out.max()


def test_low_shoes_end_below_the_ankle_bones_and_boots_above():
    """A low shoe's top line runs under the ankle bones at the sides and at a heel
    counter's height behind (it was cut level 11 cm up, over the ankle joint: an ankle
    boot); the ankle boot still covers the ankle."""
    from avatar.clothes import library, shoes
    from avatar.geometry.shell import boundary_edges

    body = library.authoring_body()
    for side in (0, 1):
        foot = shoes.Foot(body, side)
        for top, boot in ((0.96, False), (0.86, True)):
            mesh = shoes.upper(body, foot, top).mesh
            rim = np.unique(boundary_edges(mesh.faces)[0])
            rim = rim[mesh.vertices[rim, 2] > foot.ground + 0.03]  # the opening, not the sole's
            height = mesh.vertices[rim, 2] - foot.ground
            along = foot.along(mesh.vertices[rim])
            sides = (along > 0.15) & (along < 0.35)
            heel = along < 0.08
            ankle = foot.ankle[2] - foot.ground
            if boot:
                assert height.min() > ankle + 0.01
            else:
                assert sides.any() and heel.any()
                assert np.median(height[sides]) < ankle - 0.015, (height[sides], ankle)
                assert np.median(height[heel]) < ankle
                assert np.median(height[heel]) > np.median(height[sides])  # a heel counter


# ---------------------------------------------------------------------------- cap


def test_cap_brim_is_a_visor_in_front_not_a_bucket():
    """The brim reaches forward from the forehead as wide as the head, curving down a
    little at its sides: reaching out radially round the crown it stood 2.7 cm past each
    side of the head (a bucket hat's brim). On two heads."""
    from avatar.body.model import BODY_VERTICES
    from avatar.clothes import headwear
    from avatar.clothes.authoring import AuthoringBody

    for params in (ELDERLY_MAN, {"gender": 0.5, "age": 0.15}):
        body = AuthoringBody(Human(params).body)
        crown, rim = headwear.crown(body)
        v = headwear.brim(body, crown, rim).vertices.astype(np.float64)
        head = body.vertices[:BODY_VERTICES][body.part[:BODY_VERTICES] == "head"]
        centre, eye_z, _ = headwear._frame(body)
        half_width = np.abs(head[:, 0]).max()
        assert np.abs(v[:, 0]).max() < half_width  # no wider than the head
        assert v[:, 1].max() < centre[1] - 0.025  # all in front, well ahead of the ears
        assert v[:, 1].min() < head[:, 1].min() - 0.05  # still a visor's reach
        # A flat-ish pre-curved plate: its edge drops at most 2.5 cm from middle to sides.
        edge = v[v[:, 1] < v[:, 1].min() + 0.01]
        assert np.ptp(v[:, 2]) < 0.045 and np.ptp(edge[:, 2]) < 0.025


def _height_under(faces_xyz: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(N,) z of the highest of triangles (T, 3, 3) above or below each point's (N, 3) xy;
    NaN where none covers it."""
    a, b, c = (faces_xyz[:, k, None, :] for k in range(3))  # (T, 1, 3)
    p = points[None, :, :2]
    with np.errstate(divide="ignore", invalid="ignore"):  # edge-on triangles cover nothing
        return _cover(a, b, c, p)


def _cover(a, b, c, p):
    d = (b[..., 1] - c[..., 1]) * (a[..., 0] - c[..., 0]) + (c[..., 0] - b[..., 0]) * (
        a[..., 1] - c[..., 1])
    w0 = ((b[..., 1] - c[..., 1]) * (p[..., 0] - c[..., 0])
          + (c[..., 0] - b[..., 0]) * (p[..., 1] - c[..., 1])) / d  # fmt: skip
    w1 = ((c[..., 1] - a[..., 1]) * (p[..., 0] - c[..., 0])
          + (a[..., 0] - c[..., 0]) * (p[..., 1] - c[..., 1])) / d  # fmt: skip
    w2 = 1 - w0 - w1
    z = w0 * a[..., 2] + w1 * b[..., 2] + w2 * c[..., 2]
    inside = (w0 >= -1e-6) & (w1 >= -1e-6) & (w2 >= -1e-6)
    return np.where(inside, z, -np.inf).max(axis=0)


@pytest.mark.parametrize("params", [ELDERLY_MAN, {"gender": 0.5, "age": 0.15},
                                    {"gender": 0.0, "age": 0.5, "weight": 0.9}])  # fmt: skip
def test_cap_band_sits_on_the_brim_without_a_slit(params):
    """The crown's sweatband stands 1.5 mm proud of the crown; the brim was attached 2 mm
    under the crown's rim: a slit between the band's lower edge and the brim's top that
    rendered as a dark line across the forehead. Over the brim, every vertex of the band's
    lower edge lies on or just inside the brim's top surface, and the brim runs on under
    the crown (its inner edge inside the band), on a child, a man and a heavy woman."""
    from avatar.clothes import headwear
    from avatar.clothes.authoring import AuthoringBody, banded

    body = AuthoringBody(Human(params).body)
    crown, rim = headwear.crown(body)
    band = banded(crown, 0.014, 0.0015).vertices[len(crown.vertices):].astype(np.float64)
    brim = headwear.brim(body, crown, rim)
    v = brim.vertices.astype(np.float64)
    corners = v[brim.faces]
    normal = np.cross(corners[:, 2] - corners[:, 0], corners[:, 3] - corners[:, 1])
    top = normal[:, 2] > 0.5 * np.linalg.norm(normal, axis=1)
    triangles = np.concatenate([corners[top][:, [0, 1, 2]], corners[top][:, [0, 2, 3]]])
    centre, _, _ = headwear._frame(body)
    # The band's lower edge over the middle of the brim (its ends taper to nothing).
    rim_z = crown.vertices[rim, 2].astype(np.float64)
    lowest = band[np.abs(band[:, 2][:, None] - rim_z[None]).min(axis=1) < 0.003]
    phi = np.degrees(np.arctan2(lowest[:, 0] - centre[0], -(lowest[:, 1] - centre[1])))
    front = lowest[np.abs(phi) < headwear.BRIM_SPAN - 20]
    assert len(front) > 10
    surface = _height_under(triangles, front)
    assert np.isfinite(surface).all(), "the brim does not reach under the band"
    step = surface - front[:, 2]
    assert step.min() > -0.0003, step.min()  # no slit: band edge not above the brim
    assert step.max() < 0.003, step.max()  # ... nor buried deep in it


@pytest.mark.parametrize("params", [None, {"gender": 0.0, "age": 0.12},
                                    {"gender": 1.0, "weight": 1.0, "muscle": 0.8}])  # fmt: skip
def test_hood_roll_runs_level_round_the_back_of_the_neck(params):
    """Seen from behind, the hood's rolled edge lies level round the back and sides of
    the neck. Pushed clear of the skin along its normal, which points up the trapezius'
    slope, it rose 1.2-3.1 cm from the back's middle into horns either side of the neck,
    a lumpy roll. Its top, in 6-degree steps round the back half: within 1 cm."""
    from avatar.clothes import builtin, library
    from avatar.clothes.authoring import AuthoringBody

    body = library.authoring_body() if params is None else AuthoringBody(Human(params).body)
    m = body.marks
    hoodie = builtin._tights(body, builtin.top(0.95, neck=-builtin.HOODIE_NECK, hem=-0.02),
                             builtin.sleeve_ease(0.013, 0.012), 0.03)  # fmt: skip
    v = builtin._hood_collar(body, hoodie.mesh).mesh.vertices.astype(np.float64)
    angle = np.degrees(np.arctan2(v[:, 0], m.neck[1] - v[:, 1]))
    tops = [v[(angle >= lo) & (angle < lo + 6), 2].max()
            for lo in range(-180, 180, 6) if abs(lo + 3) > 75]
    assert np.ptp(tops) < 0.01, np.round((np.array(tops) - tops[0]) * 1000, 1)


# ---------------------------------------------------------------------------- swimsuit


@pytest.mark.parametrize("name", ["swimsuit", "leggings"])
def test_stretch_garments_hug_the_seat(name):
    """Lycra lies on the skin: over the seat a swimsuit or leggings stood 6.6 mm off it
    all round (the tights shell's own distance), baggy. Signed distances to the skin
    surface on a teen and a heavy woman, at rest; nothing inside."""
    from avatar.clothes.authoring import AuthoringBody
    from avatar.geometry import collision

    for params in ({"gender": 0.0, "age": 0.3, "weight": 0.35},
                   {"gender": 0.0, "age": 0.6, "weight": 1.0}):  # fmt: skip
        human = Human(params).dressed(name)
        fitted = human.outfit.garments[0]
        v = fitted.mesh.vertices[: len(fitted.garment.mesh.vertices)].astype(np.float64)
        marks = AuthoringBody(human.body).marks
        base = human.model.base
        surface = collision.skin_surface(base.faces[base.face_groups["body"]])
        off = collision.query(human.vertices[:13380], surface, v, k=4).distance
        hip_z = marks.hip[0, 2]
        seat = (v[:, 1] > marks.hip[0, 1]) & (v[:, 2] > hip_z - 0.1) & (v[:, 2] < hip_z + 0.05)
        assert seat.sum() > 10
        assert np.median(off[seat]) < 0.004, (params, np.median(off[seat]))
        assert off.min() > -0.001


# ---------------------------------------------------------------------------- knit


def _v_gradients(mesh) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(face centres (F, 3), unit 3D directions in which the texture's v grows (F, 3),
    usable (F,) bool: faces with real area in space and in UV, not a band's lip)."""
    v = mesh.vertices[mesh.faces].astype(np.float64)
    uv = mesh.uvs[mesh.face_uvs].astype(np.float64)
    e1, e2 = v[:, 1] - v[:, 0], v[:, -1] - v[:, 0]
    n = np.cross(e1, e2)
    system = np.stack([e1, e2, n], 1)
    usable = (np.linalg.norm(n, axis=1) > 2e-5) & (np.abs(np.cross(uv[:, 1] - uv[:, 0],
                                                                   uv[:, -1] - uv[:, 0])) > 1e-4)
    rhs = np.stack([uv[:, 1, 1] - uv[:, 0, 1], uv[:, -1, 1] - uv[:, 0, 1], np.zeros(len(v))], 1)
    g = np.zeros_like(n)
    g[usable] = np.linalg.solve(system[usable], rhs[usable][..., None])[..., 0]
    g /= np.maximum(np.linalg.norm(g, axis=1, keepdims=True), 1e-12)
    return v.mean(axis=1), g, usable


@pytest.mark.parametrize("name", ["cardigan", "longsleeve", "tshirt"])
def test_knit_rows_turn_over_only_at_the_shoulder_ridge(name):
    """A knit's V-loops follow the texture's v: up the front and up the back, meeting
    head to head along the shoulders' ridge as at a shoulder seam. The faces on top of
    the shoulders took v = y, so the loops turned over at the back of the shoulders
    instead (a chevron across the upper back)."""
    from avatar.clothes import builtin, library

    body = library.authoring_body()
    m = body.marks
    mesh = builtin.BY_NAME[name].make(body).mesh
    centre, g, usable = _v_gradients(mesh)
    ridge = float(m.shoulder[:, 1].mean())
    shoulders = (usable & (centre[:, 2] > m.shoulder[0, 2] - 0.04)
                 & (np.abs(centre[:, 0]) < abs(m.shoulder[0, 0]))
                 & (np.abs(centre[:, 1] - ridge) > 0.025))  # fmt: skip
    assert shoulders.sum() > 20
    towards_ridge = np.zeros((shoulders.sum(), 3))
    towards_ridge[:, 1] = np.sign(ridge - centre[shoulders, 1])
    towards_ridge[:, 2] = 1.0
    rising = np.einsum("nd,nd->n", g[shoulders], towards_ridge) > 0
    assert rising.mean() > 0.97, centre[shoulders][~rising].round(3)


def _tilt_degrees(normal: np.ndarray, metres: float, finest: float) -> tuple[float, float]:
    """(RMS normal tilt in degrees carried by relief finer than ``finest`` m, and by relief
    coarser) of a tangent-space normal map (S, S, 3) uint8 covering ``metres`` of cloth."""
    tilt = normal[..., :2].astype(np.float64) / 127.5 - 1
    tilt -= tilt.mean(axis=(0, 1))
    size = normal.shape[0]
    power = (np.abs(np.fft.fft2(tilt, axes=(0, 1))) ** 2).sum(-1) / size**4
    f = np.fft.fftfreq(size) * size / metres  # cycles per metre
    fine = np.hypot(*np.meshgrid(f, f)) > 1 / finest
    return tuple(float(np.degrees(np.arcsin(np.sqrt(min(p, 1.0)))))
                 for p in (power[fine].sum(), power[~fine].sum()))  # fmt: skip


@pytest.mark.parametrize("name", ["tshirt", "cardigan", "hoodie", "longsleeve", "socks"])
def test_knit_and_cotton_relief_does_not_alias_at_render_distance(name):
    """On a full figure a pixel spans 1-1.5 mm of cloth and Cycles has no mipmaps: relief
    finer than 3.5 mm beats into moire. The knit's 2.8 mm rows and the cotton's 1.1 mm
    threads carried 48-58 degrees of RMS normal tilt (zig-zag bands on the cardigan, a
    shimmer on the T-shirt); now under 9 degrees, while the cardigan's and hoodie's
    chunky knit keeps its stitches in the coarser relief."""
    from avatar.clothes import library
    from avatar.looks import fabrics

    material = library.load_garment(name, texture_size=512).material
    fine, coarse = _tilt_degrees(material.normal_texture, fabrics.TILE_METRES, 0.0035)
    assert fine < 9, (fine, coarse)
    if material.extras["fabric"] == "knit":
        assert coarse > 20, coarse


@pytest.mark.parametrize("name", ["cardigan", "jacket", "tshirt", "longsleeve"])
def test_loose_tops_bridge_the_cleft_of_the_buttocks(name):
    """Cut from the tights shell, a long top followed the cleft of the buttocks: a vertex
    9 mm (cardigan), 8.6 mm (jacket), 6.9 mm (T-shirt) sunk below its neighbours, a
    pocket that rendered as a black hole on the lower back. Over the seat and the small
    of the back no vertex sinks more than 3.5 mm below the mean of its neighbours."""
    from avatar.clothes import builtin, library

    body = library.authoring_body()
    mesh = builtin.BY_NAME[name].make(body).mesh
    v = mesh.vertices.astype(np.float64)
    a, b = mesh.faces.reshape(-1), np.roll(mesh.faces, -1, axis=1).reshape(-1)
    degree = np.bincount(a, minlength=len(v)) + np.bincount(b, minlength=len(v))
    total = np.zeros_like(v)
    np.add.at(total, a, v[b])
    np.add.at(total, b, v[a])
    sunk = np.einsum("nd,nd->n", total / np.maximum(degree, 1)[:, None] - v, body.outward(v))
    from avatar.geometry.shell import boundary_edges

    hip = body.marks.hip[0]
    seat = (v[:, 1] > hip[1]) & (v[:, 2] < hip[2] + 0.12)
    seat[boundary_edges(mesh.faces)[0].ravel()] = False  # an edge has neighbours on one side
    assert seat.sum() > 20
    assert sunk[seat].max() < 0.0035, sunk[seat].max()


# ---------------------------------------------------------------------------- dress


def _outer_surface_clearance(human: Human, frames, keep=None) -> list[float]:
    """Per walk frame, the least signed distance (m) from the skin of the first garment's
    outer cloth layer as rendered: dense samples on both triangulations of every quad
    (``keep``: a (F,) mask of those faces, by their rest positions)."""
    from avatar.geometry import collision

    fitted = human.outfit.garments[0]
    count = len(fitted.garment.mesh.vertices)
    outer = np.all(fitted.mesh.faces >= count, axis=1)
    if keep is not None:
        outer &= keep(fitted.mesh.vertices[fitted.mesh.faces].mean(axis=1))
    faces = fitted.mesh.faces[outer]
    base = human.model.base
    surface = collision.skin_surface(base.faces[base.face_groups["body"]])
    t = np.linspace(0, 1, 7)
    a, b = np.meshgrid(t, t)
    inside = a + b <= 1
    a, b = a[inside], b[inside]
    out = []
    for frame in frames:
        _, matrices = _mid_stride(human, frame)
        body = skinning.linear_blend(human.vertices, human.weights, matrices)
        corners = human.outfit.frame(body, matrices, exact=True)[0].astype(np.float64)[faces]
        least = np.inf
        for tri in ((0, 1, 2), (0, 2, 3), (0, 1, 3), (1, 2, 3)):
            p0, p1, p2 = (corners[:, k] for k in tri)
            points = (p0[:, None] + a[None, :, None] * (p1 - p0)[:, None]
                      + b[None, :, None] * (p2 - p0)[:, None]).reshape(-1, 3)  # fmt: skip
            q = collision.query(body[:13380].astype(np.float64), surface, points, k=4)
            least = min(least, float(q.distance.min()))
        out.append(least)
    return out


def test_no_skin_shows_through_the_dress_mid_stride():
    """The forward knee pushed into the skirt between its vertices (each kept clear of
    the skin, the faces between them 3-4 cm wide): the rendered triangles of both cloth
    layers dipped 1.2 and 2.5 mm into the knee, a speck of skin on the skirt. The dress's
    outer surface stays outside the skin through the stride."""
    human = Human({"gender": 0.0, "age": 0.5, "weight": 0.5}).dressed("dress")
    clearance = _outer_surface_clearance(human, (4, 6, 8))
    assert min(clearance) > 0.0, clearance


@pytest.mark.parametrize(("name", "params"), [
    ("swimsuit", {"gender": 0.0, "age": 0.3, "weight": 0.35}),
    ("leggings", {"gender": 0.0, "age": 0.95, "weight": 0.6}),
])  # fmt: skip
def test_no_skin_shows_through_snug_garments_from_behind_mid_stride(name, params):
    """Laid closer to the skin, a swimsuit's seat and leggings' calves showed specks of
    skin mid-stride (2 mm into the outer layer between vertices): the seat, the backs of
    the thighs and calves stay covered (the crotch's pinched fold aside)."""
    from avatar.clothes.authoring import AuthoringBody

    human = Human(params).dressed(name)
    hip = AuthoringBody(human.body).marks.hip[0]

    def behind(c):  # the swimsuit's gusset, pinched between the thighs, aside
        gusset = (np.abs(c[:, 0]) < 0.06) & (c[:, 2] < hip[2] - 0.02) & (name == "swimsuit")
        return (c[:, 1] > hip[1] + 0.02) & ~gusset

    clearance = _outer_surface_clearance(human, (6, 18), behind)
    assert min(clearance) > 0.0, clearance


def _outer_profile(human: Human, sectors: int = 24, dz: float = 0.005) -> np.ndarray:
    """(sectors, Z) the largest offset from the skin (m) of the first garment's outer
    cloth surface, per sector round the waist and per ``dz`` band of height from 2 cm
    under to 22 cm over the hip joints (NaN where none): the dress's silhouette there."""
    from avatar.clothes.authoring import AuthoringBody
    from avatar.geometry import collision

    fitted = human.outfit.garments[0]
    count = len(fitted.garment.mesh.vertices)
    faces = fitted.mesh.faces[np.all(fitted.mesh.faces >= count, axis=1)]
    v = fitted.mesh.vertices.astype(np.float64)
    tri = np.concatenate([faces[:, [0, 1, 2]], faces[:, [0, 2, 3]]])
    t = np.linspace(0, 1, 12)
    a, b = np.meshgrid(t, t)
    a, b = a[a + b <= 1], b[a + b <= 1]
    p0, p1, p2 = v[tri[:, 0]], v[tri[:, 1]], v[tri[:, 2]]
    points = (p0[:, None] + a[None, :, None] * (p1 - p0)[:, None]
              + b[None, :, None] * (p2 - p0)[:, None]).reshape(-1, 3)  # fmt: skip
    hip = AuthoringBody(human.body).marks.hip[:, 2].mean()
    points = points[(points[:, 2] > hip - 0.02) & (points[:, 2] < hip + 0.22)]
    base = human.model.base
    surface = collision.skin_surface(base.faces[base.face_groups["body"]])
    off = collision.query(human.vertices[:13380].astype(np.float64), surface, points,
                          k=4).distance  # fmt: skip
    centre = points.mean(axis=0)
    angle = np.arctan2(points[:, 0] - centre[0], -(points[:, 1] - centre[1])) + np.pi
    sector = (angle / (2 * np.pi) * sectors).astype(int) % sectors
    band = ((points[:, 2] - hip + 0.02) / dz).astype(int)
    profile = np.full((sectors, int(0.24 / dz) + 1), -1.0)
    np.maximum.at(profile, (sector, band), off)
    return np.where(profile < 0, np.nan, profile)


@pytest.mark.parametrize("params", [{"gender": 0.0, "age": 0.3}, {"gender": 0.0, "weight": 0.7},
                                    {"gender": 0.0, "age": 0.6, "weight": 1.0},
                                    {"gender": 0.3, "age": 0.15}])  # fmt: skip
def test_dress_runs_on_from_bodice_to_skirt_without_a_ledge(params):
    """The dress's silhouette round the waist, 5 mm band by band: the skirt's top stood
    8-11 mm proud of its bodice (kept 1 cm outside the bodice's tucked hem, its edge
    closing onto the bodice only where the helper skirt's top is highest, at the back,
    and bound to the helper skirt, which meets the bodice on the authoring body only).
    From a child to a heavy woman no step between bands exceeds 4 mm now."""
    human = Human(params).dressed("dress")
    step = np.abs(np.diff(_outer_profile(human), axis=1))
    assert np.nanmax(step) < 0.004, np.round(np.nanmax(step, axis=1) * 1000, 1)


def _seen_from_behind(v: np.ndarray, quads: np.ndarray, xs: np.ndarray,
                      zs: np.ndarray) -> np.ndarray:  # fmt: skip
    """(X, Z) y of the surface of quads (F, 4) over v (N, 3) nearest a camera behind the
    body (largest y) along the horizontal lines at xs (X,) and heights zs (Z,), NaN where
    no face covers a line: the profile a render from behind shows."""
    tri = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    a, b, c = v[tri[:, 0]], v[tri[:, 1]], v[tri[:, 2]]
    lo, hi = np.minimum(np.minimum(a, b), c), np.maximum(np.maximum(a, b), c)
    e1, e2 = (b - a)[:, [0, 2]], (c - a)[:, [0, 2]]
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    det = np.where(np.abs(det) < 1e-14, np.inf, det)  # edge-on faces hit nothing
    out = np.full((len(xs), len(zs)), np.nan)
    for i, x in enumerate(xs):
        across = (lo[:, 0] <= x) & (hi[:, 0] >= x)
        for j, z in enumerate(zs):
            near = np.flatnonzero(across & (lo[:, 2] <= z) & (hi[:, 2] >= z))
            d = np.array([x, z]) - a[near][:, [0, 2]]
            s = (d[:, 0] * e2[near, 1] - d[:, 1] * e2[near, 0]) / det[near]
            t = (e1[near, 0] * d[:, 1] - e1[near, 1] * d[:, 0]) / det[near]
            hit = (s >= 0) & (t >= 0) & (s + t <= 1)
            if hit.any():
                y = a[near, 1] + s * (b[near, 1] - a[near, 1]) + t * (c[near, 1] - a[near, 1])
                out[i, j] = y[hit].max()
    return out


def _skirt_vertices(fitted) -> np.ndarray:
    """(M,) bool: the dress's skirt (the second of its two pieces, both cloth layers)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    mesh = fitted.garment.mesh
    n, faces = len(mesh.vertices), mesh.faces
    rows = np.repeat(np.arange(len(faces)), faces.shape[1])
    incidence = coo_matrix((np.ones(len(rows)), (rows, faces.ravel())), shape=(len(faces), n))
    _, piece = connected_components((incidence.T @ incidence).tocsr(), directed=False)
    return np.tile(piece == piece[-1], len(fitted.mesh.vertices) // n)


def _waist_seam_turn(human: Human, frame: int | None) -> float:
    """Degrees: the worst turn, from behind, of the dress's surface across its waist seam:
    along five vertical lines 0-6 cm either side of the back's middle, between the slope
    over the centimetre under and over each height within 3 cm of the skirt's top edge."""
    fitted = human.outfit.garments[0]
    v = fitted.mesh.vertices.astype(np.float64)
    skin = human.vertices.astype(np.float64)
    if frame is not None:
        _, matrices = _mid_stride(human, frame)
        skin = skinning.linear_blend(human.vertices, human.weights, matrices)
        v = human.outfit.frame(skin, matrices, exact=True)[0].astype(np.float64)
    middle = skin[:13380, 0].mean()
    xs = middle + np.array([-0.06, -0.03, 0.0, 0.03, 0.06])
    back = _skirt_vertices(fitted) & (v[:, 1] > v[:, 1].mean()) & (np.abs(v[:, 0] - middle) < 0.07)
    edge = v[back, 2].max()
    zs = np.arange(edge - 0.03, edge + 0.03, 0.002)
    y = _seen_from_behind(v, fitted.mesh.faces, xs, zs)
    span = 5  # samples: 1 cm
    under = np.arctan((y[:, span:-span] - y[:, : -2 * span]) / (span * 0.002))
    over = np.arctan((y[:, 2 * span :] - y[:, span:-span]) / (span * 0.002))
    return float(np.degrees(np.nanmax(np.abs(over - under))))


@pytest.mark.parametrize("params", [WOMAN_45, HEAVY_MAN, CHILD, {"gender": 0.0, "weight": 0.9}])
def test_dress_back_runs_on_across_the_waist_seam(params):
    """From behind, the skirt's top met the bodice as a ledge across the small of the back:
    kept 2.5 mm outside the bodice's cloth, then closing onto it over its top 2.5 cm, the
    skirt sloped in to its edge steeper than the bodice ran on above it. The surface turned
    22-27 degrees across the seam (24-26 on the heavy man, 21-27 on a heavy woman, at rest
    and mid-stride); lying over the bodice as far as it covers it, under 22 now."""
    human = Human(params).dressed("dress")
    turns = [_waist_seam_turn(human, frame) for frame in (None, 6, 18)]
    assert max(turns) < 22.5, np.round(turns, 1)


def _corner_angle_normals(v: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(V, 3) unit vertex normals of quads (F, 4) weighted by their corner angles: what
    Blender shades a smooth mesh with when it carries no normals of its own."""
    out = np.zeros_like(v)
    for k in range(4):
        a, b, c = v[faces[:, k - 1]], v[faces[:, k]], v[faces[:, (k + 1) % 4]]
        n = np.cross(c - b, a - b)
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
        e1, e2 = a - b, c - b
        cos = np.einsum("nd,nd->n", e1, e2) / np.maximum(
            np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1), 1e-12)
        np.add.at(out, faces[:, k], n * np.arccos(np.clip(cos, -1, 1))[:, None])
    return out / np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-12)


@pytest.mark.parametrize("params", [WOMAN_45, HEAVY_MAN])
@pytest.mark.parametrize("frame", [None, 6])
def test_dress_skirt_top_is_shaded_as_cloth_not_a_roll(params, frame):
    """The skirt's top edge, 1.5 mm proud of the bodice, is a seam. The shell's hem quad
    there (at right angles to the cloth) was averaged into its outer vertices' normals:
    turned 40-45 degrees up out of the cloth, smooth shading spread a light edge over a
    dark band down the whole top row of the skirt's faces (3-4 cm), a ledge across the
    back. The normals the dress is shaded with (its part's, at rest and mid-stride) stay
    within 5 degrees of the cloth's own there."""
    from avatar.clothes import library
    from avatar.clothes.authoring import boundary_edges
    from avatar.mesh import vertex_normals

    human = Human(params).dressed("dress")
    fitted = human.outfit.garments[0]
    part = library.garment_part(fitted)
    v = fitted.mesh.vertices.astype(np.float64)
    normals = part.normals
    if frame is not None:
        _, matrices = _mid_stride(human, frame)
        body = skinning.linear_blend(human.vertices, human.weights, matrices)
        v = human.outfit.frame(body, matrices, exact=True)[0].astype(np.float64)
        normals = library.garment_normals(fitted, v)
    faces = fitted.mesh.faces
    if normals is None:
        normals = _corner_angle_normals(v, faces)
    n = len(fitted.garment.mesh.vertices)
    outer = faces[np.all(faces >= n, axis=1)]
    cloth = vertex_normals(v, outer).astype(np.float64)
    rim = np.unique(boundary_edges(fitted.garment.mesh.faces)[0])
    hip = v[:n, 2][_skirt_vertices(fitted)[:n]].min() + 0.3  # well above the skirt's hem
    top = rim[_skirt_vertices(fitted)[rim] & (v[rim, 2] > hip)] + n
    assert len(top) > 20
    turned = np.degrees(np.arccos(np.clip(np.einsum("nd,nd->n", normals[top], cloth[top]), -1, 1)))
    assert turned.max() < 5.0, np.round(np.percentile(turned, [50, 90, 100]), 1)


# ---------------------------------------------------------------------------- hems


@pytest.mark.parametrize("name", ["trousers", "jeans", "tshirt", "longsleeve", "sweatpants"])
def test_hems_and_their_bands_run_level(name):
    """Every open edge of a hemmed garment (here the inner edges of its hem, cuff, waist
    and neck bands, the lines a render shows) lies in a plane: cut along the helper
    mesh's faces they wandered 5-18 mm about it, wavy hems."""
    from avatar.clothes import builtin, library
    from avatar.clothes.authoring import boundary_loops

    mesh = builtin.BY_NAME[name].make(library.authoring_body()).mesh
    v = mesh.vertices.astype(np.float64)
    loops = [loop for loop in boundary_loops(mesh.faces) if len(loop) >= 12]  # not belt loops
    assert len(loops) >= 3
    for loop in loops:
        p = v[loop] - v[loop].mean(axis=0)
        normal = np.linalg.svd(p)[2][2]
        assert np.abs(p @ normal).max() < 0.0015, (name, len(loop), np.abs(p @ normal).max())


# ---------------------------------------------------------------------------- back midline

MUSCULAR_MAN = {"gender": 1.0, "age": 0.3, "muscle": 0.8}
BACKS = [MUSCULAR_MAN, None, {"gender": 0.0, "age": 0.9, "weight": 0.7},
         {"gender": 1.0, "weight": 1.0}]  # fmt: skip


def _side_neighbours(v: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(N,) each vertex's edge neighbour furthest to its left (-x) and right (+x); itself
    where it has none."""
    a = np.concatenate([faces.reshape(-1), np.roll(faces, -1, axis=1).reshape(-1)])
    b = np.concatenate([np.roll(faces, -1, axis=1).reshape(-1), faces.reshape(-1)])
    dx = v[b, 0] - v[a, 0]
    sides = []
    for pick in (-dx, dx):
        side, best = np.arange(len(v)), np.zeros(len(v))
        np.maximum.at(best, a, pick)
        chosen = (pick > 0) & (pick == best[a])
        side[a[chosen]] = b[chosen]
        sides.append(side)
    return sides[0], sides[1]


def _fold_angles(v: np.ndarray, faces: np.ndarray, keep: np.ndarray) -> np.ndarray:
    """Degrees between the normals of every two kept faces that share an edge."""
    q = v[faces]
    normal = np.cross(q[:, 2] - q[:, 0], q[:, -1] - q[:, 1])
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    edges = np.sort(np.stack([faces, np.roll(faces, -1, axis=1)], -1).reshape(-1, 2), axis=1)
    owner = np.repeat(np.arange(len(faces)), faces.shape[1])
    order = np.lexsort(edges.T[::-1])
    edges, owner = edges[order], owner[order]
    shared = np.all(edges[1:] == edges[:-1], axis=1)
    a, b = owner[:-1][shared], owner[1:][shared]
    both = keep[a] & keep[b]
    cos = np.einsum("nd,nd->n", normal[a[both]], normal[b[both]])
    return np.degrees(np.arccos(np.clip(cos, -1, 1)))


@pytest.mark.parametrize("name", ["hoodie", "cardigan", "jacket", "tshirt"])
@pytest.mark.parametrize("params", BACKS)
def test_loose_tops_span_the_cleft_without_folding_into_it(name, params):
    """Over the cleft of the buttocks the skin's normals point at the other side: eased
    along them (and bound to the cleft's walls) the two halves of a top crossed over at
    the back midline, a 60-130 degree fold and a 5.5-6.7 mm groove (the thin dark slit
    above the muscular man's hoodie hem). Between the band and 20 cm above the hem, on
    four bodies: the midline lies no more than 3 mm below its left and right neighbours,
    and no two faces of the back's middle (at least 4 mm wide) meet at over 45 degrees."""
    from avatar.clothes.authoring import AuthoringBody

    human = Human(params).dressed(name)
    fitted = human.outfit.garments[0]
    count = len(fitted.garment.mesh.vertices)
    v = fitted.mesh.vertices[:count].astype(np.float64)
    faces = fitted.garment.mesh.faces
    hip = AuthoringBody(human.body).marks.hip[0]
    hem = v[:, 2].min()
    seat = (v[:, 1] > hip[1]) & (v[:, 2] > hem + 0.045) & (v[:, 2] < hem + 0.2)
    left, right = _side_neighbours(v, faces)
    mid = seat & (np.abs(v[:, 0]) < 0.002) & (left != right)
    assert mid.sum() >= 3
    groove = (v[left, 1] + v[right, 1]) / 2 - v[:, 1]
    assert groove[mid].max() < 0.003, groove[mid].max()
    q = v[faces]
    area = np.linalg.norm(np.cross(q[:, 2] - q[:, 0], q[:, -1] - q[:, 1]), axis=1) / 2
    longest = np.linalg.norm(q - np.roll(q, -1, axis=1), axis=2).max(axis=1)
    middle = seat[faces].all(axis=1) & (np.abs(q[:, :, 0]).max(axis=1) < 0.03)
    fold = _fold_angles(v, faces, middle & (area / longest > 0.004))
    assert fold.max() < 45, fold.max()


# ---------------------------------------------------------------------------- skirt front

HEAVY_WOMAN = {"gender": 0.0, "age": 0.6, "weight": 1.0}


@pytest.mark.parametrize("params", [HEAVY_WOMAN, {"gender": 0.0, "age": 0.3}])
def test_skirt_front_follows_both_legs_alike_across_the_midline(params):
    """The skirt is bound to a vertex, its mirror image and the pelvis so it swings as one
    (``tailoring.blend_sides``); with the mirror weighing 0.5 at the midline beside the
    pelvis' 0.5, a vertex just off the midline followed the other leg more than its own,
    the two halves of the front crossing mid-stride (a dark notch between the legs). Each
    vertex within 15 cm of the midline weighs its own leg at least as much as the other,
    and skinned a quarter and three quarters into the walk the front's midline lies no
    more than 3 mm behind its left and right neighbours."""
    from avatar.clothes.authoring import AuthoringBody
    from avatar.clothes.fitting import garment_weights

    human = Human(params).dressed("dress")
    garment = human.outfit.garments[0].garment
    rest = human.outfit.garments[0].mesh.vertices[: len(garment.mesh.vertices)]
    w = garment_weights(garment, human.weights, human.skeleton.names)
    names = human.skeleton.names
    marks = AuthoringBody(human.body).marks
    skirt = (rest[:, 2] < marks.hip[:, 2].mean() - 0.05) & (np.abs(rest[:, 0]) < 0.15)
    leg = {}
    for tag in ("L", "R"):
        bones = [names.index(f"upperleg01.{tag}"), names.index(f"upperleg02.{tag}")]
        leg[tag] = np.where(np.isin(w.indices, bones), w.weights, 0).sum(axis=1)
    own = np.where(rest[:, 0] > 0, leg["L"] - leg["R"], leg["R"] - leg["L"])  # left is +x
    assert own[skirt & (np.abs(rest[:, 0]) > 0.005)].min() > -0.005
    left, right = _side_neighbours(rest.astype(np.float64), garment.mesh.faces)
    front = skirt & (rest[:, 1] < marks.hip[0, 1]) & (np.abs(rest[:, 0]) < 0.004)
    front &= (left != right) & (rest[:, 2] > marks.knee[0, 2] - 0.1)
    assert front.sum() >= 5
    walk = human.walk(seconds=1.0, fps=24)
    for frame in (6, 18):
        world = kinematics.forward(human.skeleton, walk.rotations[frame:frame + 1],
                                   walk.translations[frame:frame + 1])  # fmt: skip
        matrices = kinematics.skinning_matrices(human.skeleton, world)[0]
        v = skinning.linear_blend(rest, w, matrices).astype(np.float64)
        behind = v[:, 1] - (v[left, 1] + v[right, 1]) / 2
        assert behind[front].max() < 0.003, (frame, behind[front].max())


# ---------------------------------------------------------------------------- seat


ELDERLY_WOMAN = {"gender": 0.0, "age": 0.95, "weight": 0.6}


def _back_hem(points: np.ndarray, faces: np.ndarray, xs: np.ndarray) -> np.ndarray:
    """(len(xs), 2) height and depth (z, y; m) of a garment's lowest point on the back
    at each x: where its edges (faces (F, C) over points (N, 3)) cross that x."""
    a, b = faces.reshape(-1), np.roll(faces, -1, axis=1).reshape(-1)
    p, q = points[a], points[b]
    dx = q[:, 0] - p[:, 0]
    out = []
    for x in xs:
        t = (x - p[:, 0]) / np.where(np.abs(dx) < 1e-9, 1e-9, dx)
        crossing = (t >= 0) & (t <= 1) & (p[:, 1] > 0) & (q[:, 1] > 0)
        at = p[crossing] + t[crossing, None] * (q[crossing] - p[crossing])
        lowest = at[np.argmin(at[:, 2])]
        out.append((lowest[2], lowest[1]))
    return np.array(out)


@pytest.mark.parametrize("params", [ELDERLY_WOMAN, WOMAN, {"gender": 0.0, "age": 0.6,
                                                           "weight": 1.0}])  # fmt: skip
def test_cardigan_back_hem_runs_level_across_the_seat(params):
    """A cardigan's back hem hangs from the crowns of the buttocks and spans the cleft.
    Bound to the skin under it, on the elderly woman it followed her sagging seat: 30 mm
    higher at the midline than 8.5 cm to the side and 29 mm forward in the cleft, a
    heart shape from behind. Across the back it now keeps within 8 mm of one height, and
    the midline stands no more than 5 mm in front of the hem 8 cm to each side."""
    from avatar.geometry import collision

    human = Human(params).dressed("tshirt", "cardigan", "leggings")
    fitted = next(g for g in human.outfit.garments if g.name == "cardigan")
    count = len(fitted.garment.mesh.vertices)
    inner = fitted.mesh.vertices[:count].astype(np.float64)
    hem = _back_hem(inner, fitted.garment.mesh.faces, np.linspace(-0.12, 0.12, 25))
    assert np.ptp(hem[:, 0]) < 0.008, hem[:, 0].round(3)
    side = _back_hem(inner, fitted.garment.mesh.faces, np.array([-0.08, 0.0, 0.08]))[:, 1]
    assert side[1] > min(side[0], side[2]) - 0.005, side.round(3)
    # Spanning the seat does not put the cloth into the body.
    base = human.body.model.base
    faces = base.faces[base.face_groups["body"]]
    _, depth = collision.penetration(human.outfit.rest_body, faces, fitted.mesh.vertices)
    assert depth.max() < 0.001, depth.max()


def _face_pairs(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(P,), (P,) the two faces of every edge two faces share."""
    edges = np.sort(np.stack([faces, np.roll(faces, -1, axis=1)], -1).reshape(-1, 2), axis=1)
    owner = np.repeat(np.arange(len(faces)), faces.shape[1])
    order = np.lexsort(edges.T[::-1])
    edges, owner = edges[order], owner[order]
    shared = np.all(edges[1:] == edges[:-1], axis=1) & (edges[1:, 0] != edges[1:, 1])
    return owner[:-1][shared], owner[1:][shared]


@pytest.mark.parametrize("name", ["hoodie", "jacket"])
def test_tops_do_not_fold_under_the_arm(name):
    """Eased 1.3-2.5 cm out of the armpit's crease (a tighter curve than that), the cloth
    crossed itself under the arm: neighbouring faces turned up to 180 degrees against each
    other (24 such pairs on the hoodie), a dark triangle under the arm from the front and
    the side. No two neighbouring faces under the arm now turn more than 100 degrees
    against each other, on the built garment and on a body wearing it."""
    from avatar.clothes import builtin, library
    from avatar.clothes.authoring import AuthoringBody

    body = library.authoring_body()
    piece = builtin.BY_NAME[name].make(body)
    human = Human(WOMAN).dressed(name)
    fitted = human.outfit.garments[0]
    count = len(fitted.garment.mesh.vertices)
    for v, faces, marks in ((piece.mesh.vertices, piece.mesh.faces, body.marks),
                            (fitted.mesh.vertices[:count], fitted.garment.mesh.faces,
                             AuthoringBody(human.body).marks)):  # fmt: skip
        centre, under, a, _, turn = _under_arm_turns(v, faces, marks)
        assert (turn[under[a]] > -0.17).all(), centre[a[under[a] & (turn < -0.17)]]


def _under_arm_turns(v: np.ndarray, faces: np.ndarray, marks) -> tuple:
    """Face centres (F, 3), which lie under the arms (F,) bool (not the hood's roll lying
    on the back behind them), and each pair of faces sharing an edge: its two faces (P,),
    (P,) and the cosine between their normals (P,)."""
    v = v.astype(np.float64)
    centre = v[faces].mean(axis=1)
    shoulder = marks.shoulder[:, 2].mean()
    under = ((np.abs(centre[:, 0]) > 0.1) & (np.abs(centre[:, 0]) < 0.26)
             & (np.abs(centre[:, 1] - marks.shoulder[:, 1].mean()) < 0.06)
             & (centre[:, 2] > shoulder - 0.25) & (centre[:, 2] < shoulder))  # fmt: skip
    q = v[faces]
    n = np.cross(q[:, 2] - q[:, 0], q[:, -1] - q[:, 1])
    n /= np.maximum(np.linalg.norm(n, axis=1), 1e-12)[:, None]
    a, b = _face_pairs(faces)
    return centre, under, a, b, np.einsum("nd,nd->n", n[a], n[b])


@pytest.mark.parametrize("params", [{"gender": 1.0, "age": 0.5}, WOMAN])
def test_jacket_over_a_tshirt_does_not_fold_under_the_arm(params):
    """Over a T-shirt the jacket's layer asks 2.4 cm off the skin where its binding left it
    1.3 cm from arm and chest: pushed along their own skin's normals, neighbouring points
    went opposite ways (towards the chest, towards the arm), crossed, and 12 (man) and 9
    (woman) face pairs under the arms turned more than 120 degrees against each other (a
    crumpled armpit, its stitching zig-zagging). ``fitting.untangled`` shares the pushes."""
    from avatar.clothes.authoring import AuthoringBody
    from avatar.geometry import collision

    human = Human(params).dressed("tshirt", "jacket")
    fitted = next(g for g in human.outfit.garments if g.name == "jacket")
    count = len(fitted.garment.mesh.vertices)
    v = fitted.mesh.vertices[:count].astype(np.float64)
    faces = fitted.garment.mesh.faces
    centre, under, a, b, turn = _under_arm_turns(v, faces, AuthoringBody(human.body).marks)
    folded = (under[a] | under[b]) & (turn < -0.5)
    assert not folded.any(), centre[a[folded]].round(3)
    # The untangled cloth stays out of the body.
    base = human.body.model.base
    body_faces = base.faces[base.face_groups["body"]]
    _, depth = collision.penetration(human.outfit.rest_body, body_faces, v)
    assert depth.max() < 0.001, depth.max()


@pytest.mark.parametrize("params", [{"gender": 1.0, "age": 0.5}, WOMAN])
def test_jacket_over_a_tshirt_holds_still_at_rest(params):
    """A posed frame at the rest pose left the jacket where the fit put it, but for the
    points the fit left squeezed between arm and chest (1.3 cm from both where its layer
    over the T-shirt asks 2.4 cm): every frame pushed them out of the arm again, 10.7 mm
    (man) and 20.4 mm (woman) towards the chest. Frames now keep the clearance the fit
    could give them (``Pose.resolve_anchored``): 3.8 and 6.0 mm."""
    human = Human(params).dressed("tshirt", "jacket")
    rest = human.pose("rest")
    world = kinematics.forward(human.skeleton, rest.rotations[:1], rest.translations[:1])
    matrices = kinematics.skinning_matrices(human.skeleton, world)[0]
    body = skinning.linear_blend(human.vertices, human.weights, matrices)
    frame = human.outfit.frame(body, matrices)
    i = [g.name for g in human.outfit.garments].index("jacket")
    fitted = human.outfit.garments[i].mesh.vertices
    jump = np.linalg.norm(frame[i] - fitted[: len(frame[i])], axis=1)
    assert jump.max() < 0.007, jump.max()


# ---------------------------------------------------------------------------- straps


@pytest.mark.parametrize("name", ["dress", "swimsuit", "tanktop"])
@pytest.mark.parametrize("params", [WOMAN, {"gender": 0.0, "age": 0.7, "weight": 0.9}])
def test_straps_end_across_the_shoulder_without_a_tab(name, params):
    """A strap runs over the top of the shoulder, no higher than the base of the neck.
    The faces just outside the neckline that climb the side of the neck were kept: each
    strap's inner corner stood up as a tab 19-26 mm above the neck joint (a slim and a
    heavy woman), against 2-12 mm for the strap across the shoulder."""
    from avatar.clothes.authoring import AuthoringBody

    human = Human(params).dressed(name)
    v = human.outfit.garments[0].mesh.vertices.astype(np.float64)
    marks = AuthoringBody(human.body).marks
    for shoulder in marks.shoulder:
        side = v[:, 0] * np.sign(shoulder[0]) > 0.02
        assert v[side, 2].max() - marks.neck[2] < 0.015, (name, v[side, 2].max() - marks.neck[2])


# ---------------------------------------------------------------------------- cuffs


def _sleeve_radii(human: Human) -> tuple[float, float]:
    """(m) the left sleeve's radius round the forearm's axis (90th percentile of its inner
    cloth's vertices) over its last 6% of the forearm's length, and 30-50% above its end
    (35-45% fell between two rings of the woman's hoodie once its end moved by 0.2 mm)."""
    from avatar.clothes.authoring import AuthoringBody

    fitted = human.outfit.garments[-1]
    v = fitted.mesh.vertices[: len(fitted.garment.mesh.vertices)].astype(np.float64)
    marks = AuthoringBody(human.body).marks
    elbow, wrist = marks.elbow[0], marks.wrist[0]
    length = float(np.linalg.norm(wrist - elbow))
    rel = v - elbow
    along = rel @ (wrist - elbow) / length
    radius = np.linalg.norm(rel - np.outer(along, (wrist - elbow) / length), axis=1)
    forearm = (v[:, 0] * np.sign(elbow[0]) > abs(elbow[0])) & (along > 0) & (radius < 0.1)
    end = along[forearm].max()
    cuff = forearm & (along > end - 0.06 * length)
    above = forearm & (along < end - 0.3 * length) & (along > end - 0.5 * length)
    return float(np.percentile(radius[cuff], 90)), float(np.percentile(radius[above], 90))


@pytest.mark.parametrize("name", ["longsleeve", "hoodie", "cardigan"])
@pytest.mark.parametrize("params", [{"age": 0.15}, WOMAN])
def test_sleeves_gather_into_cuffs_round_the_wrist(name, params):
    """A knit sleeve closes in round the wrist. Eased as much at its end as along the
    forearm, it ran on as a straight tube 2.4-2.6 times the wrist's width, a bell round a
    child's thin wrist (cuff 0.93-1.0 of the radius a third of the forearm above it)."""
    cuff, above = _sleeve_radii(Human(params).dressed(name))
    assert cuff < 0.85 * above, (name, round(cuff * 1000), round(above * 1000))

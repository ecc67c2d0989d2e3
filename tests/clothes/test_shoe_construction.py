"""Shoes that read as shoes (issue 14): laces were five short separate bars on a rounded
shell, and sneakers were the leather shoe in white.

Checked on the built meshes and materials: one lace criss-crossing between eyelets on two
quarters over a tongue; the toe cap's seam and the welt stitched; sneakers on a deep,
light midsole with a moulded band, a toe bumper and a heel tab.
"""

from __future__ import annotations

import numpy as np
import pytest

from avatar.clothes import builtin, library, shoes


@pytest.fixture(scope="module")
def body():
    return library.authoring_body()


@pytest.fixture(scope="module")
def built(body):
    return {name: builtin.build(builtin.BY_NAME[name], body, 256)
            for name in ("shoes", "sneakers")}  # fmt: skip


def _row_faces(mesh, row: str, left: bool = True) -> np.ndarray:
    """Faces whose corners all lie in an atlas row, on the left foot (x > 0)."""
    v0, v1 = shoes.ROWS[row]
    corner_v = mesh.uvs[mesh.face_uvs, 1]
    inside = np.all((corner_v >= v0) & (corner_v <= v1), axis=1)
    side = mesh.vertices[mesh.faces].mean(axis=1)[:, 0] > 0
    return np.flatnonzero(inside & (side == left))


def _components(faces: np.ndarray) -> int:
    """Connected components of faces sharing vertices (union-find)."""
    parent = {int(v): int(v) for v in np.unique(faces)}

    def find(a: int) -> int:
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for f in faces:
        for a, b in zip(f[:-1], f[1:], strict=True):
            parent[find(int(a))] = find(int(b))
    return len({find(v) for v in parent})


def _lightness(rgb_bytes: np.ndarray) -> np.ndarray:
    linear = (rgb_bytes.astype(float) / 255) ** 2.2
    y = linear @ [0.2126, 0.7152, 0.0722]
    return 116 * np.cbrt(y) - 16


def test_one_lace_criss_crosses_over_a_tongue_between_eyelets_on_two_quarters(body, built):
    mesh = built["shoes"].mesh
    laces = mesh.faces[_row_faces(mesh, "laces")]
    assert _components(laces) == 1  # one lace, not bars
    foot = shoes.Foot(body, 0)
    plan = shoes._lacing(foot, shoes.upper(body, foot))
    points = mesh.vertices[np.unique(laces)].astype(np.float64)
    # An X between every pair of eyelet rows: the lace crosses the throat's middle half
    # way between them, twice (one end over the other).
    for k in range(len(plan.y) - 1):
        y, x = (plan.y[k] + plan.y[k + 1]) / 2, (plan.x[k] + plan.x[k + 1]) / 2
        near = points[(np.abs(points[:, 1] - y) < 0.003) & (np.abs(points[:, 0] - x) < 0.003)]
        assert len(near) >= 2, k
        assert np.ptp(near[:, 2]) > 0.0005  # one strand over the other
    # Eyelets (trim row) on both quarters, either side of the throat, the lace over them.
    eyelets = mesh.vertices[np.unique(mesh.faces[_row_faces(mesh, "trim")])]
    offset = eyelets[:, 0] - np.interp(eyelets[:, 1], plan.y[::-1], plan.x[::-1])
    # (Six corners an eyelet, most of them more than 6 mm off the throat's middle.)
    assert (offset < -0.006).sum() >= 4 * shoes.LACES and (offset > 0.006).sum() >= 4 * shoes.LACES
    assert points[:, 2].max() > eyelets[:, 2].max()
    # The tongue: upper-row leather lying over the upper under the laces' crossings.
    upper = mesh.faces[_row_faces(mesh, "upper")]
    pieces = _components(upper)
    assert pieces >= 3  # the upper, the tongue and the two facings


def test_toe_cap_seam_and_welt_are_stitched(body, built):
    m = built["shoes"].material
    image = m.base_color_texture
    size = image.shape[0]

    def row(v: float) -> np.ndarray:
        return _lightness(image[int(round((1 - v) * size))])

    plain = np.median(row(shoes.cap_stitch_v(20.0)))
    for mm in (2.5, 5.0):  # double-stitched toe cap: dashes lighter than the leather
        assert np.percentile(row(shoes.cap_stitch_v(mm)), 90) > plain + 8
    assert np.percentile(row(shoes.sole_v(0.95)), 90) > np.median(row(shoes.sole_v(0.5))) + 5
    # The cap's v grows towards its seam: the stitch rows follow the seam.
    cap = shoes.toe_cap(body, shoes.Foot(body, 0)).mesh
    corner = cap.vertices[cap.faces.reshape(-1)]
    v = cap.uvs[cap.face_uvs.reshape(-1), 1]
    foot = shoes.Foot(body, 0)
    assert np.corrcoef(foot.along(corner), v)[0, 1] < -0.5  # towards the toe, away from it


def test_sneakers_have_a_deep_light_midsole_a_toe_bumper_and_a_heel_tab(body, built):
    foot = shoes.Foot(body, 0)

    def sole_edge(name: str):
        mesh = built[name].mesh
        faces = _row_faces(mesh, "sole")
        p = mesh.vertices[np.unique(mesh.faces[faces])].astype(np.float64)
        t = foot.along(p)
        ball = p[(t > 0.65) & (t < 0.8)]
        tip = p[t > t.max() - 0.03]
        return np.ptp(ball[:, 2]), ball[:, 2].min(), tip[:, 2].max() - ball[:, 2].max()

    shoe_ball, shoe_tread, _ = sole_edge("shoes")
    sneaker_ball, sneaker_tread, bumper = sole_edge("sneakers")
    assert shoe_ball < 0.018 and sneaker_ball > 0.02  # a midsole over 2 cm tall at the ball
    assert foot.ground - sneaker_tread > 0.01  # 10+ mm of rubber under the foot
    assert bumper > 0.008  # the sole wraps up round the toe
    # White midsole, lighter than the grey canvas upper; a navy band moulded round it.
    image = built["sneakers"].material.base_color_texture
    size = image.shape[0]

    def texels(v: float) -> np.ndarray:
        return image[int(round((1 - v) * size))]

    midsole, upper = _lightness(texels(shoes.sole_v(0.3))), _lightness(texels(0.8))
    assert np.median(midsole) > np.median(upper) + 10
    band = texels(shoes.sole_v(np.mean(shoes.MIDSOLE_STRIPE))).astype(float)
    assert np.median(band[:, 2]) > np.median(band[:, 0]) + 15  # blue over red: navy
    # A heel tab (trim row) up the back of the heel, above the collar.
    mesh = built["sneakers"].mesh
    tab = mesh.vertices[np.unique(mesh.faces[_row_faces(mesh, "trim")])]
    tab = tab[foot.along(tab) < 0.1]
    upper_v = mesh.vertices[np.unique(mesh.faces[_row_faces(mesh, "upper")])]
    assert len(tab) >= 12 and tab[:, 2].max() > upper_v[foot.along(upper_v) < 0.1, 2].max()
    assert len(_row_faces(built["shoes"].mesh, "trim")) < len(_row_faces(mesh, "trim"))


def test_shoes_stay_light_for_posing(body, built):
    """Under 3000 vertices a pair, 4000 for boots (they pose with the outfit at > 60
    frames/s); the upper and toe cap are split finer to hold the last's edges (were under
    2000)."""
    for garment in built.values():
        assert len(garment.mesh.vertices) < 3000
    boots = builtin.build(builtin.BY_NAME["boots"], body, 64)
    assert len(boots.mesh.vertices) < 4000


@pytest.mark.parametrize("side", [0, 1])
def test_uppers_are_made_on_a_last(body, side):
    """A shoe's shape, not an inflated foot: upright side walls down to the sole (they
    bulged 5 mm over a pinched bottom edge), a vertical heel counter (it rounded 6 mm
    forward towards the ground), a vamp running straight down to the toe (it domed over
    and dropped to the tip like a clog's)."""
    foot = shoes.Foot(body, side)
    surface = shoes._Surface(shoes.upper(body, foot).mesh)
    g, out = foot.ground, 1 if side == 0 else -1

    def at(t: float) -> float:
        return foot.heel_y - t * (foot.heel_y - foot.toe_y)

    heights = np.array([0.006, 0.012, 0.018, 0.024])
    origins = np.array([[foot.centre_x + out * 0.15, at(0.75), g + h] for h in heights])
    points, _, hit = surface.hit(origins, (-out, 0.0, 0.0))
    wall = np.abs(points[:, 0] - foot.centre_x)
    assert hit.all() and np.ptp(wall[:3]) < 0.001 and wall[0] > wall.max() - 0.0005
    heights = np.array([0.01, 0.02, 0.03, 0.04])
    origins = np.array([[foot.centre_x, foot.heel_y + 0.1, g + h] for h in heights])
    points, _, hit = surface.hit(origins, (0.0, -1.0, 0.0))
    assert hit.all() and np.ptp(points[:, 1]) < 0.0015
    along = np.linspace(0.72, 0.96, 7)
    origins = np.array([[foot.centre_x, at(t), g + 0.3] for t in along])
    points, _, hit = surface.hit(origins, (0.0, 0.0, -1.0))
    line = np.polyval(np.polyfit(along, points[:, 2], 1), along)
    assert hit.all() and np.abs(points[:, 2] - line).max() < 0.0015

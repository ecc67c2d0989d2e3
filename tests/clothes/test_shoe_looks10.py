"""Shoes up close, the tenth look pass: a toe cap fine enough for smooth highlights, a
boot's bow with room for its loops, facings without a pale sheen at their front ends,
flex creases that still read at full-body distance, a child's sneakers as wide for the
foot as an adult's.

Measured on the built meshes and maps; each check failed on the code before the pass.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from test_shoe_looks9 import _dihedral_inside

from avatar.clothes import library, shoes


@pytest.fixture(scope="module")
def body():
    return library.authoring_body()


@pytest.fixture(scope="module", params=(0, 1))
def foot(request, body):
    return shoes.Foot(body, request.param)


def test_toe_cap_turns_smoothly_between_faces(body, foot):
    """Between neighbouring faces inside the toe cap the surface turns at most 30 degrees,
    and 15 for all but one edge in twenty (it turned up to 43 and 21.7 at the nose: the
    interpolated normals drew blotchy highlights on dark leather). Fitted on a man's and
    a child's feet no triangle of it turns over 60 degrees from its authored facing (split
    finer along its sides too, 13 and 7 did: small folds where the wall meets the top)."""
    from avatar.clothes.binding import fit
    from avatar.human import Human

    cap = shoes.toe_cap(body, foot)
    turn = _dihedral_inside(cap.mesh)
    assert turn.max() < 30 and np.percentile(turn, 95) < 15, (turn.max(), np.percentile(turn, 95))
    f = cap.mesh.faces
    tri = np.concatenate([f[:, [0, 1, 2]], f[:, [0, 2, 3]]])
    tri = tri[(tri[:, 0] != tri[:, 1]) & (tri[:, 1] != tri[:, 2]) & (tri[:, 0] != tri[:, 2])]

    def facing(v: np.ndarray) -> np.ndarray:
        n = np.cross(v[tri[:, 1]] - v[tri[:, 0]], v[tri[:, 2]] - v[tri[:, 0]])
        return n / np.linalg.norm(n, axis=1, keepdims=True)

    authored = facing(cap.mesh.vertices.astype(np.float64))
    binding = shoes._scaled_by_the_foot(body, cap).binding
    for params in ({"gender": 1.0, "age": 0.5}, {"gender": 0.3, "age": 0.12}):
        worn = facing(fit(binding, Human(params).vertices).astype(np.float64))
        assert (np.einsum("nd,nd->n", authored, worn) > 0.5).all(), params


def _faces_into_the_foot(body, mesh) -> int:
    """How many faces of ``mesh`` face into the foot (against the nearest skin normal)."""
    v = mesh.vertices[mesh.faces].astype(np.float64)
    normal = np.cross(v[:, 2] - v[:, 0], v[:, 3] - v[:, 1])
    _, i = body.skin_tree.query(v.mean(axis=1))
    return int((np.einsum("fd,fd->f", normal, body.skin_normals[i]) < 0).sum())


@pytest.mark.parametrize("top", [0.96, 0.86], ids=["shoes", "boots"])
def test_facings_and_shaft_eyelets_face_out(body, foot, top):
    """Every face of the facings (on the instep and up a boot's shaft) and of the shaft's
    eyelets faces out of the foot. The inner facing was laid from +x to -x, the shaft's
    outer facing and its eyelets the other way round: 12 of 24 instep facing faces, 9 of 18
    shaft facing faces and all 16 shaft eyelet faces faced in, their shell's outer layer
    seen from behind with the grain's highlights inverted (a pale speckled sheen down the
    inner facing, brightest at its front end)."""
    upper = shoes.upper(body, foot, top)
    pieces = shoes.lacing(body, foot, upper)
    facings = [pieces[1]] + ([pieces[4], pieces[5]] if top < shoes.LOW else [])
    assert len(pieces) == (7 if top < shoes.LOW else 4)
    for piece in facings:
        assert _faces_into_the_foot(body, piece.mesh) == 0


def test_a_boots_bow_lies_on_the_shaft_front_with_open_loops(body):
    """A boot's bow droops down the front of its shaft: no part of its lace lies where the
    shaft turns more than 60 degrees away from the front above the second row from the top
    (the low shoe's level loops reached 31 mm out, round the side of the ankle, 80 degrees
    away: from the front two squashed slits), its loops 25 mm and more long with an eye
    9 mm and more across inside the lace, its tails hanging 4 cm and more under the knot
    (3 cm)."""
    foot = shoes.Foot(body, 0)
    top = shoes.upper(body, foot, 0.86)
    surface, plan = shoes._Surface(top.mesh), shoes._lacing(foot, top)
    rows = shoes._shaft_rows(foot, top, plan, surface)
    lace = shoes._shaft_lace(surface, rows).vertices.astype(np.float64)
    lace = lace[lace[:, 2] > rows.z[-2]]
    _, normal = shoes._front(surface, lace[:, [0, 2]], 0.0)
    assert np.degrees(np.arccos(-normal[:, 1])).max() < 60
    knot = np.array([rows.x[-1], rows.z[-1] + 0.005])
    first, second = shoes._boot_bow(knot)
    for bow in (first, second):
        reach = np.linalg.norm(bow - knot, axis=1)
        assert reach.max() > 0.04  # the tail
        loop = bow[reach < 0.035]  # the loop's polyline, knot to knot
        axis = (loop[np.argmax(np.linalg.norm(loop - knot, axis=1))] - knot)
        length = np.linalg.norm(axis)
        across = (loop - knot) @ (np.array([-axis[1], axis[0]]) / length)
        eye = np.ptp(across) - shoes.LACE_WIDTH
        assert length > 0.025 and eye > 0.009, (length, eye)


def _creases_alone(size: int):
    """(the vamp's crease band of a flat normal map with the creases drawn on it, its
    texel rows and columns a 3 x 3 mm patch of the vamp spans: ~4 along the foot and ~24
    round it at 1024)."""
    from avatar.material import Material

    flat = np.tile(np.array([128, 128, 255], np.uint8), (size, size, 1))
    grey = np.full((size, size, 3), 128, np.uint8)
    m = Material(name="creases", roughness=1.0, base_color_texture=grey, normal_texture=flat)
    shoes._creased(m, size)
    rows = slice(int(round((1 - shoes.vamp_v(0.77)) * size)),
                 int(round((1 - shoes.vamp_v(0.64)) * size)))  # fmt: skip
    band = m.normal_texture[rows, int(0.25 * size) : int(0.75 * size), 1]
    return band.astype(np.float64) / 127.5 - 1, round(4 * size / 1024), round(24 * size / 1024)


def test_vamp_creases_read_at_full_body_distance():
    """Averaged over a full-body picture's pixel (~3 x 3 mm of the vamp), the creases still
    tilt the normal 6 degrees RMS (4.1 before: millimetre-wide valleys whose two walls
    averaged away), and up close no texel tilts more than 35 degrees (38.6: broader,
    softer valleys, not sharper wrinkles)."""
    tilt, down, round_ = _creases_alone(1024)
    h, w = tilt.shape[0] // down * down, tilt.shape[1] // round_ * round_
    far = tilt[:h, :w].reshape(h // down, down, w // round_, round_).mean(axis=(1, 3))
    far_rms = np.degrees(np.arcsin(np.sqrt((far**2).mean())))
    close_max = np.degrees(np.arcsin(np.abs(tilt).max()))
    assert far_rms > 6 and close_max < 35, (far_rms, close_max)


WEARERS = {"man": {"gender": 1.0, "age": 0.5}, "woman": {"gender": 0.0},
           "child": {"gender": 0.3, "age": 0.12}}  # fmt: skip


@functools.cache
def _cap_turns(who: str) -> tuple[np.ndarray, np.ndarray]:
    """(inner, outer) degrees between neighbouring faces inside the toe caps of shoes
    fitted on ``WEARERS[who]``: the shell's two layers (the cap's faces: its atlas row)."""
    from avatar.human import Human
    from avatar.mesh import Mesh

    worn = Human(WEARERS[who]).dressed("shoes").outfit.garments[0]
    cloth = worn.garment.mesh
    n = len(cloth.vertices)
    v = cloth.uvs[cloth.face_uvs].mean(axis=1)[:, 1]
    cap = np.flatnonzero((v > shoes.ROWS["cap"][0]) & (v < shoes.ROWS["cap"][1]))
    inner, outer = (Mesh(worn.mesh.vertices[s], cloth.faces).subset(cap)
                    for s in (slice(n), slice(n, None)))  # fmt: skip
    return _dihedral_inside(inner), _dihedral_inside(outer)


@pytest.mark.parametrize("who", list(WEARERS))
def test_toe_caps_outer_surface_turns_no_more_than_its_inner(who):
    """Fitted, a toe cap's outer surface (the leather seen) turns between neighbouring faces
    hardly more than its inner one: within 3 degrees of it for all but one edge in twenty,
    and never over 60. Grown along the skin's normal, which turns from toe to toe, the
    outer surface rippled over the toes (one edge in twenty: 27.5 against the inner's 21.3
    on a man, 25.6 against 18.1 on a child; up to 97, 127 and 150 degrees on a man, a woman
    and a child): blotchy highlights on the leather. Grown along the shoe's normals but the
    skin's where the shoe is edge-on to it, the nose's top still turned 90 degrees on a man's
    (75 on a child's)."""
    inner, outer = _cap_turns(who)
    assert np.percentile(outer, 95) < np.percentile(inner, 95) + 3, (
        np.percentile(outer, 95), np.percentile(inner, 95))
    assert outer.max() < 60, outer.max()


@pytest.mark.parametrize("who", list(WEARERS))
def test_toe_caps_fitted_on_other_feet_are_as_smooth_as_made(who):
    """Fitted on a man's, a woman's and a child's feet, the toe cap's surface turns between
    neighbouring faces under 16.5 degrees for all but one edge in twenty and never over 35,
    near its 15 and 30 made on the authoring body (``test_toe_cap_turns_smoothly_between_
    faces``). Each vertex evaluated by its own binding alone, neighbours bound across the
    helper's edges parted: one edge in twenty turned 21.3 on a man's (up to 61), 16.9 on a
    woman's, 18.1 on a child's (up to 48)."""
    inner, _ = _cap_turns(who)
    assert np.percentile(inner, 95) < 16.5 and inner.max() < 35, (np.percentile(inner, 95),
                                                                inner.max())  # fmt: skip



def _texture_axes(mesh) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Of each triangle of ``mesh``'s faces: (T, 3, 2) the surface one texel (1/1024 of
    the atlas) covers along u and along v, in mm; (T, 3) its facing; (T, 3) its middle."""
    f, c = mesh.faces, mesh.face_uvs
    tri = np.concatenate([f[:, [0, 1, 2]], f[:, [0, 2, 3]]])
    corners = np.concatenate([c[:, [0, 1, 2]], c[:, [0, 2, 3]]])
    real = (tri[:, 0] != tri[:, 1]) & (tri[:, 1] != tri[:, 2]) & (tri[:, 0] != tri[:, 2])
    p = mesh.vertices[tri[real]].astype(np.float64)
    uv = mesh.uvs[corners[real]].astype(np.float64) * 1024
    edges = np.stack([p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]], -1)  # (T, 3, 2)
    steps = np.stack([uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]], -1)  # (T, 2, 2)
    facing = np.cross(edges[..., 0], edges[..., 1])
    facing /= np.linalg.norm(facing, axis=1)[:, None]
    return edges @ np.linalg.inv(steps) * 1000, facing, p.mean(axis=1)


def test_toe_caps_texture_lies_square_on_its_side_walls(body, foot):
    """On the toe cap's side walls (faces within 60 degrees of upright, behind the nose) a
    texel covers at most 3 mm of leather along u (1 for all but one in twenty) and 1.5 along
    v, and the texture's two axes stand 25 degrees or more apart (60 for half the faces)
    (the grain's cells are drawn ``GRAIN_STRETCH`` wider in u texels). With u the angle round
    the foot's vertical axis and v the distance from the seam, both ran along the foot
    there: axes 0.3 degrees apart (22 for half), a texel up to 79 mm tall along u (6.5 for
    one in twenty), up to 10 along v, so the grain and gloss were drawn as wavy streaks
    down the walls."""
    axes, facing, middle = _texture_axes(shoes.toe_cap(body, foot).mesh)
    wall = (np.abs(facing[:, 2]) < 0.5) & (foot.along(middle) < 1.0)
    along_u, along_v = (np.linalg.norm(axes[wall, :, k], axis=1) for k in (0, 1))
    cos = np.abs(np.einsum("nd,nd->n", axes[wall, :, 0], axes[wall, :, 1])) / along_u / along_v
    apart = np.degrees(np.arccos(np.clip(cos, 0, 1)))
    assert along_u.max() < 3 and np.percentile(along_u, 95) < 1, (along_u.max(),
                                                                 np.percentile(along_u, 95))
    assert along_v.max() < 1.5, along_v.max()
    assert apart.min() > 25 and np.median(apart) > 60, (apart.min(), np.median(apart))

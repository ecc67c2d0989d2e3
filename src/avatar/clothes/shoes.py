"""Shoes built from the foot: a leather upper, a rubber sole with a heel block, a toe cap
and laces, all generated on the authoring body and bound to it, so they fit every foot
(their offsets scaled by the foot's size, ``_scaled_by_the_foot``).

Parts, per foot (``x > 0`` is the body's left):

- upper: the ``helper-tights`` faces of the foot and ankle, eased off the skin, its
  opening smoothed into a curve, split finer (where the last shapes it) and moved onto a
  last (``_Last``): the foot's outline in plan with upright walls (a vertical heel
  counter, straight sides down to the sole), rolling over onto a vamp that runs straight
  down over the toes and on, steepening, to a low almond toe box; the bottom edge drawn
  down to just above the ground. A boot's shaft above the last is laid close round the
  ankle and leg, flaring at its collar (``_shaft``). As worn (``capped``) it has no faces
  under the toe cap, and its throat ends just over the top eyelets;
- sole: an outsole round the upper's bottom edge (resampled to SOLE_POINTS), a thin welt
  out, its wall bellied and bevelled in under the tread (``_sole_edge``), a little below
  the foot, taller at the heel (a heel block with a breast: the waist lifted under the
  arch), curling up at the toe (toe spring), closed underneath;
- toe cap: the front of the upper again, on the same last 1.2 mm out, its back edge
  (the seam over the vamp) smoothed into a curve, its surface faired (``_faired``),
  skived down onto the vamp (``_skived``) and double-stitched;
- lacing (``lacing``): a tongue lying on the instep under the laces, two quarters'
  facings either side of it with eyelets, and one lace criss-crossing from eyelet to
  eyelet (each crossing over the one before), tied in a bow at the top; a boot's goes
  on up the front of its shaft (``shaft_lacing``) to the bow under the collar;
- a sneaker (``SNEAKER``) on a deep rubber midsole wrapping up over the toe (a toe
  bumper), with a band moulded round it, and a heel tab.

They share one material: an atlas (``look``) whose rows hold leather (grained:
``_grained``; a sneaker's textile a knit mesh: ``_knit_mesh``), the vamp's leather with
flex creases across the ball (``_vamp_uvs``, ``_creased``), trim (eyelets, a
sneaker's facings and heel tab), toe-cap leather, sole and lace cord, each piece's UVs
laid out inside its row; the toe cap's and sole's UVs run from their seams, so stitching
drawn across the atlas follows the cap's edge and the welt.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from avatar.clothes import regions
from avatar.clothes.authoring import AuthoringBody, Piece, bound, cut, join
from avatar.looks import fabrics
from avatar.material import Material
from avatar.mesh import Mesh

EASE = 0.005  # m between foot and upper (less let toes and socks through mid-stride)
# The sole's edge, as a render shows it: UNDER m of tread below the foot's lowest point,
# rising COVER m over the upper's bottom edge (which it hides), to at least HEEL m above
# the foot's ground at the heel (a heel block), and a welt WELT m out of the upper. It
# was 8 mm of tread under the foot's lowest point plus the upper's ragged edge 2.5-15 mm
# up it: a 2-3 cm slab all round, a clog's.
UNDER = 0.006
COVER = 0.002
HEEL = 0.014
WELT = 0.0012  # a thin welt, the edge flush-ish with the upper (3 mm read as a ledge)
BULGE = 0.0015  # m at most the sole follows the upper's bulge out (more read as a ledge)
ARCH = 0.008  # m the tread is lifted between heel block and ball of the foot
SPRING = 0.012  # m the tread curls up at the tip of the toe box (toe spring)
CAP_EASE = EASE + 0.0012  # a toe cap sewn flat on the vamp, not a shell over it
# The upper's faces end OPEN_BOTTOM m above the foot's lowest point, then its bottom
# edge is drawn down to EDGE m above it (the sole covers it): left where the faces ended
# it wandered 2.5-15 mm above the ground, and the sole's edge with it (a clog's slab);
# cutting the faces lower let the toes' bumps through the leather.
OPEN_BOTTOM = 0.012
EDGE = 0.002
DRAWN_CLEAR = 0.003  # m over the ease the drawn edge keeps: room for a sock where the foot flares
LACES = 5  # eyelet pairs up each side of the lacing

# Atlas rows (v0, v1) in the shoe material: leather upper, the vamp over the ball of the
# foot (``_vamp_uvs``: a fixed place for its flex creases), trim, toe cap, sole, laces.
ROWS = {"upper": (0.7, 1.0), "vamp": (0.6, 0.7), "trim": (0.5, 0.6), "cap": (0.3, 0.5),
        "sole": (0.1, 0.3), "laces": (0.0, 0.1)}  # fmt: skip


@dataclass(frozen=True)
class Style:
    """How a shoe is made: its sole (m: tread under the foot, how far its edge rises over
    the upper, the heel block, the welt, how far the edge rises round the toe), and its
    trim (a heel tab; the atlas row of the lacing's facings)."""

    under: float = UNDER
    cover: float = COVER
    heel: float = HEEL
    welt: float = WELT
    bumper: float = 0.0
    heel_tab: bool = False
    facings: str = "upper"


SHOE = Style()
# A sneaker: a 12 mm rubber midsole under the foot rising 7 mm up the upper (its edge
# ~2.3 cm tall at the ball, against a leather shoe's ~1 cm), 2 cm at the heel, wrapping
# a centimetre further up round the toe (the toe bumper); contrasting facings, heel tab.
# (15 mm rising 11 mm read as an orthopaedic platform.)
SNEAKER = Style(under=0.012, cover=0.007, heel=0.02, welt=0.002, bumper=0.01,
                heel_tab=True, facings="trim")  # fmt: skip


class Foot:
    """One foot of the authoring body: where its heel and toes are, and its ground."""

    def __init__(self, body: AuthoringBody, side: int):
        skin = body.vertices[: len(body.part)]
        mine = (body.part == "foot") & (np.sign(skin[:, 0]) == (1 if side == 0 else -1))
        points = skin[mine]
        self.side = side
        self.heel_y, self.toe_y = float(points[:, 1].max()), float(points[:, 1].min())
        self.ground = float(points[:, 2].min())
        self.centre_x = float(np.median(points[:, 0]))
        self.ankle = body.marks.ankle[side]

    def along(self, p: np.ndarray) -> np.ndarray:
        """(N,) 0 at the heel, 1 at the toes."""
        return (self.heel_y - p[..., 1]) / (self.heel_y - self.toe_y)


# A low shoe's top line (m above the ground) along the foot (0 heel, 1 toes): the heel
# counter, dipping under the ankle bones at the sides, rising to the throat of the lacing
# over the instep; the vamp in front is all kept. Measured on oxfords and derbies.
TOPLINE = ((0.0, 0.12, 0.28, 0.4, 0.5), (0.066, 0.062, 0.048, 0.062, 0.09))
LOW = 0.9  # ``top`` above this along the leg: a low shoe (below the ankle), cut to TOPLINE


def _shoe_faces(body: AuthoringBody, foot: Foot, faces: np.ndarray,
                top: float = 0.96) -> np.ndarray:  # fmt: skip
    """(F,) bool: helper-tights faces of one foot and its ankle, the bottom left open for
    the sole (faces within 1.5 cm of the ground and facing down or out low). A low shoe
    (``top`` > LOW) ends at TOPLINE, under the ankle bones: cut level round the ankle it
    read as an ankle boot (a collar 11 cm high, over the ankle joint)."""
    ff = regions.face_features(body.vertices, faces, body.part, body.marks)
    side = np.sign(ff.centre[:, 0]) == (1 if foot.side == 0 else -1)
    shoe = (ff.part == "foot") | ((ff.part == "leg") & (ff.leg > top))
    low = ff.centre[:, 2] < foot.ground + OPEN_BOTTOM
    if top > LOW:
        line = np.interp(foot.along(ff.centre), *TOPLINE)
        shoe &= ff.centre[:, 2] < foot.ground + line
    return shoe & side & ~low


def upper(body: AuthoringBody, foot: Foot, top: float = 0.96) -> Piece:
    """The upper up to ``top`` along the leg (0.96: below the ankle; 0.85: an ankle boot)."""
    faces = body.group_faces("helper-tights")
    mesh = cut(body, faces, _shoe_faces(body, foot, faces, top), EASE, relax=10)
    mesh = _drawn_down(body, foot, _toe_box(body, foot, mesh, EASE))
    if top <= LOW:
        mesh = _shaft(body, foot, mesh)
    return bound(body, _vamp_uvs(_planar_uvs(mesh, "upper"), foot), faces)


# The vamp's place in the atlas: the upper's faces between these fractions of the foot's
# length (from the heel) over the ball, where the foot bends and the leather creases,
# above the upper's low stitch (VAMP_CLEAR m over it). Its row's v runs with t, its u
# round the foot from the inner side (the big toe's) over the instep to the outer side,
# the same on both feet, so the creases drawn across the row (``_creased``) lie across
# the vamp where the foot flexes. Unwrapped with the rest of the upper (round the foot,
# up it), no texel of the atlas had a fixed place on the vamp.
VAMP_UV = (0.55, 0.85)
VAMP_CLEAR = 0.004


def _vamp_uvs(mesh: Mesh, foot: Foot) -> Mesh:
    """The upper with its vamp's faces' UVs in the vamp row (``VAMP_UV``)."""
    p = mesh.vertices[mesh.faces].astype(np.float64)  # (F, C, 3)
    uvs = mesh.uvs.copy()  # type: ignore[union-attr]
    low, high = float(p[..., 2].min()), float(p[..., 2].max())
    stitch = low + (high - low) * 0.1  # the upper's low stitch (UPPER_STITCH_V)
    t = foot.along(p)
    vamp = ((t.min(axis=1) > VAMP_UV[0]) & (t.max(axis=1) < VAMP_UV[1])
            & (p[..., 2].min(axis=1) > stitch + VAMP_CLEAR))  # fmt: skip
    inner = 1.0 if foot.side == 0 else -1.0  # x > 0 is the left foot: its big toe at -x
    q = p[vamp]
    # The angle round the foot's long axis (a line 1 cm over the ground down its middle):
    # -pi/2 low on the inner side, 0 over the instep, pi/2 low on the outer side.
    phi = np.arctan2(inner * (q[..., 0] - foot.centre_x), q[..., 2] - (foot.ground + 0.01))
    u = 0.02 + 0.96 * np.clip(phi / np.pi + 0.5, 0, 1)
    w = (t[vamp] - VAMP_UV[0]) / (VAMP_UV[1] - VAMP_UV[0])
    v0, v1 = ROWS["vamp"]
    corners = mesh.face_uvs[vamp]  # type: ignore[index]
    uvs[corners] = np.stack([u, v0 + (v1 - v0) * (0.05 + 0.9 * w)], -1)
    return Mesh(mesh.vertices, mesh.faces, uvs, mesh.face_uvs)


def vamp_v(t: float) -> float:
    """Atlas v of the vamp at ``t`` along the foot (0 heel, 1 toes)."""
    v0, v1 = ROWS["vamp"]
    return v0 + (v1 - v0) * (0.05 + 0.9 * (t - VAMP_UV[0]) / (VAMP_UV[1] - VAMP_UV[0]))


# A boot's shaft above the last: SHAFT_EASE m off the skin round the ankle and up the leg,
# flaring out COLLAR m more over its top COLLAR_DEPTH m (a padded collar). Cut from the
# tights shell it stood a straight tube 10-13 mm off the leg all the way up.
SHAFT_EASE = 0.0065
COLLAR = 0.004
COLLAR_DEPTH = 0.025


def _shaft(body: AuthoringBody, foot: Foot, mesh: Mesh) -> Mesh:
    """The upper with its shaft (above the last, ``SHAPED_TO``) laid SHAFT_EASE off the
    leg along the skin's normals, its collar flared."""
    v = mesh.vertices.astype(np.float64)
    z = v[:, 2] - foot.ground
    w = np.clip((z - SHAPED_TO[0]) / (SHAPED_TO[1] - SHAPED_TO[0]), 0, 1)
    w = w * w * (3 - 2 * w)
    flare = np.clip((z - (z.max() - COLLAR_DEPTH)) / COLLAR_DEPTH, 0, 1)
    target = SHAFT_EASE + COLLAR * flare * flare * (3 - 2 * flare)
    for _ in range(2):  # twice: the nearest skin vertex changes as the shaft moves in
        _, i = body.skin_tree.query(v)
        normal = body.skin_normals[i].astype(np.float64)
        gap = np.einsum("nd,nd->n", v - body.vertices[i], normal)
        v -= (w * (gap - target))[:, None] * normal
    return Mesh(v.astype(np.float32), mesh.faces, mesh.uvs, mesh.face_uvs)


def _toe_box(body: AuthoringBody, foot: Foot, mesh: Mesh, ease: float,
             smooth_rim: int = 0) -> Mesh:  # fmt: skip
    """The toe box, and all the shoe: a cut of the foot's faces, split finer and moved onto
    the last (``_Last``), still ``ease`` off the skin; ``smooth_rim``: passes smoothing
    the cut (its boundary along itself, the rest after it) before it goes on the last
    again, so a seam runs in a curve, not in whole faces' steps."""
    # Split finer only where the last shapes it (a boot's shaft above stays as cut).
    low = mesh.vertices[mesh.faces, 2].min(axis=1) < foot.ground + SHAPED_TO[1]
    mesh = _subdivided(mesh, low)
    last = _Last(body, foot, ease)
    points = last.shape(mesh.vertices.astype(np.float64))
    if smooth_rim:
        points = last.shape(_smoothed(mesh.faces, points, smooth_rim))
    # Out to ``ease`` (less over the toes, as the last) along the nearest skin vertex's
    # normal where the last cuts into the foot (a few vertices at the ankle): the worst of
    # eight neighbours (``_at_least``) pushed a third of the shell out up to 16 mm, lumps
    # all over the leather.
    _, i = body.skin_tree.query(points)
    normal = body.skin_normals[i].astype(np.float64)
    gap = np.einsum("nd,nd->n", points - body.vertices[i], normal)
    need = np.interp(foot.along(points), last.t, last.over) + (ease - last.ease)
    points += np.clip(need - gap, 0, None)[:, None] * normal
    return Mesh(points.astype(np.float32), mesh.faces)


def _drawn_down(body: AuthoringBody, foot: Foot, mesh: Mesh, ease: float | None = None,
                reach: float = OPEN_BOTTOM + 0.01) -> Mesh:  # fmt: skip
    """The upper with its bottom edge drawn straight down to EDGE m above the ground, the
    tip curling up with the sole's toe spring (the sole can only curl as far as the edge
    it covers), still ``ease`` + DRAWN_CLEAR off the skin."""
    v = mesh.vertices.astype(np.float64)
    loop = _lowest_loop(mesh)
    loop = loop[v[loop, 2] < foot.ground + reach]  # a toe cap's back edge stays
    spring = SPRING * np.clip((foot.along(v[loop]) - 0.84) / 0.2, 0, 1) ** 2
    v[loop, 2] = np.minimum(v[loop, 2], foot.ground + EDGE + spring)
    if ease is not None:  # on a last the wall already stands clear of the foot
        v[loop] = _at_least(body, v[loop], ease + DRAWN_CLEAR)
    return Mesh(v.astype(np.float32), mesh.faces, mesh.uvs, mesh.face_uvs)


def toe_cap(body: AuthoringBody, foot: Foot) -> Piece:
    faces = body.group_faces("helper-tights")
    centre = body.vertices[faces].mean(axis=1)
    keep = _shoe_faces(body, foot, faces) & (foot.along(centre) > 0.78)
    mesh = cut(body, faces, keep, CAP_EASE, relax=8)
    # Only its bottom edge drawn down to the sole: its seam, one boundary with it, comes
    # down to the sole at the sides and was dragged into spikes.
    mesh = _toe_box(body, foot, mesh, CAP_EASE, smooth_rim=6)
    mesh = _drawn_down(body, foot, mesh, reach=OPEN_BOTTOM)
    mesh = _faired(body, mesh, CAP_EASE)
    # The nose split in four and faired again: faired at the last's resolution it still
    # turned up to 43 degrees between neighbouring faces (21 for one edge in twenty), and
    # the shading's interpolated normals drew blotchy highlights on dark leather.
    nose = foot.along(mesh.vertices[mesh.faces].astype(np.float64).mean(axis=1)) > NOSE_FROM
    mesh = _faired(body, _subdivided(mesh, nose), CAP_EASE)
    return bound(body, _cap_uvs(_skived(mesh, foot), foot), faces)


FAIR_PASSES = 20  # Taubin passes over the toe cap (its folds 55-70 degrees before)
# Along the foot, where the toe cap's nose (split finer) begins. Split back to the cap's
# sides too, its small faces there (where the toe box's wall rolls over onto its top) folded
# over on other feet: the binding's closest points jump across the helper's edge there.
NOSE_FROM = 0.92


def _faired(body: AuthoringBody, mesh: Mesh, ease: float) -> Mesh:
    """The toe cap's surface faired: Taubin-smoothed (a shrinking pass, then an inflating
    one, so the nose keeps its size) with its edges held, then no nearer the skin than
    ``ease``. The last is sampled by the helper's few big faces over the toes, stretched
    14 mm past them, and the edge drawn down to the sole: the cap folded up to 55-70
    degrees between neighbouring faces, and the grain's highlights showed each fold."""
    from avatar.geometry.shell import boundary_edges

    f = mesh.faces
    a = f.reshape(-1).astype(np.int64)
    b = np.roll(f, -1, axis=1).reshape(-1).astype(np.int64)
    keep = a != b  # a triangle's repeated corner is no edge
    a, b = a[keep], b[keep]
    held = np.zeros(len(mesh.vertices), bool)
    held[boundary_edges(f)[0].ravel()] = True
    count = np.zeros(len(held))
    np.add.at(count, a, 1)
    np.add.at(count, b, 1)
    p = mesh.vertices.astype(np.float64)
    for k in range(2 * FAIR_PASSES):
        total = np.zeros_like(p)
        np.add.at(total, a, p[b])
        np.add.at(total, b, p[a])
        step = total / np.maximum(count, 1)[:, None] - p
        p = p + np.where(held[:, None], 0, (0.5 if k % 2 == 0 else -0.53) * step)
    _, i = body.skin_tree.query(p)
    normal = body.skin_normals[i].astype(np.float64)
    gap = np.einsum("nd,nd->n", p - body.vertices[i], normal)
    p += np.clip(ease - gap, 0, None)[:, None] * normal * ~held[:, None]
    return Mesh(p.astype(np.float32), f, mesh.uvs, mesh.face_uvs)


SKIVE = 0.008  # m from the toe cap's seam over which its edge is thinned down to the vamp
SEAM_STEP = 0.0003  # m the cap's edge stands over the vamp at its seam


def _skived(mesh: Mesh, foot: Foot) -> Mesh:
    """The toe cap with its seam edge sunk onto the vamp (to SEAM_STEP over it) over the
    last SKIVE m, as a skived, stitched edge: standing CAP_EASE - EASE proud all the way
    to the seam, its edge caught the light as a pale lip."""
    from scipy.spatial import cKDTree

    from avatar.geometry.shell import boundary_edges
    from avatar.mesh import vertex_normals

    v = mesh.vertices.astype(np.float64)
    rim = np.unique(boundary_edges(mesh.faces)[0])
    seam = rim[v[rim, 2] > foot.ground + OPEN_BOTTOM + 0.004]
    d, _ = cKDTree(v[seam]).query(v)
    w = np.clip(1 - d / SKIVE, 0, 1)
    w = w * w * (3 - 2 * w)
    normal = vertex_normals(mesh.vertices, mesh.faces).astype(np.float64)
    centre = v.mean(axis=0) + [0, 0, -0.02]
    normal *= np.sign(np.einsum("nd,nd->n", normal, v - centre))[:, None]  # outwards
    v -= ((CAP_EASE - EASE - SEAM_STEP) * w)[:, None] * normal
    return Mesh(v.astype(np.float32), mesh.faces, mesh.uvs, mesh.face_uvs)


CAP_UV_REACH = 0.1  # m from the toe cap's seam that its row's height spans
# The width of the atlas the cap's seam spans: across all of it (0.96) a texel was 0.14 mm
# along the seam against 0.57 across it, the stitches' 6-texel dashes beads under a
# millimetre long; across half, 0.28 mm and dashes of 1.7 mm, as on the quarters.
CAP_U_SPAN = 0.48


def _cap_uvs(mesh: Mesh, foot: Foot) -> Mesh:
    """The toe cap's UVs: v from its seam (its back edge, over the vamp: the open edge
    above the sole's) towards the tip, so the atlas's stitch rows run parallel to the seam,
    a few millimetres in front of it; u along the seam (``_along_the_seam``), so it runs
    down the cap's side walls where v runs along the foot. (u was the angle round the
    foot's vertical axis: on the side walls it ran along the foot as v did, the texture's
    axes 1-20 degrees apart and a texel centimetres tall: the grain and gloss drawn as
    wavy streaks down the walls.)"""
    from scipy.spatial import cKDTree

    p = mesh.vertices.astype(np.float64)
    seam = _cap_seam(mesh, foot)
    d, _ = cKDTree(p[seam]).query(p)
    w = 1 - np.clip(d / CAP_UV_REACH, 0, 1)
    v0, v1 = ROWS["cap"]
    u = _along_the_seam(mesh, seam)
    uvs = np.stack([0.02 + CAP_U_SPAN * u, v0 + (v1 - v0) * (0.05 + 0.9 * w)], -1)
    return Mesh(mesh.vertices, mesh.faces, uvs.astype(np.float32), mesh.faces.copy())


def _cap_seam(mesh: Mesh, foot: Foot) -> np.ndarray:
    """Vertex indices, in order along it, of the toe cap's seam: its boundary loop less
    the bottom edge that the sole covers."""
    loop = _lowest_loop(mesh)  # the cap's one boundary loop
    high = mesh.vertices[loop, 2] > foot.ground + OPEN_BOTTOM + 0.004
    start = int(np.argmin(high))  # roll the loop so the seam is one run
    loop, high = np.roll(loop, -start), np.roll(high, -start)
    return loop[high]


def _along_the_seam(mesh: Mesh, seam: np.ndarray) -> np.ndarray:
    """(V,) in [0, 1]: how far along the seam (a fraction of its length) each vertex's
    nearest seam point lies, the seam points within a few SEAM_BLEND m of the nearest
    weighed in softly, so u stays smooth where two stretches of the seam are about as near.
    Across the distance to the seam, as a closest point moves along it."""
    p = mesh.vertices.astype(np.float64)
    s = p[seam]
    length = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(s, axis=0), axis=1))])
    fine = np.linspace(0, length[-1], max(2, int(length[-1] / 0.0005)))  # every 0.5 mm
    points = np.stack([np.interp(fine, length, s[:, k]) for k in range(3)], -1)
    d = np.linalg.norm(p[:, None] - points[None], axis=-1)  # (V, seam points)
    weight = np.exp(-(d - d.min(axis=1, keepdims=True)) / SEAM_BLEND)
    return (weight @ (fine / fine[-1])) / weight.sum(axis=1)


# m: how much farther than the nearest a seam point may lie and still count (at 6-25 mm
# the stretches of seam behind the nose blurred into one another: u crowded into folds).
SEAM_BLEND = 0.003


def cap_stitch_v(mm: float) -> float:
    """Atlas v of a stitch row ``mm`` millimetres in front of the toe cap's seam."""
    v0, v1 = ROWS["cap"]
    return v0 + (v1 - v0) * (0.05 + 0.9 * (1 - mm / 1000 / CAP_UV_REACH))


def _at_least(body: AuthoringBody, points: np.ndarray, gap: float) -> np.ndarray:
    """(N, 3) points pushed out along the nearest skin vertex's normal to ``gap`` m off it."""
    _, i = body.skin_tree.query(points, k=8)
    out = points.copy()
    for k in range(i.shape[1]):  # the worst of the nearest skin vertices decides
        skin, n = body.vertices[i[:, k]], body.skin_normals[i[:, k]].astype(np.float64)
        d = np.einsum("nd,nd->n", out - skin, n)
        out += np.clip(gap - d, 0, None)[:, None] * n * (d > -0.02)[:, None]
    return out


def sole(body: AuthoringBody, foot: Foot, top: Piece, style: Style = SHOE) -> Piece:
    """The sole under an upper: its lowest boundary loop extruded out and down, capped."""
    loop = _lowest_loop(top.mesh)
    ring = _resampled(top.mesh.vertices[loop].astype(np.float64), SOLE_POINTS)
    centre = ring.mean(axis=0)
    out = ring[:, :2] - centre[:2]
    out /= np.linalg.norm(out, axis=1, keepdims=True)
    # The upper bulges over its bottom edge at the sides of the foot: the sole reaches as
    # far out as the upper's lowest 3 cm does in each direction, then a welt further.
    upper = top.mesh.vertices.astype(np.float64)
    low = upper[upper[:, 2] < ring[:, 2].max() + 0.025, :2] - centre[:2]
    reach = low @ out.T  # (L, n) how far each low vertex lies along each ring direction
    across = np.abs(low @ np.stack([-out[:, 1], out[:, 0]], 1).T)  # sideways from that ray
    reach = np.where(across < 0.012, reach, -np.inf).max(axis=0)
    extra = np.clip(reach - np.einsum("nd,nd->n", ring[:, :2] - centre[:2], out), 0, None)
    # A smooth outline in plan (it wavily followed the upper's faces): averaged round the
    # ring (widening it over the neighbours first lifted a settled pose off its soles).
    for _ in range(3):
        extra = 0.5 * extra + 0.25 * (np.roll(extra, 1) + np.roll(extra, -1))
    extra = np.minimum(extra, BULGE)
    ring = ring.copy()
    ring[:, :2] += extra[:, None] * out
    t = foot.along(ring)
    edge, tread = _sole_edge(ring, t, foot, style)
    welt = style.welt
    # The edge's profile: in from the welt's lip, out to a belly a third of the way down,
    # bevelled in under the tread: a rounded outsole (it was a flat plate with a ledge).
    belly = edge - (edge - tread) / 3
    rings = [
        np.column_stack([ring[:, :2] - 0.001 * out - extra[:, None] * out,
                         edge + 0.001]),  # tucked under the upper's edge
        np.column_stack([ring[:, :2] + 0.5 * welt * out, edge]),  # welt top
        np.column_stack([ring[:, :2] + welt * out, belly]),
        np.column_stack([ring[:, :2] + (welt - 0.002) * out, tread]),  # the edge bevelled
    ]
    n = len(ring)
    # The tread's middle, under the arch: lifted as the arch's edge is, by half.
    points = np.concatenate([*rings, [[centre[0], centre[1], tread.min() + ARCH / 2]]])
    faces = []
    for r in range(len(rings) - 1):
        a, b = r * n, (r + 1) * n
        for i in range(n):
            j = (i + 1) % n
            faces.append([a + i, a + j, b + j, b + i])
    middle, bottom = len(points) - 1, (len(rings) - 1) * n
    # The tread (never seen from above): quads of two ring edges each to the middle.
    faces += [[bottom + (i + 2) % n, bottom + (i + 1) % n, bottom + i, middle]
              for i in range(0, n - n % 2, 2)]
    if n % 2:
        faces.append([bottom, bottom + n - 1, middle, middle])
    mesh = Mesh(points.astype(np.float32), np.array(faces, np.int32))
    mesh = _facing_out(mesh, centre + [0, 0, 0.02])
    mesh = _planar_uvs(mesh, "sole")
    # v by ring (the welt's top lip, the wall, the tread), so a stitch row or a moulded
    # band drawn across the atlas runs round the sole at one place on its edge.
    height = np.concatenate([np.repeat(SOLE_RINGS, n), [0.0]])[mesh.faces.reshape(-1)]
    v0, v1 = ROWS["sole"]
    uvs = mesh.uvs.copy()  # type: ignore[union-attr]
    uvs[:, 1] = v0 + (v1 - v0) * (0.05 + 0.9 * height)
    mesh = Mesh(mesh.vertices, mesh.faces, uvs, mesh.face_uvs)
    return bound(body, mesh, body.group_faces("helper-tights"))


SOLE_POINTS = 44  # round the sole (the upper's bottom edge has ~60: a 30% lighter sole)


def _resampled(ring: np.ndarray, n: int) -> np.ndarray:
    """(n, 3) points evenly along a closed polyline (M, 3)."""
    closed = np.concatenate([ring, ring[:1]])
    length = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(closed, axis=0), axis=1))])
    s = np.linspace(0, length[-1], n, endpoint=False)
    return np.column_stack([np.interp(s, length, closed[:, k]) for k in range(3)])


# The sole's rings' places in its atlas row (0 the tread's middle, 1 the edge tucked under
# the upper): the welt's top lip spans 0.9-1, the wall 0.1-0.9 (its belly, a third of the
# way down, at 0.63).
SOLE_RINGS = (1.0, 0.9, 0.63, 0.1)


def sole_v(place: float) -> float:
    """Atlas v of a ``place`` on the sole's edge (``SOLE_RINGS``: 0.1 bottom of the wall,
    0.9 its top, 0.95 on the welt's lip)."""
    v0, v1 = ROWS["sole"]
    return v0 + (v1 - v0) * (0.05 + 0.9 * place)


def _sole_edge(ring: np.ndarray, t: np.ndarray, foot: Foot,
               style: Style = SHOE) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """(top (n,), tread (n,)) z of the sole's edge round the ``ring`` (n, 3) of the upper's
    bottom edge at ``t`` (n,) along the foot: the top COVER over the upper's edge (smoothed
    round the ring, at least HEEL above the ground behind the heel's breast); the tread
    flat under heel and ball, lifted ARCH under the arch and SPRING at the toe's tip."""
    top = ring[:, 2] + style.cover
    for _ in range(6):  # the upper's edge follows whole helper faces: a ragged line
        smooth = 0.5 * top + 0.25 * (np.roll(top, 1) + np.roll(top, -1))
        top = np.maximum(ring[:, 2] + style.cover, smooth)
    heel = np.clip((0.3 - t) / 0.06, 0, 1)  # the heel block ends at its breast, t ~ 0.27
    top = np.maximum(top, foot.ground + style.heel * heel)
    toe = np.clip((t - 0.82) / 0.12, 0, 1)
    top = top + style.bumper * toe * toe * (3 - 2 * toe)  # a sneaker's toe bumper
    # The waist lifted off the ground from the heel's breast (a step, so the heel reads as
    # a heel) to the ball, easing down into it.
    rise, fall = np.clip((t - 0.27) / 0.04, 0, 1), np.clip((0.66 - t) / 0.12, 0, 1)
    arch = ARCH * np.minimum(rise, fall * fall * (3 - 2 * fall))
    spring = SPRING * np.clip((t - 0.84) / 0.2, 0, 1) ** 2
    tread = foot.ground - style.under + arch + spring
    return top, np.minimum(tread, top - 0.004)


# Heights (m) over the upper's surface of the lacing's layers: the tongue, the quarters'
# facings on it, eyelets in the facings, the lace through them (its crown a little higher
# again, and higher still where it crosses over the one before). Each layer is bound to
# the body on its own: on other bodies than the authoring one a layer 0.6 mm over the one
# under it sank into it in patches (navy facings as blotches on a sneaker).
TONGUE_LIFT, FACING_LIFT, EYELET_LIFT, LACE_LIFT = 0.001, 0.002, 0.0026, 0.0032
LACE_WIDTH = 0.0035
SKIVED_END = 0.0003  # m a tongue's or facing's front end stands over the upper
TONGUE_OVER = 0.003  # m the tongue's top stands over the top eyelets
BOW_OVER = 0.005  # m the bow's loops reach over the top eyelets (flopped on the instep)
LACE_ROWS = (0.72, 0.47)  # along the foot: the lowest eyelets (towards the toes), the top


class _Surface:
    """Rays against an upper (its quads as triangles): where a vertical ray from above,
    or a ray from behind, first meets the leather."""

    def __init__(self, mesh: Mesh):
        f = mesh.faces
        tris = np.concatenate([f[:, [0, 1, 2]], f[:, [0, 2, 3]]])
        self.v = mesh.vertices.astype(np.float64)
        self.tris = tris[(tris[:, 0] != tris[:, 1]) & (tris[:, 1] != tris[:, 2])
                         & (tris[:, 0] != tris[:, 2])]  # fmt: skip

    def hit(self, origins: np.ndarray, direction) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(points (N, 3), unit normals facing the ray's origin (N, 3), hit (N,) bool) of
        rays from ``origins`` (N, 3) along ``direction`` (3,) (Moller-Trumbore)."""
        d = np.asarray(direction, np.float64)
        a, b, c = (self.v[self.tris[:, i]] for i in range(3))
        e1, e2 = b - a, c - a
        p = np.cross(d, e2)
        det = np.einsum("td,td->t", e1, p)
        ok = np.abs(det) > 1e-12
        inv = np.where(ok, 1 / np.where(ok, det, 1), 0)
        s = origins[:, None] - a[None]  # (N, T, 3)
        u = np.einsum("ntd,td->nt", s, p) * inv
        q = np.cross(s, e1[None])
        w = np.einsum("d,ntd->nt", d, q) * inv
        dist = np.einsum("ntd,td->nt", q, e2) * inv
        inside = ok & (u >= 0) & (w >= 0) & (u + w <= 1) & (dist > 0)
        dist = np.where(inside, dist, np.inf)
        first = np.argmin(dist, axis=1)
        found = np.isfinite(dist[np.arange(len(origins)), first])
        points = origins + np.where(found, dist[np.arange(len(origins)), first], 0)[:, None] * d
        normal = np.cross(e1, e2)[first]
        normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-12)
        normal *= -np.sign(normal @ d)[:, None]
        return points, normal, found

    def over(self, xy: np.ndarray, lift: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Points ``lift`` m above the upper's top at xy (N, 2), their normals, hit."""
        origins = np.column_stack([xy, np.full(len(xy), self.v[:, 2].max() + 0.05)])
        points, normal, found = self.hit(origins, (0.0, 0.0, -1.0))
        return points + lift * normal, normal, found


@dataclass(frozen=True)
class Lacing:
    """Where a shoe's lacing is: eyelet rows ``y`` (K,) from the toes up, the throat's
    middle ``x`` (K,) and its half-width ``half`` (K,) at each."""

    y: np.ndarray
    x: np.ndarray
    half: np.ndarray

    def eyelets(self, side: int) -> np.ndarray:
        """(K, 2) xy of the eyelets on one quarter (side -1 or +1)."""
        return np.column_stack([self.x + side * self.half, self.y])


def _lacing(foot: Foot, top: Piece, rows: int = LACES) -> Lacing:
    """The lacing's plan on an upper: rows from LACE_ROWS[0] up the instep to LACE_ROWS[1],
    or as far as both eyelets of the top row still lie on the leather (the throat)."""
    v = top.mesh.vertices.astype(np.float64)
    t = foot.along(v)
    surface = _Surface(top.mesh)
    for highest in np.arange(LACE_ROWS[1], LACE_ROWS[0] - 0.1, 0.01):
        at = np.linspace(LACE_ROWS[0], highest, rows)
        x = np.empty(rows)
        for k, tk in enumerate(at):  # the instep's ridge: the middle of its top 0.5 mm (its
            band = np.abs(t - tk) < 0.03  # highest vertex wandered 1 cm over a flat top)
            ridge = band & (v[:, 2] > v[band, 2].max() - 0.0005) if band.any() else band
            x[k] = v[ridge, 0].mean() if ridge.any() else foot.centre_x
        x = np.polyval(np.polyfit(at, x, 1), at)  # one straight throat
        y = foot.heel_y - at * (foot.heel_y - foot.toe_y)
        half = 0.0095 + 0.0045 * (LACE_ROWS[0] - at) / (LACE_ROWS[0] - LACE_ROWS[1])
        plan = Lacing(y, x, half)
        ends = np.concatenate([plan.eyelets(-1)[-1:], plan.eyelets(1)[-1:]])
        top_xy = ends + [0, 0.006]  # the tongue's end and the knot, beyond the top pair
        if surface.over(np.concatenate([ends, top_xy]), 0.0)[2].all():
            break
    return plan


def _ribbon(points: np.ndarray, normals: np.ndarray, width: float, crown: float) -> Mesh:
    """A strip along a polyline (M, 3) lying on a surface of ``normals`` (M, 3): two
    vertices across, its edges ``crown`` m lower than its middle line (the garment's
    thickness makes it a cord; a third vertex across for a crown cost 40% of a pair's
    triangles in laces)."""
    tangent = np.gradient(points, axis=0)
    tangent /= np.maximum(np.linalg.norm(tangent, axis=1, keepdims=True), 1e-12)
    side = np.cross(normals, tangent)
    side /= np.maximum(np.linalg.norm(side, axis=1, keepdims=True), 1e-12)
    across = [points - side * width / 2 + normals * crown / 2,
              points + side * width / 2 + normals * crown / 2]
    n = len(points)
    faces = [[i, i + 1, n + i + 1, n + i] for i in range(n - 1)]
    return Mesh(np.concatenate(across).astype(np.float32), np.array(faces, np.int32))


def _sheet(surface: _Surface, xy: np.ndarray, lift: float) -> Mesh | None:
    """A grid (R, C, 2) of xy laid ``lift`` m over the upper (rows missing it dropped),
    its first row (the front end, towards the toes) sunk to SKIVED_END over it: a step
    the leather's thickness over the vamp caught the light as a pale lip."""
    r, c = xy.shape[:2]
    points, normal, found = surface.over(xy.reshape(-1, 2), 0.0)
    rows = np.full(r, lift)
    rows[0] = min(lift, SKIVED_END)
    points = points + np.repeat(rows, c)[:, None] * normal
    keep = found.reshape(r, c).all(axis=1)
    if keep.sum() < 2:
        return None
    grid = points.reshape(r, c, 3)[keep]
    r = len(grid)
    idx = np.arange(r * c).reshape(r, c)
    faces = np.stack([idx[:-1, :-1], idx[:-1, 1:], idx[1:, 1:], idx[1:, :-1]], -1).reshape(-1, 4)
    return Mesh(grid.reshape(-1, 3).astype(np.float32), faces.astype(np.int32))


# The tongue's and facings' share of their atlas row: above the stitch low on the upper
# (UPPER_STITCH_V, at 0.14 of the row), which, over all the row, ran across their front
# ends by the lowest eyelets as a pale dashed line.
LACING_BAND = (0.3, 0.95)


def lacing(body: AuthoringBody, foot: Foot, top: Piece, style: Style = SHOE) -> list[Piece]:
    """The lacing on an upper: a tongue, the quarters' facings with their eyelets, and the
    lace criss-crossing between them, one strip from bow to bow (``lace``)."""
    surface = _Surface(top.mesh)
    plan = _lacing(foot, top)
    faces = body.group_faces("helper-tights")
    along = np.linspace(plan.y[0] - 0.012, plan.y[-1] + 0.004, 7)  # toes to throat
    x = np.interp(along, plan.y[::-1], plan.x[::-1])
    half = np.interp(along, plan.y[::-1], plan.half[::-1])
    tongue = _sheet(surface, np.stack([np.column_stack([x + f * (half + 0.004), along])
                                       for f in np.linspace(-1, 1, 4)], 1), TONGUE_LIFT)
    pieces = []
    if tongue is not None:
        # Lying on the instep, its top TONGUE_OVER over the top eyelets: laid over the
        # steep throat it stood up as a flap above the laces.
        v = tongue.vertices.copy()
        v[:, 2] = np.minimum(v[:, 2], _top_eyelets_z(surface, plan) + TONGUE_OVER)
        tongue = Mesh(v, tongue.faces)
        pieces.append(bound(body, _planar_uvs(tongue, "upper", LACING_BAND), faces))
    facings = []
    for side in (-1, 1):
        # Columns from -x to +x, so both facings' faces face up: the inner one's faced down,
        # its shell's outer layer seen from behind, the grain's highlights inverted (a pale
        # speckled sheen down it, brightest at its front end).
        across = np.sort(side * np.array([half - 0.005, half + 0.002, half + 0.009]), axis=0)
        grid = np.stack([np.column_stack([x + a, along]) for a in across], 1)
        sheet = _sheet(surface, grid, FACING_LIFT)
        if sheet is not None:
            facings.append(sheet)
    if facings:
        facing_uvs = _planar_uvs(_merge(facings), style.facings, LACING_BAND)
        pieces.append(bound(body, facing_uvs, faces))
    eyelets = [_disc(surface, xy, 0.0024) for side in (-1, 1) for xy in plan.eyelets(side)]
    pieces.append(bound(body, _planar_uvs(_merge(eyelets), "trim"), faces))
    shaft = _shaft_rows(foot, top, plan, surface)
    pieces.append(bound(body, _planar_uvs(lace(surface, plan, shaft is None), "laces"), faces))
    if shaft is not None:
        pieces += shaft_lacing(body, surface, plan, shaft, style)
    return pieces


# A boot's lacing goes on up the front of its shaft: rows SHAFT_STEP m apart from the
# instep's top eyelets to SHAFT_TOP m under the collar, the throat's half-width there
# widening by SHAFT_SPREAD; facings up it, the bow at the top. Laced only
# over the instep, a boot's shaft stood closed and bare up the front of the ankle.
SHAFT_STEP = 0.02
SHAFT_TOP = 0.014
SHAFT_SPREAD = 0.002


@dataclass(frozen=True)
class ShaftRows:
    """Where a boot's lacing runs up its shaft: rows at heights ``z`` (K,) (the first the
    instep's top eyelets), the throat's middle ``x`` (K,) and half-width ``half`` (K,)."""

    z: np.ndarray
    x: np.ndarray
    half: np.ndarray

    def eyelets(self, side: int) -> np.ndarray:
        """(K, 2) xz of the eyelets on one side (-1 or +1)."""
        return np.column_stack([self.x + side * self.half, self.z])


def _shaft_rows(foot: Foot, top: Piece, plan: Lacing, surface: _Surface) -> ShaftRows | None:
    """The rows up a boot's shaft (None for a low shoe: no shaft above the lacing)."""
    v = top.mesh.vertices.astype(np.float64)
    start = _top_eyelets_z(surface, plan) - EYELET_LIFT
    collar = float(v[:, 2].max())
    count = int((collar - SHAFT_TOP - start) // SHAFT_STEP)
    if count < 1:
        return None
    z = start + SHAFT_STEP * np.arange(count + 1)
    # The throat's middle: the instep's at the bottom, the shin's front (its foremost
    # vertices) at the top.
    x = np.empty(len(z))
    for k, zk in enumerate(z):
        band = v[np.abs(v[:, 2] - zk) < 0.006]
        front = band[band[:, 1] < band[:, 1].min() + 0.004]
        x[k] = front[:, 0].mean()
    x[0] = plan.x[-1]
    x = np.polyval(np.polyfit(z, x, 1), z)  # one straight line up the shin
    x += (plan.x[-1] - x[0]) * np.linspace(1, 0, len(z))  # from the instep's top pair
    half = plan.half[-1] + SHAFT_SPREAD * np.linspace(0, 1, len(z))
    return ShaftRows(z, x, half)


def _front(surface: _Surface, xz: np.ndarray, lift: float) -> tuple[np.ndarray, np.ndarray]:
    """Points ``lift`` m out of the upper's front at xz (N, 2) (rays from in front along
    +y, the way the body faces), and the normals there."""
    y = surface.v[:, 1].min() - 0.05
    origins = np.column_stack([xz[:, 0], np.full(len(xz), y), xz[:, 1]])
    points, normal, found = surface.hit(origins, (0.0, 1.0, 0.0))
    if not found.all():  # past the shaft's edge (over the collar): as far back as the rest
        index = np.arange(len(xz))
        points[~found, 1] = np.interp(index[~found], index[found], points[found, 1])
        normal[~found] = (0.0, -1.0, 0.0)
    return points + lift * normal, normal


def shaft_lacing(body: AuthoringBody, surface: _Surface, plan: Lacing, rows: ShaftRows,
                 style: Style = SHOE) -> list[Piece]:  # fmt: skip
    """A boot's lacing up its shaft's front (``ShaftRows``): a facing either side with
    eyelets, and the lace's two ends criss-crossing on up from the instep's top eyelets to
    a bow under the collar. (No tongue up the shaft: the shaft's own leather under the
    lace reads as one, a millimetre lower, for a fifth of the lacing's triangles.)"""
    faces = body.group_faces("helper-tights")
    z = np.linspace(rows.z[0] - 0.004, rows.z[-1] + 0.01, 2 * len(rows.z))  # ~1 cm apart
    x = np.interp(z, rows.z, rows.x)
    half = np.interp(z, rows.z, rows.half)

    def sheet(across: np.ndarray, lift: float) -> Mesh:  # a grid up the shaft's front
        across = np.sort(across, axis=1)  # columns from -x to +x: faces facing forward (-y)
        xz = np.stack([np.column_stack([x + a, z]) for a in across.T], 1)  # (R, C, 2)
        points, _ = _front(surface, xz.reshape(-1, 2), lift)
        r, c = xz.shape[:2]
        idx = np.arange(r * c).reshape(r, c)
        quads = np.stack([idx[:-1, :-1], idx[:-1, 1:], idx[1:, 1:], idx[1:, :-1]], -1)
        return Mesh(points.astype(np.float32), quads.reshape(-1, 4).astype(np.int32))

    facings = [sheet(side * (half[:, None] + np.array([[-0.005, 0.009]])), FACING_LIFT)
               for side in (-1, 1)]  # fmt: skip
    eyelets = [_front_disc(surface, xz, 0.0024) for side in (-1, 1)
               for xz in rows.eyelets(side)[1:]]  # fmt: skip
    return [
        bound(body, _planar_uvs(_merge(facings), style.facings, LACING_BAND), faces),
        bound(body, _planar_uvs(_merge(eyelets), "trim"), faces),
        bound(body, _planar_uvs(_shaft_lace(surface, rows), "laces"), faces),
    ]


def _front_disc(surface: _Surface, xz: np.ndarray, radius: float) -> Mesh:
    """An eyelet on the shaft's front: a hexagon ``radius`` m round xz, EYELET_LIFT out."""
    angle = np.linspace(0, 2 * np.pi, 6, endpoint=False)
    ring = xz + radius * np.column_stack([np.cos(angle), np.sin(angle)])
    points, _ = _front(surface, ring, EYELET_LIFT)
    faces = [[0, 1, 2, 3], [0, 3, 4, 5]]  # counter-clockwise in xz: facing forward (-y)
    return Mesh(points.astype(np.float32), np.array(faces, np.int32))


def _shaft_lace(surface: _Surface, rows: ShaftRows) -> Mesh:
    """The lace's two ends on up the shaft from the instep's top eyelets, crossing between
    every pair of rows (the one from the right over), to a knot over the top pair and a
    bow lying on the shaft's front: two strips."""
    left, right = rows.eyelets(-1), rows.eyelets(1)
    k = len(rows.z)
    a_ends = [left[i] if i % 2 == 0 else right[i] for i in range(k)]
    b_ends = [right[i] if i % 2 == 0 else left[i] for i in range(k)]
    knot = np.array([rows.x[-1], rows.z[-1] + 0.005])
    first, second = _boot_bow(knot)
    strips = []
    for ends, rise, loop in ((a_ends, 0.0003, first[::-1]), (b_ends, 0.0012, second)):
        path, lift = [], []
        for a, b in zip(ends[:-1], ends[1:], strict=True):
            s = np.linspace(0, 1, 2, endpoint=False)
            path.extend(a + s[:, None] * (b - a))
            lift.extend(LACE_LIFT + rise * np.sin(np.pi * s))
        s = np.linspace(0, 1, 3, endpoint=False)
        path.extend(ends[-1] + s[:, None] * (knot - ends[-1]))
        lift.extend([LACE_LIFT + 0.0008] * 3)
        path.extend(loop)
        lift.extend([LACE_LIFT + BOOT_BOW_LIFT] * len(loop))  # over the top crossing
        points, normal = _front(surface, np.asarray(path), 0.0)
        strips.append(_ribbon(points + np.asarray(lift)[:, None] * normal, normal,
                              LACE_WIDTH, 0.0007))  # fmt: skip
    return _merge(strips)


def _top_eyelets_z(surface: _Surface, plan: Lacing) -> float:
    """z (m) of the higher of the top pair of eyelets."""
    ends = np.concatenate([plan.eyelets(-1)[-1:], plan.eyelets(1)[-1:]])
    return float(surface.over(ends, EYELET_LIFT)[0][:, 2].max())


def _disc(surface: _Surface, xy: np.ndarray, radius: float) -> Mesh:
    """An eyelet: a hexagon ``radius`` m round xy lying EYELET_LIFT over the upper."""
    angle = np.linspace(0, 2 * np.pi, 6, endpoint=False)
    ring = xy + radius * np.column_stack([np.cos(angle), np.sin(angle)])
    points, _, _ = surface.over(ring, EYELET_LIFT)
    faces = [[0, 1, 2, 3], [0, 3, 4, 5]]  # two quads, not a fan of six: a third the triangles
    return Mesh(points.astype(np.float32), np.array(faces, np.int32))


def lace(surface: _Surface, plan: Lacing, bow: bool = True) -> Mesh:
    """One lace: straight across the lowest eyelets, then each end up to the next eyelet on
    the far side (criss-cross: the two ends cross between every pair of rows, the end
    coming from the right over the one from the left), up to a knot above the top pair,
    tied in a bow (two loops and two tails); without ``bow`` its ends stop at the top pair
    (a boot's lace goes on up the shaft: ``shaft_lacing``)."""
    left, right = plan.eyelets(-1), plan.eyelets(1)
    k = len(plan.y)
    # The path through the eyelets: L(K-1) ... R1, L0 | R0, L1, R2 ... (one strip).
    up_a = [left[i] if i % 2 == 0 else right[i] for i in range(k)]  # from L0
    up_b = [right[i] if i % 2 == 0 else left[i] for i in range(k)]  # from R0
    knot = np.array([plan.x[-1], plan.y[-1] + 0.004])
    path, lift = [], []

    def run(a, b, rise: float, steps: int = 2) -> None:  # a vertex where the ends cross
        s = np.linspace(0, 1, steps, endpoint=False)
        path.extend(a + s[:, None] * (b - a))
        lift.extend(LACE_LIFT + rise * np.sin(np.pi * s))

    loops = _bow(knot, plan.half[-1])
    if bow:
        for a, b in zip(loops[0][:-1], loops[0][1:], strict=True):  # tail, loop, to the knot
            run(a, b, 0.0015, 1)
        run(knot, up_a[-1], 0.0008, 3)
    for a, b in zip(up_a[::-1][:-1], up_a[::-1][1:], strict=True):  # down one end
        run(a, b, 0.0003)
    run(left[0], right[0], 0.0006)  # across the lowest pair
    for a, b in zip(up_b[:-1], up_b[1:], strict=True):  # up the other, over the first
        run(a, b, 0.0012)
    if bow:
        run(up_b[-1], knot, 0.0008, 3)
        for a, b in zip(loops[1][:-1], loops[1][1:], strict=True):
            run(a, b, 0.0015, 1)
    end = loops[1][-1] if bow else up_b[-1]
    path.append(end)
    lift.append(LACE_LIFT)
    xy = np.asarray(path)
    points, normal, found = surface.over(xy, 0.0)
    # Past the upper's edge (a loop's end over the opening): at its neighbours' height.
    index = np.arange(len(xy))
    points[~found, 2] = np.interp(index[~found], index[found], points[found, 2])
    normal[~found] = (0.0, 0.0, 1.0)
    points = points + np.asarray(lift)[:, None] * normal
    points[:, 2] = np.minimum(points[:, 2], _top_eyelets_z(surface, plan) + BOW_OVER)
    return _ribbon(points, normal, LACE_WIDTH, 0.0007)


def _bow(knot: np.ndarray, half: float) -> tuple[np.ndarray, np.ndarray]:
    """(first, second) xy polylines of a bow: the first from one tail's end to the knot and
    round its loop back to it, the second round the other loop and out to the other tail."""
    phi = np.linspace(0, 2 * np.pi, 8)

    def loop(side: int) -> np.ndarray:
        return knot + np.column_stack([side * (half + 0.012) * (1 - np.cos(phi)) / 2,
                                       0.009 * side * np.sin(phi)])  # fmt: skip

    def tail(side: int) -> np.ndarray:  # from the knot out to its end
        return knot + np.linspace(0, 1, 3)[:, None] * [side * 0.008, -0.03]

    return np.concatenate([tail(-1)[::-1], loop(-1)[1:]]), np.concatenate([loop(1), tail(1)[1:]])


# A boot's bow, on the shaft's front under the collar: loops BOOT_LOOP m long and
# BOOT_LOOP_WIDE across at their widest (towards their ends), drooping BOOT_DROOP radians
# below level, and tails hanging BOOT_TAIL m down beside the lacing, BOOT_BOW_LIFT over the
# lace. The low shoe's bow (``_bow``: level loops reaching the eyelets' half-width and
# 12 mm more either side) put the loops' ends 31 mm out, round the side of the ankle,
# where the shaft turned 80 degrees away: from the front two squashed slits, tails 3 cm.
BOOT_LOOP, BOOT_LOOP_WIDE, BOOT_DROOP = 0.026, 0.019, 1.1
BOOT_TAIL = 0.045
BOOT_BOW_LIFT = 0.0025


def _boot_bow(knot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(first, second) xz polylines of a boot's bow (``_bow``'s order: one tail's end to
    the knot and round its loop; the other loop, then out to its tail): teardrop loops,
    narrow at the knot and round at their ends, drooping down the shaft's front."""
    phi = np.linspace(0, 2 * np.pi, 12)
    along = BOOT_LOOP * (1 - np.cos(phi)) / 2
    across = BOOT_LOOP_WIDE / 2 * np.sin(phi) * (0.45 + 0.55 * (1 - np.cos(phi)) / 2)

    def loop(side: int) -> np.ndarray:
        axis = np.array([side * np.cos(BOOT_DROOP), -np.sin(BOOT_DROOP)])
        normal = np.array([side * np.sin(BOOT_DROOP), np.cos(BOOT_DROOP)])
        return knot + along[:, None] * axis + (side * across)[:, None] * normal

    def tail(side: int) -> np.ndarray:  # from the knot down beside the lacing
        return knot + np.linspace(0, 1, 4)[:, None] * [side * 0.007, -BOOT_TAIL]

    return np.concatenate([tail(-1)[::-1], loop(-1)[1:]]), np.concatenate([loop(1), tail(1)[1:]])


def heel_tab(body: AuthoringBody, foot: Foot, top: Piece) -> Piece:
    """A sneaker's heel tab: a strip 2.4 cm wide down the back of the heel from 9 mm above
    the collar (a pull loop) to 3.5 cm below it, a millimetre over the upper."""
    from avatar.geometry.shell import boundary_edges

    surface = _Surface(top.mesh)
    v = top.mesh.vertices.astype(np.float64)
    rim = np.unique(boundary_edges(top.mesh.faces)[0])
    rim = rim[v[rim, 2] > foot.ground + 0.03]
    collar = v[rim[np.argmin(foot.along(v[rim]))]]
    zs = collar[2] - np.linspace(0.035, 0.002, 6)
    xs = collar[0] + np.linspace(-0.012, 0.012, 3)
    origins = np.array([[x, foot.heel_y + 0.05, z] for z in zs for x in xs])
    points, normal, found = surface.hit(origins, (0.0, -1.0, 0.0))
    points = points + 0.001 * normal
    grid = points.reshape(len(zs), len(xs), 3)
    ok = found.reshape(len(zs), len(xs)).all(axis=1)
    grid = grid[ok]
    # The loop above the collar: on up the heel's line, clear of the skin.
    slope = grid[-1] - grid[-2]
    slope /= np.linalg.norm(slope, axis=1, keepdims=True)
    above = grid[-1] + 0.009 * slope
    above = _at_least(body, above, EASE + 0.003)
    grid = np.concatenate([grid, above[None]])
    r, c = grid.shape[:2]
    idx = np.arange(r * c).reshape(r, c)
    faces = np.stack([idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]], -1).reshape(-1, 4)
    mesh = _facing_out(Mesh(grid.reshape(-1, 3).astype(np.float32), faces.astype(np.int32)),
                       collar + [0, -0.04, -0.02])  # fmt: skip
    return bound(body, _planar_uvs(mesh, "trim"), body.group_faces("helper-tights"))


def shoes(body: AuthoringBody, top: float = 0.96, style: Style = SHOE) -> Piece:
    """Both shoes, every piece bound to the body's ``helper-tights`` shell; ``top``: how
    far up the leg the upper reaches (``upper``); ``style``: a shoe's or a sneaker's."""
    pieces = []
    for side in (0, 1):
        foot = Foot(body, side)
        top_piece = upper(body, foot, top)
        pieces += [*capped(body, foot, top_piece), sole(body, foot, top_piece, style),
                   *lacing(body, foot, top_piece, style)]  # fmt: skip
        if style.heel_tab:
            pieces.append(heel_tab(body, foot, top_piece))
    return _scaled_by_the_foot(body, join(pieces))


def _scaled_by_the_foot(body: AuthoringBody, piece: Piece) -> Piece:
    """The shoes with their offsets scaled by the foot (its width, length and height), not
    by the head (``bound``'s pairs, MakeHuman's default): a child's head is large for its
    feet, so a child's soles, welts and toe boxes came out a third too thick."""
    from avatar.clothes.binding import make_binding

    skin = body.vertices[: len(body.part)]
    foot = np.flatnonzero((body.part == "foot") & (skin[:, 0] > 0))
    p = skin[foot]
    refs = np.array([[foot[np.argmin(p[:, k])], foot[np.argmax(p[:, k])]] for k in range(3)])
    lengths = np.ptp(p, axis=0).astype(np.float64)
    b = piece.binding
    binding = make_binding(b.indices, b.weights, b.offsets, refs, lengths, b.single)
    return Piece(piece.mesh, binding, piece.layout)


CAP_OVERLAP = 0.012  # m the upper runs on under the toe cap past its seam
THROAT_OVER = 0.003  # m over the top eyelets where the upper's throat ends


def capped(body: AuthoringBody, foot: Foot, top: Piece) -> tuple[Piece, Piece]:
    """(the upper as worn, its toe cap): the upper without its faces hidden under the cap
    (all corners within 4 mm of it and CAP_OVERLAP past its seam: never seen, they were
    a tenth of a pair's triangles) and its throat cut down to THROAT_OVER over the top
    eyelets."""
    from scipy.spatial import cKDTree

    from avatar.geometry.shell import boundary_edges

    cap = toe_cap(body, foot)
    c = cap.mesh.vertices.astype(np.float64)
    rim = np.unique(boundary_edges(cap.mesh.faces)[0])
    seam = rim[c[rim, 2] > foot.ground + OPEN_BOTTOM + 0.004]  # the seam over the vamp
    v = top.mesh.vertices.astype(np.float64)
    under = (cKDTree(c).query(v)[0] < 0.004) & (cKDTree(c[seam]).query(v)[0] > CAP_OVERLAP)
    keep = ~under[top.mesh.faces].all(axis=1)
    # The throat opens to just over the top eyelets: the upper ran on up the front of the
    # ankle, a flap standing over the laces and the tongue.
    corners = v[top.mesh.faces]
    surface, plan = _Surface(top.mesh), _lacing(foot, top)
    line = _top_eyelets_z(surface, plan) + THROAT_OVER
    if _shaft_rows(foot, top, plan, surface) is None:  # a boot's is laced on up the shaft
        keep &= ~((foot.along(corners.mean(axis=1)) > 0.42) & (corners[..., 2].max(axis=1) > line))
    seen = bound(body, top.mesh.subset(np.flatnonzero(keep)), body.group_faces("helper-tights"))
    return seen, cap


def sneakers(body: AuthoringBody) -> Piece:
    """Low sneakers: the shoe on a deep midsole with a toe bumper and a heel tab."""
    return shoes(body, style=SNEAKER)


# ---------------------------------------------------------------------------- the last
# A shoe is made on a last, not on the foot: its upper follows the foot's outline in plan
# (the footprint's convex hull, eased, the toe box drawn out past the toes) with upright
# walls WALL m high round the sole, rolling over (a quarter round of radius up to
# ROLL x the height left) onto a top that runs straight down the vamp from the throat to
# the toe. Shaped from the foot's helper faces the upper was a smoothed foot: an inflated
# shell, the vamp domed, the toe a ball, the sides bulging over a pinched bottom edge.
WALL = 0.011
ROLL = 0.75
TOE_BOX = 0.0125  # m the outline reaches past the toes (the cap faired: ~13; 16 read long)
TAPER = 0.3  # how much narrower the toe box's tip is than the toes' spread
TOE_EASE = 0.003  # m over the toes (the instep has EASE)
# The toe box's front in profile: its top comes down from over the toes in a curve to
# NOSE m over the wall at its tip, where the wall is TOE_WALL x WALL high, and the roll
# over onto the top rounds it (it ran down to a low tip 15 mm over the ground, under the
# wall's top, with the toe spring rising to meet it: a beak).
NOSE = 0.0055
TOE_WALL = 0.3
VAMP = (0.66, 0.97)  # along the foot: the vamp's straight run, from the throat to the toe
SHAPED_TO = (0.07, 0.1)  # m above the ground: shaped fully below, not at all above (a boot)


class _Last:
    """The last a shoe is made on: its outline in plan, wall and top heights along the foot."""

    def __init__(self, body: AuthoringBody, foot: Foot, ease: float):
        skin = body.vertices[: len(body.part)]
        near = (np.sign(skin[:, 0]) == (1 if foot.side == 0 else -1)) & (
            skin[:, 2] < foot.ground + 0.13) & (np.abs(skin[:, 0] - foot.centre_x) < 0.08)
        low = near & (skin[:, 2] < foot.ground + 0.07)  # all the shoe covers: no dents
        from scipy.spatial import ConvexHull

        plan = skin[low, :2].astype(np.float64)
        hull = plan[ConvexHull(plan).vertices]
        self.outline = _offset_outline(hull, ease, foot)
        self.foot, self.ease = foot, ease
        # Stations along the foot: half-width in plan and the top (the skin's highest point
        # there, eased; straight down the vamp).
        self.t = np.linspace(-0.15, 1.2, 82)
        y = foot.heel_y - self.t * (foot.heel_y - foot.toe_y)
        points = skin[near & (body.part == "foot")]  # the leg's front is the throat's
        along = foot.along(points)
        top = np.full(len(self.t), np.nan)
        # Less ease over the toes than over the instep: the toe box sits low on them.
        over = ease - (ease - TOE_EASE) * np.clip((self.t - 0.8) / 0.1, 0, 1)
        for k, tk in enumerate(self.t):
            band = np.abs(along - tk) < 0.02
            if band.any():
                top[k] = points[band, 2].max() + over[k]
        have = np.isfinite(top)
        top = np.interp(self.t, self.t[have], top[have])
        top[self.t > 1.0] = top[self.t <= 1.0][-1]
        a, b = VAMP
        ha = float(np.interp(a, self.t, top))
        toe = float(np.interp(b, self.t, top))  # over the toes' tips
        line = ha + (toe - ha) * (self.t - a) / (b - a)
        top = np.where(self.t >= a, np.maximum(line, np.where(self.t <= 1.0, top, -1)), top)
        # Past the toes the vamp's line runs on, curving down to a round nose (``_nose``).
        reach = float(foot.along(np.column_stack([self.outline, np.zeros(len(self.outline))
                                                  ])).max())  # fmt: skip
        front = self.wall(np.array([reach]))[0] + NOSE
        nose = _nose(self.t, b, reach, toe, (ha - toe) / (b - a), front)
        top = np.where(self.t > b, np.maximum(np.minimum(top, nose), front), top)
        self.over = over
        # Behind the throat the counter and quarters stand up to the topline, no top.
        self.top = np.maximum(top, 0.3 * np.clip((0.4 - self.t) / 0.1, 0, 1))
        self.half = np.array([_half_width(self.outline, yk) for yk in y])

    def bottom(self, t: np.ndarray) -> np.ndarray:
        """(N,) z of the last's bottom edge: EDGE above the ground, curling up at the toe."""
        return self.foot.ground + EDGE + SPRING * np.clip((t - 0.84) / 0.2, 0, 1) ** 2

    def wall(self, t: np.ndarray) -> np.ndarray:
        """(N,) z of the top of the last's upright wall: WALL over its bottom, lower round
        the toe (TOE_WALL x at its tip), where the front rolls over from low down."""
        lower = (1 - TOE_WALL) * np.clip((t - 0.9) / 0.15, 0, 1)
        return self.bottom(t) + WALL * (1 - lower)

    def inside(self, q: np.ndarray) -> np.ndarray:
        """(N,) bool: points (N, 3) inside the last."""
        t = self.foot.along(q)
        depth = _depth_in(self.outline, q[:, :2])  # m inside the outline in plan (< 0 out)
        bottom = self.bottom(t)
        wall = self.wall(t)
        height = np.interp(t, self.t, self.top) - wall
        radius = np.clip(np.minimum(ROLL * height, 0.9 * np.interp(t, self.t, self.half)),
                         0.004, None)  # fmt: skip
        floor = bottom - 0.01  # open below its bottom edge: the sole covers it
        u = np.clip(depth / radius, 0, 1)
        ceiling = wall + height * np.sqrt(np.clip(1 - (1 - u) ** 2, 0, 1))
        ceiling = np.where(depth >= radius, wall + height, ceiling)
        return (depth > 0) & (q[:, 2] > floor) & (q[:, 2] < np.maximum(ceiling, wall))

    def shape(self, points: np.ndarray) -> np.ndarray:
        """(N, 3) points moved along rays from inside the foot to the last's surface."""
        foot = self.foot
        t = np.clip(foot.along(points), 0.2, 0.85)
        y = foot.heel_y - t * (foot.heel_y - foot.toe_y)
        x = np.array([_middle(self.outline, yk) for yk in y])
        origin = np.column_stack([x, y, np.full(len(y), foot.ground + 0.02)])
        ray = points - origin
        ray /= np.maximum(np.linalg.norm(ray, axis=1, keepdims=True), 1e-9)
        steps = np.linspace(0.0, 0.2, 101)
        inside = np.stack([self.inside(origin + s * ray) for s in steps], 1)
        first_out = np.argmax(~inside, axis=1)  # the first sample outside
        lo, hi = steps[np.maximum(first_out - 1, 0)], steps[first_out]
        for _ in range(14):
            mid = (lo + hi) / 2
            ins = self.inside(origin + mid[:, None] * ray)
            lo, hi = np.where(ins, mid, lo), np.where(ins, hi, mid)
        shaped = origin + ((lo + hi) / 2)[:, None] * ray
        z = points[:, 2] - foot.ground
        weight = np.clip((SHAPED_TO[1] - z) / (SHAPED_TO[1] - SHAPED_TO[0]), 0, 1)[:, None]
        return points + weight * (shaped - points)


def _nose(t: np.ndarray, b: float, reach: float, toe: float, slope: float,
          front: float) -> np.ndarray:  # fmt: skip
    """(N,) z of the toe box's top at ``t`` past ``b`` (over the toes, at ``toe`` m and
    coming down ``slope`` m per unit of t): a cubic leaving the vamp's line smoothly and
    reaching ``front`` at the tip (``reach``) three times as steep."""
    span = reach - b
    u = np.clip((t - b) / span, 0, 1)
    m0, m1 = -slope * span, -3 * slope * span  # slopes per unit of u
    h00, h10 = 2 * u**3 - 3 * u**2 + 1, u**3 - 2 * u**2 + u
    h01, h11 = -2 * u**3 + 3 * u**2, u**3 - u**2
    return h00 * toe + h10 * m0 + h01 * front + h11 * m1


def _offset_outline(hull: np.ndarray, ease: float, foot: Foot, n: int = 96) -> np.ndarray:
    """(n, 2) the hull (K, 2) resampled evenly, out by ``ease``, its front drawn out."""
    closed = np.concatenate([hull, hull[:1]])
    length = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(closed, axis=0), axis=1))])
    s = np.linspace(0, length[-1], n, endpoint=False)
    ring = np.column_stack([np.interp(s, length, closed[:, 0]), np.interp(s, length, closed[:, 1])])
    centre = ring.mean(axis=0)
    for _ in range(3):  # round the hull's corners
        ring = 0.5 * ring + 0.25 * (np.roll(ring, 1, 0) + np.roll(ring, -1, 0))
    tangent = np.roll(ring, -1, 0) - np.roll(ring, 1, 0)
    normal = np.column_stack([tangent[:, 1], -tangent[:, 0]])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    normal *= np.sign(np.einsum("nd,nd->n", normal, ring - centre))[:, None]
    ring = ring + ease * normal
    t = foot.along(np.column_stack([ring, np.zeros(n)]))
    ring[:, 1] -= TOE_BOX * np.clip((t - 0.6) / 0.4, 0, 1) ** 2
    # An almond toe, not the toes' square front: the box narrowed towards its tip.
    front = t > 0.8
    middle = float(ring[front, 0].mean())
    ring[:, 0] = middle + (ring[:, 0] - middle) * (1 - TAPER * np.clip((t - 0.85) / 0.25, 0, 1))
    return ring


def _depth_in(outline: np.ndarray, q: np.ndarray) -> np.ndarray:
    """(N,) signed distance (m, > 0 inside) of plan points (N, 2) from a closed outline."""
    a, b = outline, np.roll(outline, -1, 0)
    ab = b - a
    rel = q[:, None] - a[None]
    s = np.clip(np.einsum("nkd,kd->nk", rel, ab) / np.einsum("kd,kd->k", ab, ab), 0, 1)
    d = np.linalg.norm(rel - s[..., None] * ab[None], axis=2).min(axis=1)
    crosses = (a[None, :, 1] > q[:, None, 1]) != (b[None, :, 1] > q[:, None, 1])
    x_at = a[None, :, 0] + (q[:, None, 1] - a[None, :, 1]) * ab[None, :, 0] / np.where(
        ab[None, :, 1] == 0, 1e-12, ab[None, :, 1])
    inside = (crosses & (q[:, None, 0] < x_at)).sum(axis=1) % 2 == 1
    return np.where(inside, d, -d)


def _crossing(outline: np.ndarray, y: float) -> np.ndarray:
    """x where the outline crosses the line at ``y``."""
    a, b = outline, np.roll(outline, -1, 0)
    hit = (a[:, 1] > y) != (b[:, 1] > y)
    return a[hit, 0] + (y - a[hit, 1]) * (b[hit, 0] - a[hit, 0]) / (b[hit, 1] - a[hit, 1])


def _half_width(outline: np.ndarray, y: float) -> float:
    x = _crossing(outline, y)
    return float(np.ptp(x) / 2) if len(x) >= 2 else 0.0


def _middle(outline: np.ndarray, y: float) -> float:
    x = _crossing(outline, y)
    return float(x.mean()) if len(x) else float(outline[:, 0].mean())


def _smoothed(faces: np.ndarray, points: np.ndarray, passes: int) -> np.ndarray:
    """(N, 3) points Laplacian-smoothed over the mesh: boundary vertices only along the
    boundary (its curve smoothed, not pulled in), the others over their neighbours."""
    from avatar.geometry.shell import boundary_edges

    a = faces.reshape(-1).astype(np.int64)
    b = np.roll(faces, -1, axis=1).reshape(-1).astype(np.int64)
    rim, _ = boundary_edges(faces)
    on_rim = np.zeros(len(points), bool)
    on_rim[rim.ravel()] = True
    n = len(points)
    key = np.minimum(a, b) * n + np.maximum(a, b)
    along = np.isin(key, np.minimum(rim[:, 0], rim[:, 1]).astype(np.int64) * n
                    + np.maximum(rim[:, 0], rim[:, 1]))  # fmt: skip
    p = points.copy()
    for _ in range(passes):
        total, count = np.zeros_like(p), np.zeros(n)
        for i, j in ((a, b), (b, a)):  # i takes j's position where it may
            use = ~on_rim[i] | along
            np.add.at(total, i[use], p[j[use]])
            np.add.at(count, i[use], 1)
        moved = total / np.maximum(count, 1)[:, None]
        p = np.where((count > 0)[:, None], 0.5 * p + 0.5 * moved, p)
    return p


def _subdivided(mesh: Mesh, refine: np.ndarray | None = None) -> Mesh:
    """Quads split in four (edge midpoints, face centre): room for the last's edges.
    ``refine`` (F,) bool: only these (None: all), grown until no other face has two split
    edges; a face with one split edge becomes a quad and a triangle (no T-junctions)."""
    v = mesh.vertices.astype(np.float64)
    f = mesh.faces
    edges = np.sort(np.stack([f, np.roll(f, -1, axis=1)], -1).reshape(-1, 2), axis=1)
    unique, inverse = np.unique(edges, axis=0, return_inverse=True)
    inverse = inverse.reshape(f.shape)
    refine = np.ones(len(f), bool) if refine is None else refine.copy()
    while True:
        split = np.zeros(len(unique), bool)
        split[inverse[refine].ravel()] = True
        grow = ~refine & (split[inverse].sum(axis=1) >= 2)
        if not grow.any():
            break
        refine |= grow
    edge_vertex = np.cumsum(split) - 1 + len(v)  # the new vertex of each split edge
    mids = v[unique[split]].mean(axis=1)
    fine = np.flatnonzero(refine)
    c0 = len(v) + len(mids)
    faces = []
    for k in range(4):  # corner k, the edge after it, the centre, the edge before it
        faces.append(np.stack([f[fine, k], edge_vertex[inverse[fine, k]],
                               c0 + np.arange(len(fine)),
                               edge_vertex[inverse[fine, (k - 1) % 4]]], 1))  # fmt: skip
    coarse = np.flatnonzero(~refine)
    cut_edge = split[inverse[coarse]]  # (C, 4) at most one per face
    faces.append(f[coarse[~cut_edge.any(axis=1)]])
    for k in range(4):  # corner k, its split edge's middle m, then the others: quad + triangle
        one = coarse[cut_edge[:, k]]
        if len(one):
            m = edge_vertex[inverse[one, k]]
            c = [f[one, (k + j) % 4] for j in range(4)]
            faces.append(np.stack([c[0], m, c[2], c[3]], 1))
            faces.append(np.stack([m, c[1], c[2], c[2]], 1))
    points = np.concatenate([v, mids, v[f[fine]].mean(axis=1)]).astype(np.float32)
    return Mesh(points, np.concatenate(faces).astype(np.int32))


# ---------------------------------------------------------------------------- look


def look(upper: str, upper_colour: str, sole: str, sole_colour: str, *,
         cap_colour: str | None = None, trim: tuple[str, str] | None = None,
         lace_colour=None, band: str | None = None):  # fmt: skip
    """A shoe's atlas material (``ROWS``) as a ``Spec.look``: the upper's fabric and
    colour, the sole's; ``cap_colour``: the toe cap's (the upper's if None); ``trim``:
    (fabric, colour) of eyelets, a sneaker's facings and heel tab (dark leather if None);
    laces ``builtin.lace_contrast`` to the upper unless ``lace_colour``; ``band``: the
    colour of a stripe moulded round a sneaker's midsole (with a groove under it).
    Stitching: double rows 2.5 and 5 mm in front of the toe cap's seam, a row on the
    welt's lip, and one low on the quarters above the sole."""

    def material(spec, size: int) -> Material:
        from avatar.clothes.builtin import lace_contrast

        laces = lace_contrast(upper_colour) if lace_colour is None else lace_colour
        trim_fabric, trim_colour = trim or ("calf", "sole black")
        stitches = [UPPER_STITCH_V, cap_stitch_v(2.5), cap_stitch_v(5.0)]
        if band is None:
            stitches.append(sole_v(0.95))
        # Rows that fall within 3 texels of one another at this size (the cap's double row
        # on a small texture) are drawn once: drawn twice the thread came out white.
        pixel = np.round((1 - np.asarray(stitches)) * size)
        stitches = [v for i, v in enumerate(stitches) if np.all(np.abs(pixel[:i] - pixel[i]) > 3)]
        m = fabrics.atlas(spec.name, [
            (*ROWS["upper"], upper, upper_colour),
            (*ROWS["vamp"], upper, upper_colour),
            (*ROWS["trim"], trim_fabric, trim_colour),
            (*ROWS["cap"], upper, cap_colour or upper_colour),
            (*ROWS["sole"], sole, sole_colour),
            (*ROWS["laces"], "cord", laces),
        ], size, stitches=tuple(stitches))  # fmt: skip
        if band is not None:
            _moulded_band(m, fabrics.rgb(band), size)
        for row in ("upper", "vamp", "cap"):
            if upper in LEATHERS:
                _grained(m, ROWS[row], size, GRAIN_STRETCH[row])
            else:
                _knit_mesh(m, ROWS[row], size, KNIT_STRETCH.get(row, 1.0))
        _creased(m, size, 1.0 if upper in LEATHERS else 0.6)
        return m

    return material


# A stitch low on the upper (quarters and vamp) just above the sole: the upper's v runs
# with height over its own range, 0.05-0.95 of the row.
UPPER_STITCH_V = ROWS["upper"][0] + (ROWS["upper"][1] - ROWS["upper"][0]) * (0.05 + 0.9 * 0.1)
MIDSOLE_STRIPE = (0.62, 0.78)  # the band's span up the midsole's wall (``sole_v`` places)
MIDSOLE_GROOVE = 0.45


LEATHERS = ("calf", "leather", "suede")
GRAIN = 0.5  # the pebble's slope in the normal map (tangent units per texel of height)


def _rows(span: tuple[float, float], size: int) -> slice:
    return slice(int(round((1 - span[1]) * size)), int(round((1 - span[0]) * size)))


def _smooth_noise(rng: np.random.Generator, shape: tuple[int, int], cell: int,
                  stretch: float = 1.0) -> np.ndarray:  # fmt: skip
    """(H, W) noise in [-1, 1]: random values every ``cell`` texels across (``stretch`` x
    ``cell`` down the rows), smoothly interpolated."""
    h, w = shape
    down = cell * stretch
    coarse = rng.uniform(-1, 1, (int(h // down) + 2, w // cell + 2))
    y, x = np.arange(h) / down, np.arange(w) / cell
    y0, x0 = y.astype(int), x.astype(int)
    fy, fx = y - y0, x - x0
    fy, fx = fy * fy * (3 - 2 * fy), fx * fx * (3 - 2 * fx)
    a, b = coarse[y0][:, x0], coarse[y0][:, x0 + 1]
    c, d = coarse[y0 + 1][:, x0], coarse[y0 + 1][:, x0 + 1]
    top = a + (b - a) * fx[None]
    return top + (c + (d - c) * fx[None] - top) * fy[:, None]


def _bumped(normal: np.ndarray, height: np.ndarray, slope: float,
            aspect: float = 1.0) -> np.ndarray:  # fmt: skip
    """(H, W, 3) uint8 tangent-space normals tilted by the gradient of ``height`` (H, W);
    ``aspect``: a texel's width over its height on the garment (its slope down the rows is
    per that much less surface)."""
    n = normal.astype(np.float32) / 127.5 - 1
    gy, gx = np.gradient(height)
    n[..., 0] -= slope * gx
    n[..., 1] += slope * aspect * gy  # image rows run down the texture, v up
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    return np.clip((n + 1) * 127.5, 0, 255).astype(np.uint8)


# How much taller than wide a grain cell is in each row's texels, so that it is round on
# the shoe: the upper's u runs round the foot (~0.6 mm a texel at 1024) and its v up it
# (~0.33 mm), the toe cap's v away from its seam (~0.57 mm) and its u along it (~0.28 mm),
# the vamp's v along the foot (~0.8 mm) and its u round it (~0.13 mm). Square in texels,
# the pebble was streaked round the quarters and along the cap.
GRAIN_STRETCH = {"upper": 1.8, "vamp": 0.16, "cap": 0.5}
KNIT_STRETCH = {"vamp": 0.16, "cap": 0.5}  # a sneaker's mesh cells, the same way


def _grained(m: Material, span: tuple[float, float], size: int, stretch: float = 1.0) -> None:
    """Leather grain in one atlas row, in place: a fine pebble in the normal map (cells of
    ~1/300 of the texture), rougher in its valleys, and the gloss varying in soft patches
    (the leather was a plain, uniform gloss)."""
    normal, rough = m.normal_texture, m.roughness_texture
    assert normal is not None and rough is not None
    rows = _rows(span, size)
    rng = np.random.default_rng(8)
    shape = (normal[rows].shape[0], normal[rows].shape[1])
    cell = max(2, size // 420)
    if stretch < 1:  # cells narrower down the rows than across: wider across instead
        cell = int(round(cell / stretch))
    pebble = np.abs(_smooth_noise(rng, shape, cell, stretch)) + 0.5 * np.abs(
        _smooth_noise(rng, shape, 2 * cell, stretch))
    height = -pebble  # pores and pebble valleys between raised grains
    # The vamp's texels are 6 times longer along the foot than round it: per texel, its
    # grain's slopes along the foot were 6 times too steep (streaks across the vamp).
    normal[rows] = _bumped(normal[rows], height, GRAIN, min(1.0, stretch) if span == ROWS["vamp"]
                           else 1.0)  # fmt: skip
    patches = _smooth_noise(rng, shape, max(8, size // 24))
    r = rough[rows].astype(np.float32) + 255 * (0.1 + 0.07 * patches + 0.08 * pebble)
    rough[rows] = np.clip(r, 0, 255).astype(np.uint8)


def _knit_mesh(m: Material, span: tuple[float, float], size: int, stretch: float = 1.0) -> None:
    """A sneaker's textile upper in one atlas row, in place: an engineered mesh, open
    cells in a diamond lattice, each a shade darker and sunk in the normal map; ``stretch``:
    how much taller than wide a cell is in texels (square on the shoe)."""
    image, normal, rough = m.base_color_texture, m.normal_texture, m.roughness_texture
    assert image is not None and normal is not None and rough is not None
    rows = _rows(span, size)
    h, w = image[rows].shape[:2]
    pitch = max(4, size // 170)
    y, x = np.mgrid[0:h, 0:w].astype(np.float32)
    if stretch < 1:  # cells shorter down the rows than across: as wide as they are tall
        pitch, x = max(2, int(round(pitch * stretch))), x * stretch
    a = (x + y) * np.pi / pitch
    b = (x - y) * np.pi / pitch
    cells = np.clip(np.sin(a) * np.sin(b), 0, None) ** 0.5  # 1 in a cell's middle, 0 on ribs
    image[rows] = (image[rows].astype(np.float32) * (1 - 0.22 * cells[..., None])).astype(np.uint8)
    normal[rows] = _bumped(normal[rows], -cells, 0.6)
    rough[rows] = np.clip(rough[rows].astype(np.float32) + 30 * cells, 0, 255).astype(np.uint8)


# Flex creases across the vamp: at these fractions of the foot's length (the ball's
# joints, the big toe's further forward: CREASE_TILT over the vamp's width), each an arc
# across the instep whose ends bend back towards the heel (CREASE_BEND) down the sides,
# a narrow valley wavering along it, some shallower or broken, fading out low on the
# sides, with a soft ridge before it.
CREASES = (0.67, 0.7, 0.73, 0.755)
CREASE_TILT = 0.03
CREASE_BEND = 0.05
CREASE_SLOPE = 2.0  # the normal map's tilt per unit of the crease's depth per texel
# A valley's half-width, texels at 1024 (~0.8 mm along the foot each): at 1.3 the creases
# were a millimetre wide, their walls tilting up to 39 degrees; a full-body picture's pixel
# (~3 mm of shoe) averaged each valley's two walls away (4 degrees RMS left: no creases).
# At 3, steeper per unit depth: 32 degrees at most up close, 7 RMS over 3 mm.
CREASE_WIDTH = 3.0


def _creased(m: Material, size: int, strength: float = 1.0) -> None:
    """Flex creases in the vamp row's normal map (and a shade darker in their valleys),
    in place (``CREASES``; u in the row runs round the foot, v along it: ``_vamp_uvs``)."""
    image, normal = m.base_color_texture, m.normal_texture
    assert image is not None and normal is not None
    rows = _rows(ROWS["vamp"], size)
    h, w = normal[rows].shape[:2]
    y = np.arange(h, dtype=np.float64)[:, None]  # texel rows down the vamp row
    u = np.clip((np.arange(w) / w - 0.02) / 0.96, 0, 1)  # 0 low inside, 1 low outside
    side = np.abs(2 * u - 1)  # 0 over the instep, 1 low on either side
    across = np.clip(1.25 - 1.25 * side, 0, 1) ** 1.5  # fades out down the sides
    rng = np.random.default_rng(14)
    height = np.zeros((h, w))
    for t in CREASES:
        line = t + CREASE_TILT * (0.5 - u) - CREASE_BEND * side**2
        waver = 1.2 * _smooth_noise(rng, (1, w), max(8, w // 10))[0]  # texels at 1024
        centre = (1 - np.array([vamp_v(x) for x in line])) * size - rows.start
        d = (y - centre[None]) * 1024 / size - waver[None]  # texels at 1024 off the line
        depth = np.clip(0.35 + 0.9 * _smooth_noise(rng, (1, w), max(8, w // 5))[0], 0, 1)
        d = d / CREASE_WIDTH  # valley half-widths off the line
        valley = np.exp(-(d**2)) - 0.3 * np.exp(-(((d + 1.7) / 1.4) ** 2))
        height -= depth * across * valley
    normal[rows] = _bumped(normal[rows], height * strength * size / 1024, CREASE_SLOPE)
    shade = 1 - 0.08 * strength * np.clip(-height, 0, 1)
    image[rows] = (image[rows].astype(np.float32) * shade[..., None]).astype(np.uint8)


def _moulded_band(m: Material, colour: np.ndarray, size: int) -> None:
    """A stripe of ``colour`` round a midsole's wall, with a moulded groove below it: rows
    of the sole's atlas row, in place."""
    def row(place: float) -> int:
        return int(round((1 - sole_v(place)) * size))

    image, normal = m.base_color_texture, m.normal_texture
    assert image is not None and normal is not None
    top, bottom = row(MIDSOLE_STRIPE[1]), row(MIDSOLE_STRIPE[0])
    image[top:bottom] = fabrics.srgb(
        np.broadcast_to(colour, (bottom - top, size, 3)).astype(np.float32))
    groove = row(MIDSOLE_GROOVE)
    image[groove - 1:groove + 2] = (image[groove - 1:groove + 2].astype(np.float32)
                                    * 0.7).astype(np.uint8)  # fmt: skip
    normal[groove - 2:groove] = (128, 90, 235)  # the groove's walls face up and down
    normal[groove + 1:groove + 3] = (128, 166, 235)


# ---------------------------------------------------------------------------- helpers


def _lowest_loop(mesh: Mesh) -> np.ndarray:
    """Vertex indices, in order, of the open boundary loop with the lowest mean height."""
    from avatar.geometry.shell import boundary_edges

    edges, _ = boundary_edges(mesh.faces)
    following = dict(zip(edges[:, 0].tolist(), edges[:, 1].tolist(), strict=True))
    loops, seen = [], set()
    for start in following:
        if start in seen:
            continue
        loop = [start]
        seen.add(start)
        while following.get(loop[-1], start) != start and following[loop[-1]] not in seen:
            loop.append(following[loop[-1]])
            seen.add(loop[-1])
        loops.append(np.array(loop))
    return min(loops, key=lambda lp: float(mesh.vertices[lp, 2].mean()))


def _strip(a: np.ndarray, b: np.ndarray) -> Mesh:
    """A quad strip between two (N, 3) polylines."""
    n = len(a)
    faces = [[i, i + 1, n + i + 1, n + i] for i in range(n - 1)]
    return Mesh(np.concatenate([a, b]).astype(np.float32), np.array(faces, np.int32))


def _merge(meshes: list[Mesh]) -> Mesh:
    offset = np.cumsum([0, *(len(m.vertices) for m in meshes)])
    faces = np.concatenate([m.faces + o for m, o in zip(meshes, offset, strict=False)])
    return Mesh(np.concatenate([m.vertices for m in meshes]), faces.astype(np.int32))


def _facing_out(mesh: Mesh, inside: np.ndarray) -> Mesh:
    """Flip faces whose normal points towards ``inside`` (a point within the solid)."""
    v = mesh.vertices[mesh.faces].astype(np.float64)
    n = np.cross(v[:, 2] - v[:, 0], v[:, 3] - v[:, 1])
    n[np.linalg.norm(n, axis=1) < 1e-12] = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])[
        np.linalg.norm(n, axis=1) < 1e-12
    ]
    inward = np.einsum("fd,fd->f", n, v.mean(axis=1) - inside) < 0
    faces = mesh.faces.copy()
    faces[inward] = faces[inward][:, ::-1]
    return Mesh(mesh.vertices, faces)


def _planar_uvs(mesh: Mesh, row: str, band: tuple[float, float] = (0.05, 0.95)) -> Mesh:
    """Per-corner UVs inside the atlas row: the piece seen from its side (y, z) for the
    upper, toe cap and sole, from above (x, y) for laces, scaled to fit the row's ``band``
    (fractions of its height)."""
    v0, v1 = ROWS[row]
    p = mesh.vertices[mesh.faces].astype(np.float64)  # (F, C, 3)
    if row == "laces":
        u, w = p[..., 0], p[..., 1]
    else:
        # Around the foot: the angle about its vertical axis, so sides and toes all unwrap.
        centre = mesh.vertices.mean(axis=0)
        u = np.arctan2(p[..., 1] - centre[1], p[..., 0] - centre[0]) / (2 * np.pi) + 0.5
        w = p[..., 2]
        wrapped = u.max(axis=1, keepdims=True) - u > 0.5
        u = np.where(wrapped, u + 1.0, u) * 0.5  # [0, 1): faces across the seam stay whole
    u = (u - u.min()) / max(float(np.ptp(u)), 1e-9)
    w = (w - w.min()) / max(float(np.ptp(w)), 1e-9)
    w = band[0] + (band[1] - band[0]) * w
    uvs = np.stack([0.02 + 0.96 * u, v0 + (v1 - v0) * w], -1).reshape(-1, 2)
    face_uvs = np.arange(mesh.faces.size, dtype=np.int32).reshape(mesh.faces.shape)
    return Mesh(mesh.vertices, mesh.faces, uvs.astype(np.float32), face_uvs)

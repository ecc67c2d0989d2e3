"""The built-in wardrobe: garments cut from the body's own helper geometry.

Each entry is a short recipe (which faces, how much ease, fabric, colour, thickness,
layer); ``build(name, body)`` turns it into a Garment bound to the base mesh, so it follows
every body from babies to old people. Nothing is downloaded: the geometry comes from the
MakeHuman base mesh Avatar already needs, the textures from ``fabrics``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from avatar.clothes import face, hair, headwear, hems, jacket, shoes, tailoring
from avatar.clothes.authoring import (
    AuthoringBody,
    Piece,
    banded,
    bound,
    covered_skin,
    cut,
    join,
    level_hems,
    on_their_side,
    orient_outward,
    seat_crowns,
    seat_share,
    with_box_uvs,
)
from avatar.clothes.fitting import CLEARANCE, Garment
from avatar.clothes.limb_ease import across_the_limbs
from avatar.clothes.regions import face_features
from avatar.looks import fabrics, facial_hair, tailored, textures
from avatar.material import Material
from avatar.mesh import Mesh

RELAX = 12  # smoothing passes over cut edges (hems, armholes, necklines)


@dataclass(frozen=True)
class Spec:
    """A built-in garment's recipe."""

    name: str
    category: str  # tops, bottoms, dresses, swimwear, legwear, footwear, headwear, hair, face
    make: Callable[[AuthoringBody], Piece]
    fabric: str
    colour: str
    thickness: float
    z_depth: int
    tags: tuple[str, ...] = ()
    collide: bool = True
    # (spec, texture size) -> Material, for garments of several materials in one atlas.
    look: Callable[[Spec, int], Material] | None = None
    # m a garment keeps off the skin (None: fitting's CLEARANCE). Loose cloth on a coarse
    # mesh (a skirt) needs more: a thigh curves more than 2 mm between two of its vertices.
    clearance: float | None = None
    # A skirt: its skin weights ramp from the hips to the hem below the hip joints
    # (``Garment.swing_below``), so its hem bends as one curve mid-stride.
    swing: bool = False
    # A loose top: its cloth below the waist hangs from the torso as one piece, its skin
    # weights held at the waist and carried down to the hem (``Garment.swing_below`` at the
    # waist). Bound to the skin under it, a cardigan's hem took 80% of its weight from the
    # thighs: mid-stride its two halves swung with the legs (the back hem 5 cm higher on
    # one side than the other, a torn-looking diagonal), and it zig-zagged where those
    # weights gave way to the spine's (its front corners) or where the frames' cut to four
    # bones kept one thigh of a hoodie's back midline vertex but not the other (a notch).
    hang: bool = False
    # Loose trousers spanning the front of the crotch (``across_the_fly``): the bridge's
    # skin weights shared between its left and right halves (``Garment.fly_share``).
    fly: bool = False


def _tights(body: AuthoringBody, keep_fn, ease, band: float = 0.0, snug: float | None = None,
            bridge: bool = False, fly: bool = False,
            open_front: bool = False) -> Piece:  # fmt: skip
    """A garment cut from ``helper-tights``; ``band`` > 0: a rib/hem band that wide (m)
    along every open edge (``authoring.banded``); ``snug``: m off the skin a stretch
    garment is laid at (``tailoring.hug_skin``) instead of ``ease`` off the shell;
    ``bridge``: loose cloth spanning the body's hollows (``bridged``); ``fly``: loose
    trousers spanning the front of the crotch (``across_the_fly``); ``open_front``: cut
    ``opened``, its hem levelled up to the opening's corners (``level_hems``)."""
    faces = body.group_faces("helper-tights")
    ff = face_features(body.vertices, faces, body.part, body.marks)
    mesh = cut(body, faces, keep_fn(ff, body.marks), ease, relax=RELAX, sided=bridge)
    mesh = level_hems(mesh, open_front=open_front)
    if fly:
        mesh = across_the_fly(body, mesh)
    if bridge:
        mesh = spread_across(body, spanned(body, bridged(body, mesh)))
        if open_front:  # lifted along the skin's normals, the hem dipped 2.5 mm in the cleft
            mesh = level_hems(mesh, open_front=True)
    if snug is not None:
        points = tailoring.hug_skin(body, mesh.vertices.astype(np.float64), snug)
        mesh = Mesh(points.astype(np.float32), mesh.faces, mesh.uvs, mesh.face_uvs)
    if band:  # the band's inner edge (a staircase of whole faces) levelled as the hem is
        mesh = level_hems(banded(mesh, band), reach=0.012, open_front=open_front)
    # A snug garment follows the skin itself on every body (the shell stands off the skin
    # by different amounts on different bodies: bound to it, the seat sagged again).
    if snug is not None:
        return bound(body, mesh, body.skin_faces)
    midline = MIDLINE_SPAN / 2 if bridge else 0.0
    return round_the_limbs(body, bound(body, mesh, faces, midline=midline))


def round_the_limbs(body: AuthoringBody, piece: Piece) -> Piece:
    """``piece`` with its ease round the arms and legs scaling with each limb's girth
    (``limb_ease.across_the_limbs``), not the body's size: a child's thin limbs."""
    return replace(piece, binding=across_the_limbs(body, piece.mesh.vertices, piece.binding))


def bridged(body: AuthoringBody, mesh: Mesh, passes: int = 12) -> Mesh:
    """Loose cloth over the body's hollows: smoothing passes that only ever move a vertex
    outwards (along the skin's normal; a hem too, where it crosses a hollow). Cut from
    the tights shell a long cardigan followed the cleft of the buttocks down into a 9 mm
    pocket that rendered as a black hole on the lower back."""
    v = mesh.vertices.astype(np.float64)
    a = mesh.faces.reshape(-1)
    b = np.roll(mesh.faces, -1, axis=1).reshape(-1)
    degree = np.maximum(np.bincount(a, minlength=len(v)) + np.bincount(b, minlength=len(v)), 1)
    normal = body.outward(v)
    start = v.copy()
    left, right = _side_neighbours(v, np.concatenate([a, b]), np.concatenate([b, a]))
    midline = np.abs(v[:, 0]) < MIDLINE_SPAN
    for _ in range(passes):
        total = np.zeros_like(v)
        np.add.at(total, a, v[b])
        np.add.at(total, b, v[a])
        rise = np.einsum("nd,nd->n", total / degree[:, None] - v, normal)
        # A cleft runs down the midline while the buttocks bulge across it: the mean of all
        # four neighbours sat level with a 1 cm deep groove (those above and below it lie in
        # the cleft too), so near the midline the cloth also spans from side to side.
        across = np.einsum("nd,nd->n", (v[left] + v[right]) / 2 - v, normal)
        rise = np.where(midline, np.maximum(rise, across), rise)
        lifted = v + np.clip(rise, 0, None)[:, None] * normal
        v = start + on_their_side(start, lifted - start, keep_length=False)
    return Mesh(v.astype(np.float32), mesh.faces, mesh.uvs, mesh.face_uvs)


def spanned(body: AuthoringBody, mesh: Mesh) -> Mesh:
    """Loose cloth spanning the seat: on the back below the hip line, every vertex between
    the crowns of the buttocks brought out to the crowns' depth at its height (the cloth's
    own rearmost vertices there, ``seat_crowns``), fading out above (``seat_share``).
    ``bridged`` only fills a groove as deep as its neighbours: the cardigan's back hem
    still dipped 27 mm forward at the midline against 6 cm to the side."""
    v = mesh.vertices.astype(np.float64)
    share = seat_share(body, v)
    crown = seat_crowns(v, v, body.marks.hip[0])
    between = (share > 0) & (crown >= 0) & (np.abs(v[:, 0]) < v[np.maximum(crown, 0), 0])
    lift = np.where(between, np.clip(v[np.maximum(crown, 0), 1] - v[:, 1], 0, None), 0.0)
    v[:, 1] += share * lift
    return Mesh(v.astype(np.float32), mesh.faces, mesh.uvs, mesh.face_uvs)


# Loose trousers across the front of the crotch: from the crotch point up, the cloth over
# the groin is laid FLY_SHARE of the way out to the thighs' fronts (reached FLY_RISE m above
# the crotch point, from nothing there: the crotch seam still runs back between the legs).
FLY_RISE, FLY_SHARE = 0.06, 0.85
FLY_SEAM = 0.03  # m below the crotch point the bridge's shared skin weights start (``fly_share``)


def across_the_fly(body: AuthoringBody, mesh: Mesh) -> Mesh:
    """Loose trousers spanning the front of the crotch from thigh to thigh: each vertex
    on the front between the hip joints brought towards the depth of the cloth's
    front-most vertex about its height (the thighs' crowns), never back. Cut from the
    tights shell, sweatpants, trousers, shorts and jeans followed the groin: seen from the
    front, 5-8 cm above the crotch point their cloth at the midline stood 44-75 mm behind
    the cloth over the thighs, a deep V (a camel toe) on women and children. Vertices whose
    cloth faces back (the crotch's gusset between the legs, the far wall of the seam's
    curve) stay: laid flat with the rest, the small faces round the front crotch seam
    folded over (2-8 turned back, specks on the fly). Moving forward over the groin only
    takes the cloth further off the skin."""
    v = mesh.vertices.astype(np.float64)
    hip = body.marks.hip
    reach = abs(float(hip[0, 0]))  # the thighs' crowns lie within a hip joint's x of the midline
    crotch = float(v[np.abs(v[:, 0]) < 0.015, 2].min())
    front = (v[:, 1] < hip[0, 1]) & (np.abs(v[:, 0]) < reach)
    pick = np.flatnonzero(front & (v[:, 2] > crotch) & (v[:, 2] < hip[0, 2]))
    if len(pick) == 0:
        return mesh
    crowns = np.flatnonzero(front)
    row = np.abs(v[pick, None, 2] - v[None, crowns, 2]) < 0.03  # (P, C) about level
    depth = np.where(row, v[None, crowns, 1], np.inf).min(axis=1)  # front-most y per row
    t = np.clip((v[pick, 2] - crotch) / FLY_RISE, 0, 1)
    facing = np.clip((0.2 - _vertex_normals(v, mesh.faces)[pick, 1]) / 0.4, 0, 1)
    share = FLY_SHARE * t * t * (3 - 2 * t) * facing
    v[pick, 1] -= share * np.clip(v[pick, 1] - depth, 0, None)
    return Mesh(v.astype(np.float32), mesh.faces, mesh.uvs, mesh.face_uvs)


def fly_share(body: AuthoringBody, mesh: Mesh) -> np.ndarray:
    """(N,) in [0, 1]: how far each vertex's skin weights are blended towards the mean of
    its own and its mirror twin's (``weights.shared_across``): 1 over the middle of the
    fly (``across_the_fly``'s cloth between the thighs, from FLY_RISE - FLY_SEAM above the
    crotch point up to the hip joints), falling to 0 at the thighs' crowns and FLY_SEAM
    below the crotch point (the crotch seam's front shares too: from the crotch point up
    only, the bridge's bottom row still creased over the trailing thigh). Laid across from
    thigh to thigh, the bridge kept the weights of the groin under it, left thigh on its
    left half and right on its right, a few cm off the skin: mid-stride the legs swung its
    halves apart and together and the heavy man's shorts crumpled into a pinch at the top
    of the crotch."""
    v = mesh.vertices.astype(np.float64)
    hip = body.marks.hip
    reach = abs(float(hip[0, 0]))
    crotch = float(v[np.abs(v[:, 0]) < 0.015, 2].min())
    front = (v[:, 1] < hip[0, 1]) & (v[:, 2] < hip[0, 2])
    t = np.clip((v[:, 2] - crotch + FLY_SEAM) / FLY_RISE, 0, 1)
    across = np.clip(1 - np.abs(v[:, 0]) / reach, 0, 1)
    return np.where(front, t * t * (3 - 2 * t) * across, 0.0)


def _vertex_normals(v: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(N, 3) unit normals of a quad mesh's vertices, turned to face out of the body (most
    of a garment's faces face away from its centre)."""
    normal = np.cross(v[faces[:, 2]] - v[faces[:, 0]], v[faces[:, 3]] - v[faces[:, 1]])
    if np.einsum("nd,nd->", normal, v[faces].mean(axis=1) - v.mean(axis=0)) < 0:
        normal = -normal
    out = np.zeros_like(v)
    for k in range(faces.shape[1]):
        np.add.at(out, faces[:, k], normal)
    return out / np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-12)


def spread_across(body: AuthoringBody, mesh: Mesh, passes: int = 8) -> Mesh:
    """Loose cloth over the back's midline with its vertices spaced evenly from side to
    side (each moved sideways to the middle of its left and right neighbours, a few
    passes). Cut from the tights shell, the cleft's two walls and its floor came out of
    ``bridged`` and ``spanned`` 1.5-1.8 mm apart across the cardigan's back above its hem
    (5 cm apart down the back): the cloth's outer layer, grown along the skin's normals,
    which face each other across the cleft, crossed its neighbours there, a dark pinch at
    the hem's midline."""
    v = mesh.vertices.astype(np.float64)
    a = mesh.faces.reshape(-1)
    b = np.roll(mesh.faces, -1, axis=1).reshape(-1)
    left, right = _side_neighbours(v, np.concatenate([a, b]), np.concatenate([b, a]))
    near = np.flatnonzero((np.abs(v[:, 0]) < MIDLINE_SPAN / 2) & (v[:, 1] > body.marks.hip[0, 1])
                          & (left != np.arange(len(v))) & (right != np.arange(len(v))))  # fmt: skip
    for _ in range(passes):
        v[near, 0] = (v[left[near], 0] + v[right[near], 0]) / 2
    return Mesh(v.astype(np.float32), mesh.faces, mesh.uvs, mesh.face_uvs)


# The buzz cut: many narrow short cards lying flat over its base cap (1.5 mm off the
# skin), rooted 0.7 mm above it. Rooted on the skin, 1400 cards 8 mm wide came up through
# the cap and stood 3 mm off it: from the side the grey buzz read as flat lumpy scales.
# One segment a card (a 9 mm card bends 0.5 mm over the skull): 10,000 vertices in all.
BUZZ_CARDS = 2400
BUZZ_WIDTH = 0.0045  # m
BUZZ_ROOT = 0.0022  # m above the skin
BUZZ_HAIRLINE_M = 0.012  # the buzz cut's stubble thins out over this much above the hairline
# Long hair's volume over the temples and ears (``hair.side_volume``): lying on the skull
# there, it looked painted on from the side.
LONG_SIDE_LIFT_M = 0.008

MIDLINE_SPAN = 0.04  # m either side of the midplane where loose cloth spans a cleft


def _side_neighbours(v: np.ndarray, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(N,) index of each vertex's neighbour furthest to its left (-x) and to its right
    (+x) along the edges a -> b (each edge both ways); a vertex itself where it has none."""
    count = len(v)
    dx = v[b, 0] - v[a, 0]
    left, right = np.arange(count), np.arange(count)
    for side, pick in ((left, -dx), (right, dx)):
        best = np.zeros(count)
        np.maximum.at(best, a, pick)
        chosen = (pick > 0) & (pick == best[a])
        side[a[chosen]] = b[chosen]
    return left, right


def _skirt(body: AuthoringBody, bottom_z: float, ease, tailor: bool = False,
          hug: float | None = None, under: np.ndarray | None = None,
          gap: float = 0.004, edge_gap: float = 0.0025) -> Piece:  # fmt: skip
    """A skirt from ``helper-skirt`` down to ``bottom_z``, swinging as one (``blend_sides``);
    ``tailor``: its own panel texture with side seams, a waistband (geometry too), a
    centre-back zip and a stitched hem band. ``hug``: m off the skin the skirt keeps down
    to the hip joints, flaring only below them (``tailoring.sit_on_hips``), outside the
    points ``under`` (M, 3) of what it is worn over (``gap`` m out, ``edge_gap`` at its
    top edge)."""
    faces = body.group_faces("helper-skirt")
    centre_z = body.vertices[faces].mean(axis=1)[:, 2]
    mesh = cut(body, faces, centre_z > bottom_z, ease, RELAX, loose=True)
    if hug is not None:
        points = tailoring.sit_on_hips(body, mesh.vertices, hug, float(body.marks.hip[:, 2].mean()),
                                       under=under, gap=gap, edge_gap=edge_gap)  # fmt: skip
        mesh = Mesh(points.astype(np.float32), mesh.faces, mesh.uvs, mesh.face_uvs)
    # Below the hips the helper's D-shaped section rounded off (a crease down each side).
    mesh = hems.rounded_rows(mesh, float(body.marks.hip[:, 2].mean()))
    if not tailor:
        return tailoring.blend_sides(body, bound(body, mesh, faces), "helper-skirt")
    panels = tailoring.Panels(mesh, tailoring.SKIRT_PANELS, tailoring.body_axis(body.marks))
    h = tailoring.heights(mesh, body.marks, 0.035)
    top = h.top
    mesh = banded(panels.textured(), lambda p: np.where(p[:, 2] > top - 0.05, 0.035, 0.02),
                  0.0015)  # fmt: skip
    layout = tailoring.layout(panels, tailoring.skirt_marks(panels, h), "red")
    piece = replace(bound(body, mesh, faces), layout=layout)
    return tailoring.blend_sides(body, piece, "helper-skirt")


# m the waistband's top reaches above the hip joints on the authoring body (a mid rise,
# over the iliac crest). At 7 cm jeans rode low on women (whose waist is higher over the
# hip joints): the top of the seat and the small of the back showed.
RISE = 0.095


def _tailored(body: AuthoringBody, kind: str, length: float, ease, hang: float,
              thread: str, taper: float = 0.9) -> Piece:  # fmt: skip
    """Jeans or trousers: cut from ``helper-tights`` to ``length`` along the leg, falling
    straight from the knee (``hang`` x the knee's radius, narrowing to ``taper`` x that at
    the ankle: ``tailoring.straight_legs``), unrolled into four panels
    painted with ``kind``'s construction (``tailoring``), a raised waistband and hem bands,
    and belt loops."""
    faces = body.group_faces("helper-tights")
    ff = face_features(body.vertices, faces, body.part, body.marks)
    mesh = cut(body, faces, bottom(length, RISE)(ff, body.marks), ease, relax=RELAX)
    mesh = level_hems(Mesh(tailoring.straight_legs(body, mesh.vertices.astype(np.float64), hang,
                                                   taper=taper).astype(np.float32), mesh.faces))
    mesh = across_the_fly(body, mesh)
    panels = tailoring.Panels(mesh, tailoring.TROUSER_PANELS, tailoring.leg_axis(body.marks))
    band = 0.04 if kind == "jeans" else 0.035
    h = tailoring.heights(mesh, body.marks, band)
    top = h.top
    mesh = banded(panels.textured(), lambda p: np.where(p[:, 2] > top - 0.05, band, 0.02),
                  0.002)  # fmt: skip
    mesh = level_hems(mesh, reach=0.012)  # the bands' inner edges, as the hems
    marks = (tailoring.jeans_marks if kind == "jeans" else tailoring.trouser_marks)(panels, h)
    piece = join([round_the_limbs(body, bound(body, mesh, faces)),
                  tailoring.belt_loops(body, mesh, h, faces)])
    metal = None if kind == "jeans" else tailoring.HORN
    return replace(piece, layout=tailoring.layout(panels, marks, thread, metal))


def _z(ff):
    return ff.centre[:, 2]


def top(sleeve: float, neck: float = 0.0, hem: float = 0.04):
    """Torso above the hip line (+hem), sleeves to ``sleeve`` along the arm."""

    def keep(ff, m):
        # Upper-thigh faces too, so a long top's hem runs level instead of following the groin.
        trunk = (ff.part == "torso") | (ff.part == "leg")
        torso = trunk & (_z(ff) > m.hip[0, 2] + hem) & (_z(ff) < m.neck[2] - neck)
        return torso | ((ff.part == "arm") & (ff.arm < sleeve))

    return keep


def opened(keep_fn, gap: float = 0.012):
    """A front opening: ``keep_fn``'s faces less a strip ``gap`` m either side of the
    body's midline on the front (a jacket or cardigan worn open)."""

    def keep(ff, m):
        front = ff.centre[:, 1] < m.neck[1] + 0.01  # the neck's front too: open to the collar
        return keep_fn(ff, m) & ~(front & (np.abs(ff.centre[:, 0]) < gap))

    return keep


def bottom(length: float, rise: float = 0.07):
    """Pelvis up to ``rise`` above the hip joints, legs to ``length`` along the leg."""

    def keep(ff, m):
        pelvis = (ff.part == "torso") & (_z(ff) < m.hip[0, 2] + rise)
        return pelvis | ((ff.part == "leg") & (ff.leg < length))

    return keep


def strapped(hem: float, armhole: float = 0.062, front: float = 0.12, back: float = 0.05):
    """Torso on straps down to ``hem`` m above the hip joints: a neckline scooped ``front``
    and ``back`` m below the neck joint, oval armholes ``armhole`` m in from the shoulder
    joint reaching a hand's width below it (shoulder faces count as arm)."""

    def keep(ff, m):
        x, y, z = ff.centre.T
        across, shoulder_x = np.abs(x), abs(m.shoulder[0, 0])
        hole = ((across - shoulder_x) / armhole) ** 2 + ((z - m.shoulder[0, 2] - 0.05) / 0.15) ** 2
        depth = np.where(y < m.neck[1], front, back)
        neckline = m.neck[2] - depth * np.sqrt(np.clip(1 - (across / 0.07) ** 2, 0, 1))
        upper = (ff.part == "torso") | ((ff.part == "arm") & (across < shoulder_x - 0.03))
        body = upper & (z > m.hip[0, 2] + hem) & (hole > 1) & (across < shoulder_x)
        body &= z < m.neck[2] - STRAP_TOP
        return body & ~((across < 0.07) & (z > neckline))

    return keep


# m below the neck joint at which straps end across the top of the shoulder: the faces just
# outside the neckline climbing the side of the neck (centres up to 4 mm above the joint)
# stood up from each strap's inner corner as a 1-2 cm tab.
STRAP_TOP = 0.008


# Stretch garments (lycra) lie SNUG m off the skin, as SNUG_THICKNESS m of cloth: closer,
# or thinner, and mid-stride the skin bulged through between their vertices (specks of
# skin on the seat and the calves).
SNUG, SNUG_THICKNESS = 0.004, 0.003
tank = strapped(0.04)
# A one-piece: high-cut legs (the torso faces end at the groin), narrow straps, deep neck.
swimsuit = strapped(-0.15, armhole=0.072, front=0.15, back=0.13)


def socks(ff, m):
    return (ff.part == "foot") | ((ff.part == "leg") & (ff.leg > 0.78))


def bodice(ff, m):
    return (ff.part == "torso") & (_z(ff) > m.hip[0, 2] + 0.02) & (_z(ff) < m.chest_z + 0.12)


def flare(base: float, extra: float, start: float = 0.0):
    """Ease growing down a limb (trouser legs hang straight from the widest part)."""
    return lambda p, arm, leg: base + extra * np.clip((leg - start) / (1 - start), 0, 1)


def sleeve_ease(base: float, extra: float):
    return lambda p, arm, leg: base + extra * np.clip(arm, 0, 1)


# Where along the arm (0 shoulder, 0.5 elbow, 1 wrist) a knit cuff starts gathering in,
# and where it has closed to its own ease (the sleeves end at 0.94-0.95).
CUFF_FROM, CUFF_TO = 0.8, 0.93


def cuffed(ease, cuff: float):
    """``ease`` closing in to ``cuff`` m over the sleeve's last few centimetres: a knit
    cuff gathered round the wrist. Eased as much as the forearm, a sleeve ran on as a
    straight tube 2.4-2.6 times the wrist's width, its open end a bell round a child's
    thin wrist."""

    def eased(p, arm, leg):
        t = np.clip((arm - CUFF_FROM) / (CUFF_TO - CUFF_FROM), 0, 1)
        gather = t * t * (3 - 2 * t)  # smoothstep: no kink where the gathering starts
        loose = ease(p, arm, leg)
        return loose + (np.minimum(cuff, loose) - loose) * gather

    return eased


def shoe_look(upper: str, upper_colour: str, sole_colour: str, lace_colour: str | None = None,
              cap_colour: str | None = None, sole: str = "rubber"):  # fmt: skip
    """A shoe's atlas material (``shoes.ROWS``): upper, toe cap, sole and laces; laces
    ``lace_contrast`` to the upper unless ``lace_colour`` names one."""

    def look(spec: Spec, size: int) -> Material:
        rows = shoes.ROWS
        laces = lace_contrast(upper_colour) if lace_colour is None else lace_colour
        return fabrics.atlas(spec.name, [
            (*rows["upper"], upper, upper_colour),
            (*rows["cap"], upper, cap_colour or upper_colour),
            (*rows["sole"], sole, sole_colour),
            (*rows["laces"], "cord", laces),
        ], size, stitches=(0.5 + 0.5 * 0.12, 0.3 + 0.2 * 0.2))  # fmt: skip

    return look


LACE_CONTRAST = 18.0  # CIE L* between laces and the upper: black laces vanished on black


def lace_contrast(upper_colour) -> tuple[float, float, float]:
    """Linear RGB of laces that read against an upper of ``upper_colour``: its own hue,
    LACE_CONTRAST units of CIE lightness lighter on a dark upper (grey on black, mid brown
    on dark brown), darker on a light one (dark brown on brown, light grey on white
    canvas), never white."""
    colour = fabrics.rgb(upper_colour)
    luminance = max(float(colour @ [0.2126, 0.7152, 0.0722]), 1e-4)
    lightness = _cie_lightness(luminance)
    wanted = lightness + LACE_CONTRAST if lightness < 30 else lightness - LACE_CONTRAST
    # Scaling keeps the hue; a near-black upper (no hue to keep) is mixed towards grey.
    target = _cie_luminance(wanted)
    grey = max(0.0, 1 - 30 * luminance)
    mixed = (1 - grey) * colour * (target / luminance) + grey * np.full(3, target)
    r, g, b = (float(c) for c in np.clip(mixed, 0, 1))
    return r, g, b


def _cie_lightness(luminance: float) -> float:
    y = luminance
    return 116 * y ** (1 / 3) - 16 if y > 216 / 24389 else y * 24389 / 27


def _cie_luminance(lightness: float) -> float:
    f = (lightness + 16) / 116
    return f**3 if f**3 > 216 / 24389 else lightness * 27 / 24389


# A dress's bodice: the tank top's cut on wider straps, its neckline scooped 9 cm below the
# neck joint in front (well above the bust at every size) and 7 cm at the back.
# It ends 3 cm under the skirt's top (helper-skirt reaches 13 cm above the hip joints): a
# longer bodice showed through the skirt at the back as a stray panel.
DRESS_HUG = 0.009  # m the dress's skirt keeps off the skin at the waist and hips
# The skirt's faces span 3-4 cm: mid-stride the forward knee bulged between vertices kept
# 5 mm clear and through both 1.5 mm layers (a speck of skin on the skirt). 6 mm clear and
# 3 mm of cloth keep its outer surface outside the knee through the stride.
DRESS_CLEARANCE, DRESS_THICKNESS = 0.006, 0.003
# m the skirt keeps outside the bodice's (inner) points wherever it covers them: inside the
# bodice's cloth, so the skirt's surface runs on from the bodice's, its top edge 1.5 mm
# proud of it as across a sewn waist seam (at 2.5 mm it stood 3-6 mm proud, a ledge). Kept
# 2.5 mm outside the bodice's cloth lower down and closing to this over its top 2.5 cm,
# the skirt's top sloped in to its edge 10-13 degrees steeper than the bodice ran on
# above it: from behind, a dark band and a step across the small of the back.
DRESS_SEAM = 0.0015
_dress_bodice_back = strapped(0.10, armhole=0.056, front=0.09, back=0.07)
_dress_bodice_front = strapped(0.07, armhole=0.056, front=0.09, back=0.07)


def dress_bodice(ff, m):
    """The dress's bodice, 3 cm longer in front: the skirt's top dips 2 cm lower there than
    at the sides, and a bodice cut level with the back ran level with it, its hem at the
    skirt's edge 4-6 cm either side of the middle (two dark slits between the layers)."""
    front = ff.centre[:, 1] < m.hip[0, 1]
    return _dress_bodice_back(ff, m) | (_dress_bodice_front(ff, m) & front)


def _dress(body: AuthoringBody) -> Piece:
    """Bodice on straps and a skirt, one garment. The bodice's waist edge has no band (it
    ran as a ridge round the waist) and tucks under the skirt's top; the skirt swings as
    one (``tailoring.blend_sides``), so it neither splits nor bells between the legs."""
    faces = body.group_faces("helper-tights")
    ff = face_features(body.vertices, faces, body.part, body.marks)
    bodice = cut(body, faces, dress_bodice(ff, body.marks), 0.004, relax=RELAX)
    bodice = _tucked(body, bodice, 0.0025, 0.05)
    waist = float(np.percentile(bodice.vertices[:, 2], 1)) + 0.03
    bodice = banded(bodice, lambda p: np.where(p[:, 2] > waist, 0.012, 0.0))
    # The skirt's top lies over the bodice's hem (the bodice keeps 4 mm), sits on the hips
    # and flares below them.
    skirt_piece = _skirt(body, body.marks.knee[0, 2] - 0.12, _skirt_ease(body, 0.014, 0.04),
                         hug=DRESS_HUG, under=bodice.vertices, gap=DRESS_SEAM,
                         edge_gap=DRESS_SEAM)  # fmt: skip
    waist = float(body.marks.hip[:, 2].mean()) + DRESS_WAIST
    return join([bound(body, bodice, faces), _waist_bound(body, skirt_piece, faces, waist)])


# m above the hip joints from which the dress's skirt follows the surface its bodice
# follows (``_waist_bound``).
DRESS_WAIST = 0.03


def _waist_bound(body: AuthoringBody, piece: Piece, faces: np.ndarray, above: float) -> Piece:
    """``piece`` with its vertices above ``above`` m re-bound to ``faces`` (the bodice's
    surface): bound to the helper skirt, the skirt's top met its bodice on the authoring
    body only, and stood 3-7 mm proud of it on a child or a slim woman (a ledge round the
    waist). Below, the swinging skirt's binding is kept."""
    from avatar.clothes.binder import bind
    from avatar.clothes.binding import make_binding

    b = piece.binding
    tight = bind(piece.mesh.vertices, body.vertices, faces)
    top = (piece.mesh.vertices[:, 2] > above)[:, None]
    binding = make_binding(np.where(top, tight.indices, b.indices),
                           np.where(top, tight.weights, b.weights),
                           np.where(top, tight.offsets, b.offsets), b.scale_refs,
                           b.scale_lengths, np.zeros(len(b), bool))  # fmt: skip
    return Piece(piece.mesh, binding, piece.layout)


def _tucked(body: AuthoringBody, mesh: Mesh, ease: float, reach: float) -> Mesh:
    """The mesh with its lowest ``reach`` m laid ``ease`` m off the skin (smoothly from
    its own ease above): a bodice's hem tucked in flat under a skirt, so the skirt's top
    over it steps out by a seam's few millimetres, not a ledge round the waist."""
    v = mesh.vertices.astype(np.float64)
    bottom = float(np.percentile(v[:, 2], 1))
    t = np.clip((bottom + reach - v[:, 2]) / reach, 0, 1)
    w = t * t * (3 - 2 * t)
    low = w > 0
    off, normal = tailoring.skin_offset(body, v[low])
    target = np.minimum(off, w[low] * ease + (1 - w[low]) * off)
    v[low] += (target - off)[:, None] * normal
    return Mesh(v.astype(np.float32), mesh.faces, mesh.uvs, mesh.face_uvs)


def _hood(body: AuthoringBody, across: int = 25, down: int = 22) -> Piece:
    """A hood lying down on the back: a pouch hanging from round the neck, widest over the
    shoulder blades and narrowing to a rounded point, flat in its middle and rolled up at
    its rim (the face opening folded over), the rim banded so the cloth shows its
    thickness. Modelled as a grid over the back (the helper mesh is too coarse to cut a
    point from), each point the back's surface plus the hood's puff, then bound to it."""
    m = body.marks
    low, high = m.neck[2] - 0.24, m.neck[2] - 0.005  # its top tucked under the collar

    def half_width(d):
        """m either side of the spine at depth d (0 at the neck, 1 at the tip)."""
        wide = 0.075 + 0.08 * np.sin(np.pi / 2 * np.clip(d / 0.5, 0, 1))
        return wide * np.sqrt(np.clip(1 - (np.clip(d - 0.5, 0, None) / 0.5) ** 2, 0, 1)) + 0.012

    d = np.linspace(0, 1, down)[:, None]
    u = np.linspace(-1, 1, across)[None, :]
    x = (u * half_width(d)).ravel()
    z = np.broadcast_to(high - d * (high - low), (down, across)).ravel()
    skin = body.vertices[: len(body.part)]
    skin = skin[(skin[:, 1] > m.neck[1] - 0.03) & (skin[:, 2] > low - 0.05)]
    # The back's surface seen from behind: the farthest back of the nearest skin points.
    from scipy.spatial import cKDTree

    _, near = cKDTree(skin[:, [0, 2]]).query(np.stack([x, z], -1), k=8)
    grid = skin[near, 1].max(axis=1).reshape(down, across)
    for _ in range(3):  # the cloth bridges the spine's and blades' small bumps
        grid[:, 1:-1] = 0.5 * grid[:, 1:-1] + 0.25 * (grid[:, :-2] + grid[:, 2:])
        grid[1:-1] = 0.5 * grid[1:-1] + 0.25 * (grid[:-2] + grid[2:])
    edge = np.abs(np.broadcast_to(u, (down, across)))
    # The rolled opening runs down the sides and fades out over the lower third, where the
    # bag folds round onto the back: rolled all the way round its point, a valley between
    # the roll and the bag's dome ran along the lower edge (a crease from behind).
    rim = np.exp(-(((1 - edge) / 0.22) ** 2)) * np.clip(d * 4, 0, 1) * _fade(d, HOOD_ROLL)
    pouch = np.sin(np.pi * np.clip(d, 0, 1)) ** 0.8  # the hood's bag lying on the back
    # Domed across as well as down: the bag's two layers hold air, up to 4 cm over the
    # back, settling to the rolled rim at its outline (over the hoodie: 2.1 cm at least).
    dome = np.sqrt(np.clip(1 - np.broadcast_to(u, (down, across)) ** 2, 0, 1))
    puff = 0.021 + (0.008 + 0.028 * dome) * pouch + 0.016 * rim
    points = np.stack([x, (grid + puff).ravel(), z], -1)
    points = shoes._at_least(body, points, 0.019)  # clear of the skin and the hoodie
    index = np.arange(down * across).reshape(down, across)
    faces = np.array([[index[r, c], index[r + 1, c], index[r + 1, c + 1], index[r, c + 1]]
                      for r in range(down - 1) for c in range(across - 1)], np.int32)  # fmt: skip
    mesh = orient_outward(body, points.astype(np.float32), faces)
    mesh = banded(with_box_uvs(mesh), 0.022, 0.003)
    return bound(body, mesh, body.group_faces("helper-tights"))


HOOD_ROLL = 0.65  # depth (0 at the neck, 1 at the tip) down to which the hood's rim rolls


def _fade(d: np.ndarray, end: float) -> np.ndarray:
    """1 down to depth ``end``, smoothly 0 at the tip (depth 1)."""
    t = np.clip((d - end) / (1 - end), 0, 1)
    return 1 - t * t * (3 - 2 * t)


def _drawstrings(body: AuthoringBody, length: float = 0.2, radius: float = 0.0028) -> Piece:
    """Two cords from either side of the hood's opening at the throat, hanging down the
    chest 3 mm off the cloth, each a six-sided tube ending in a narrower aglet."""
    m = body.marks
    tubes = []
    for side in (1, -1):
        start = np.array([side * 0.03, m.neck[1], m.neck[2] - 0.02])
        z = start[2] - np.linspace(0, length, 14)
        x = side * (0.03 + 0.012 * np.linspace(0, 1, 14) ** 2)
        # Lie on the chest: 2.4 cm (the hoodie's cloth and the cord) in front of the skin's
        # frontmost point at each height.
        skin = body.vertices[: len(body.part)]
        skin = skin[skin[:, 1] < m.neck[1] + 0.03]
        front = np.array([skin[(np.abs(skin[:, 0] - xi) < 0.012)
                               & (np.abs(skin[:, 2] - zi) < 0.012), 1].min()
                          for xi, zi in zip(x, z, strict=True)])  # fmt: skip
        path = np.stack([x, front - 0.024, z], -1)
        r = np.full(14, radius)
        r[-3:] = radius * 0.75  # the aglet
        a = np.linspace(0, 2 * np.pi, 6, endpoint=False)
        ring = []
        for k, p in enumerate(path):
            t = path[min(k + 1, 13)] - path[max(k - 1, 0)]
            t /= np.linalg.norm(t)
            u = np.cross(t, [1.0, 0, 0])
            u /= np.linalg.norm(u)
            w = np.cross(t, u)
            ring.append(p + r[k] * (np.cos(a)[:, None] * u + np.sin(a)[:, None] * w))
        pts = np.concatenate(ring)
        idx = np.arange(len(pts)).reshape(14, 6)
        faces = [[idx[k, j], idx[k, (j + 1) % 6], idx[k + 1, (j + 1) % 6], idx[k + 1, j]]
                 for k in range(13) for j in range(6)]  # fmt: skip
        faces += [[idx[-1, 0], idx[-1, 1], idx[-1, 2], idx[-1, 3]],
                  [idx[-1, 3], idx[-1, 4], idx[-1, 5], idx[-1, 0]]]  # fmt: skip
        f = np.asarray(faces, np.int32)
        mesh = Mesh(pts.astype(np.float32), f)
        tubes.append(bound(body, with_box_uvs(_out_of(mesh, path)), body.group_faces(
            "helper-tights")))  # fmt: skip
    return join(tubes)


def _out_of(mesh: Mesh, axis_points: np.ndarray) -> Mesh:
    """A tube's faces turned away from its axis (nearest axis point)."""
    v = mesh.vertices[mesh.faces].astype(np.float64)
    n = np.cross(v[:, 2] - v[:, 0], v[:, 3] - v[:, 1])
    mid = v.mean(axis=1)
    nearest = axis_points[np.argmin(np.linalg.norm(mid[:, None] - axis_points[None], axis=2),
                                    axis=1)]  # fmt: skip
    flip = np.einsum("fd,fd->f", n, mid - nearest) < 0
    faces = mesh.faces.copy()
    faces[flip] = faces[flip][:, ::-1]
    return Mesh(mesh.vertices, faces)


def _kangaroo_pocket(ff, m):
    """The hoodie's front pocket: a patch across the belly, above the hem band."""
    x, y, z = ff.centre.T
    return ((ff.part == "torso") & (y < m.neck[1] - 0.02) & (np.abs(x) < 0.115)
            & (z > m.hip[0, 2] + 0.01) & (z < m.hip[0, 2] + 0.17))  # fmt: skip


HOODIE_NECK = 0.0  # m the hoodie's body reaches above the neck joint (under the collar)
COLLAR_V = 0.075  # m below the neck joint where the hood's two front edges cross


def neckline(mesh: Mesh, neck: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The neck opening of a top: (centre (2,) xy, radius (A,) m and height (A,) z at the
    angles ``NECK_ANGLES`` round it, 0 the front, + the wearer's left), from the open edge
    of ``mesh`` nearest the neck joint ``neck`` (3,)."""
    from avatar.geometry.shell import boundary_edges

    v = mesh.vertices.astype(np.float64)
    rim = np.unique(boundary_edges(mesh.faces)[0])
    rim = rim[(np.abs(v[rim, 2] - neck[2]) < 0.08) & (np.hypot(v[rim, 0], v[rim, 1] - neck[1])
                                                      < 0.12)]  # fmt: skip
    p = v[rim]
    centre = np.array([0.0, p[:, 1].mean()])
    angle = np.arctan2(p[:, 0], centre[1] - p[:, 1])
    order = np.argsort(angle)
    a = np.concatenate([angle[order] - 2 * np.pi, angle[order], angle[order] + 2 * np.pi])
    r = np.tile(np.hypot(p[order, 0], p[order, 1] - centre[1]), 3)
    z = np.tile(p[order, 2], 3)
    return centre, np.interp(NECK_ANGLES, a, r), np.interp(NECK_ANGLES, a, z)


NECK_ANGLES = np.linspace(-np.pi, np.pi, 73)


def _tube(path: np.ndarray, outward: np.ndarray, radii: np.ndarray, segments: int = 10,
          ) -> Mesh:  # fmt: skip
    """A closed tube along ``path`` (P, 3): elliptic rings of ``radii`` (P, 2) (along
    ``outward`` (P, 3), then across it), capped at both ends, faces out."""
    t = np.gradient(path, axis=0)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    n = outward - np.einsum("pd,pd->p", outward, t)[:, None] * t
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    b = np.cross(t, n)
    a = np.linspace(0, 2 * np.pi, segments, endpoint=False)
    rings = (path[:, None] + np.cos(a)[None, :, None] * (radii[:, 0, None] * n)[:, None]
             + np.sin(a)[None, :, None] * (radii[:, 1, None] * b)[:, None])  # fmt: skip
    count = len(path)
    idx = np.arange(count * segments).reshape(count, segments)
    faces = [[idx[k, j], idx[k, (j + 1) % segments], idx[k + 1, (j + 1) % segments],
              idx[k + 1, j]] for k in range(count - 1) for j in range(segments)]  # fmt: skip
    points = np.concatenate([rings.reshape(-1, 3), path[[0, -1]]])
    ends = (count * segments, count * segments + 1)
    faces += [[idx[0, (j + 1) % segments], idx[0, j], ends[0], ends[0]] for j in range(segments)]
    faces += [[idx[-1, j], idx[-1, (j + 1) % segments], ends[1], ends[1]] for j in range(segments)]
    mesh = _out_of(Mesh(points.astype(np.float32), np.asarray(faces, np.int32)), path)
    return with_box_uvs(mesh)


def _hood_collar(body: AuthoringBody, top_mesh: Mesh) -> Piece:
    """The hood's opening edge lying round the neck as a soft roll over the hoodie's
    neckline: two halves from the back of the neck round the sides, down the front into
    a crossover V ``COLLAR_V`` below the neck joint, the wearer's left half over the right.
    Each half is an elliptic tube (the folded double layer of the hood's edge with its
    drawstring channel), kept clear of the skin and the hoodie."""
    m = body.marks
    centre, radius, height = neckline(top_mesh, m.neck)
    pieces = []
    for side in (1, -1):
        a = np.linspace(side * np.pi, side * np.radians(4), 40)  # back centre -> front
        r = np.interp(a, NECK_ANGLES, radius)
        z = np.interp(a, NECK_ANGLES, height)
        front = np.clip(1 - np.abs(a) / np.radians(70), 0, 1)  # 0 at the sides, 1 in front
        direction = np.stack([np.sin(a), -np.cos(a), np.zeros_like(a)], -1)
        path = np.concatenate([centre, [0.0]]) + (r + 0.012)[:, None] * direction
        # Level round the back and sides at the back's neckline (a neckline rises over
        # the trapezius; a roll lying on it does not), its lower edge over the hoodie's.
        level = float(np.interp(np.pi, NECK_ANGLES, height)) + 0.014
        rest = level * (1 - front) + (z + 0.008) * front
        path[:, 2] = rest + (m.neck[2] - COLLAR_V - rest) * front**1.6
        # The front ends run past the middle: the left half crosses over the right.
        path[:, 0] -= side * 0.02 * front**3
        lift = 0.003 + (0.007 if side > 0 else 0.0) * front**2
        radii = np.stack([0.0085 + 0.002 * (1 - front), 0.013 - 0.004 * front**2], -1)
        # The roll's centre clears the skin by its own size (over the hoodie and, at the
        # back, over the bag's top); the per-vertex push below only mops up.
        gap = 0.011 + 0.005 * (1 - front) + radii.max(axis=1) + lift
        axis_xy = np.asarray(centre, np.float64)
        for _ in range(3):  # pushed clear, then smoothed along (no horns over the trapezius)
            path = _clear_outwards(body, path, gap, axis_xy)
            for _ in range(4):
                path[1:-1] = 0.5 * path[1:-1] + 0.25 * (path[:-2] + path[2:])
        path = _clear_outwards(body, path, gap, axis_xy)
        outward = np.concatenate([direction[:, :2], np.full((len(a), 1), 0.5)], 1)
        tube = _tube(path, outward, radii)
        ring_lift = np.concatenate([np.repeat(lift, 10), lift[[0, -1]]])
        points = _clear_rings(body, tube.vertices.astype(np.float64), 0.008 + ring_lift,
                              axis_xy, 10)  # fmt: skip
        tube = Mesh(points.astype(np.float32), tube.faces, tube.uvs, tube.face_uvs)
        pieces.append(bound(body, tube, body.group_faces("helper-tights")))
    return join(pieces)


def _clear_outwards(body: AuthoringBody, points: np.ndarray, gap, axis_xy: np.ndarray,
                    ) -> np.ndarray:  # fmt: skip
    """(N, 3) points moved straight out from the vertical axis through ``axis_xy`` (2,)
    until ``gap`` m (scalar or (N,)) off the skin: along the skin's normal (up and out
    on the trapezius' slope) the hood's roll rose into horns either side of the neck and
    its tube's underside went lumpy from behind."""
    out = points.copy()
    for _ in range(4):
        need = np.linalg.norm(shoes._at_least(body, out, gap) - out, axis=1)
        if need.max() < 1e-5:
            break
        radial = out[:, :2] - axis_xy
        radial /= np.maximum(np.linalg.norm(radial, axis=1, keepdims=True), 1e-9)
        facing = np.einsum("nd,nd->n", radial, body.outward(out)[:, :2])
        out[:, :2] += radial * (need / np.clip(facing, 0.4, 1.0))[:, None]
    return out


def _clear_rings(body: AuthoringBody, points: np.ndarray, gap: np.ndarray,
                 axis_xy: np.ndarray, segments: int) -> np.ndarray:  # fmt: skip
    """A ``_tube``'s points (rings of ``segments``, then its two end centres) cleared as
    ``_clear_outwards`` does, each ring moved as one (by its most pressed point), so the
    tube stays round instead of dented where single points were pushed."""
    rings = (len(points) - 2) // segments
    body_part = points[: rings * segments]
    moved = _clear_outwards(body, body_part, gap[: rings * segments], axis_xy)
    shift = (moved - body_part).reshape(rings, segments, 3)
    worst = np.argmax(np.linalg.norm(shift, axis=2), axis=1)
    ring_shift = shift[np.arange(rings), worst]  # (rings, 3)
    out = points.copy()
    out[: rings * segments] += np.repeat(ring_shift, segments, axis=0)
    out[rings * segments :] += ring_shift[[0, -1]]
    return out


def _hoodie(body: AuthoringBody) -> Piece:
    sleeves = cuffed(sleeve_ease(0.013, 0.012), 0.004)
    top_piece = _tights(body, top(0.95, neck=-HOODIE_NECK, hem=-0.02), sleeves, 0.03,
                        bridge=True)  # fmt: skip
    pocket = _tights(body, _kangaroo_pocket, 0.017, 0.012)
    collar = _hood_collar(body, top_piece.mesh)
    return join([top_piece, pocket, _hood(body), collar, _drawstrings(body)])


def _skirt_ease(body: AuthoringBody, base: float, extra: float):
    hip, knee = body.marks.hip[0, 2], body.marks.knee[0, 2]
    return lambda p, arm, leg: base + extra * np.clip((hip - p[:, 2]) / (hip - knee), 0, 1.5)


def _cap(body: AuthoringBody) -> Piece:
    return headwear.cap(body)


EYELASH_GROUPS = (
    "helper-l-eyelashes-1",
    "helper-l-eyelashes-2",
    "helper-r-eyelashes-1",
    "helper-r-eyelashes-2",
)

SPECS = [
    Spec("tshirt", "tops", lambda b: _tights(b, top(0.3), sleeve_ease(0.007, 0.02), 0.014, bridge=True), "cotton", "white", 0.0015, 40, ("t-shirt", "short sleeve", "casual")),  # noqa: E501
    Spec("longsleeve", "tops", lambda b: _tights(b, top(0.94), cuffed(sleeve_ease(0.006, 0.012), 0.002), 0.02, bridge=True), "jersey", "navy", 0.0015, 40, ("long sleeve", "shirt")),  # noqa: E501
    Spec("tanktop", "tops", lambda b: _tights(b, tank, 0.004), "jersey", "grey", 0.0012, 40, ("tank top", "vest", "sleeveless")),  # noqa: E501
    Spec("jacket", "tops", lambda b: jacket.tailored(b, _tights(b, opened(top(0.95, neck=-0.03, hem=-0.03), 0.02), sleeve_ease(0.016, 0.01), 0.02, bridge=True, open_front=True)), "leather", "black", 0.003, 60, ("jacket", "outerwear", "open"), hang=True),  # noqa: E501
    Spec("cardigan", "tops", lambda b: _tights(b, opened(top(0.94, neck=-0.01, hem=-0.05), 0.022), cuffed(sleeve_ease(0.012, 0.01), 0.006), 0.025, bridge=True, open_front=True), "knit", "beige", 0.003, 58, ("cardigan", "knit", "elderly", "open"), hang=True),  # noqa: E501
    Spec("hoodie", "tops", _hoodie, "knit", "grey", 0.004, 55, ("hoodie", "sweater", "knit"), hang=True),  # noqa: E501
    Spec("shorts", "bottoms", lambda b: _tights(b, bottom(0.4), flare(0.007, 0.02), fly=True), "canvas", "khaki", 0.002, 35, ("shorts",), fly=True),  # noqa: E501
    Spec("trousers", "bottoms", lambda b: _tailored(b, "trousers", 0.97, flare(0.008, 0.02, 0.2), 1.0, "grey", 0.88), "wool", "charcoal", 0.002, 35, ("trousers", "pants", "formal"), fly=True),  # noqa: E501
    Spec("jeans", "bottoms", lambda b: _tailored(b, "jeans", 0.96, flare(0.005, 0.01, 0.3), 1.0, "yellow", 0.92), "denim", "indigo", 0.0025, 35, ("jeans", "denim", "pants"), fly=True),  # noqa: E501
    Spec("sweatpants", "bottoms", lambda b: _tights(b, bottom(0.95), flare(0.012, 0.02, 0.1), 0.03, fly=True), "jersey", "grey", 0.002, 35, ("sweatpants", "joggers", "children", "elderly"), fly=True),  # noqa: E501
    Spec("leggings", "bottoms", lambda b: _tights(b, bottom(0.95), 0.0015, snug=SNUG), "lycra", "black", SNUG_THICKNESS, 25, ("leggings", "sport")),  # noqa: E501
    Spec("skirt", "bottoms", lambda b: _skirt(b, b.marks.knee[0, 2] + 0.1, _skirt_ease(b, 0.004, 0.03), tailor=True), "cotton", "red", 0.0015, 36, ("skirt",), clearance=0.006, swing=True),  # noqa: E501
    Spec("dress", "dresses", _dress, "cotton", "teal", DRESS_THICKNESS, 38, ("dress",), clearance=DRESS_CLEARANCE, swing=True),  # noqa: E501
    Spec("swimsuit", "swimwear", lambda b: _tights(b, swimsuit, 0.001, snug=SNUG), "lycra", "sky", SNUG_THICKNESS, 25, ("swimwear", "one-piece")),  # noqa: E501
    Spec("socks", "legwear", lambda b: _tights(b, socks, 0.0015), "knit", "white", 0.0015, 20, ("socks",)),  # noqa: E501
    Spec("shoes", "footwear", shoes.shoes, "leather", "brown", 0.0025, 30, ("shoes", "leather", "laced"), look=shoes.look("calf", "brown", "sole", "sole brown")),  # noqa: E501
    Spec("shoes-black", "footwear", shoes.shoes, "leather", "black", 0.0025, 30, ("shoes", "formal", "laced"), look=shoes.look("calf", "black", "sole", "sole black")),  # noqa: E501
    Spec("sneakers", "footwear", shoes.sneakers, "canvas", "light grey", 0.0025, 30, ("sneakers", "trainers", "children", "sport"), look=shoes.look("cotton", "light grey", "rubber", "white", cap_colour="grey", trim=("cotton", "navy"), band="navy")),  # noqa: E501
    Spec("boots", "footwear", lambda b: shoes.shoes(b, top=0.86), "leather", "brown", 0.0025, 30, ("boots", "ankle boots", "laced"), look=shoes.look("calf", "dark brown", "sole", "sole black")),  # noqa: E501
    Spec("cap", "headwear", _cap, "canvas", "red", 0.0, 80, ("cap", "hat", "baseball")),
    Spec("hair-short", "hair", lambda b: join([hair.base_cap(b), hair.grow_cards(b, hair.flow_crown())]), "hair", "dark brown hair", 0.0, 70, ("hair", "short")),  # noqa: E501
    Spec("hair-long", "hair", lambda b: join([hair.base_cap(b), hair.grow_cards(b, hair.flow_parted(), 300, (0.1, 0.16), 0.025, (0.004, 0.012), 4, side_lift=LONG_SIDE_LIFT_M), hair.long_cards(b, side_lift=LONG_SIDE_LIFT_M), hair.side_locks(b, hair.flow_parted())]), "hair", "blond hair", 0.0, 70, ("hair", "long")),  # noqa: E501
    Spec("hair-ponytail", "hair", lambda b: join([hair.base_cap(b), hair.grow_cards(b, hair.flow_tied(), 480, (0.08, 0.14), 0.015, (0.003, 0.01), 4), hair.ponytail(b)]), "hair", "black hair", 0.0, 70, ("hair", "tied back", "ponytail")),  # noqa: E501
    Spec("hair-buzz", "hair", lambda b: join([hair.base_cap(b, 0.0015, soft=BUZZ_HAIRLINE_M), hair.grow_cards(b, hair.flow_crown(sweep=0.0), BUZZ_CARDS, (0.005, 0.009), BUZZ_WIDTH, (0.0024, 0.003), 1, root=BUZZ_ROOT, thin=BUZZ_HAIRLINE_M)]), "hair", "dark brown hair", 0.0, 70, ("hair", "buzz", "short", "men"), look=textures.buzz_material),  # noqa: E501
    Spec("hair-bob", "hair", lambda b: join([hair.base_cap(b), hair.grow_cards(b, hair.flow_parted(), 300, (0.06, 0.1), 0.025, (0.004, 0.014), 4), hair.hang_cards(b, hair.flow_parted())]), "hair", "auburn hair", 0.0, 70, ("hair", "bob", "fringe")),  # noqa: E501
    Spec("hair-bun", "hair", lambda b: join([hair.base_cap(b), hair.grow_cards(b, hair.flow_tied((0.0, 0.06, 0.075)), 360, (0.08, 0.14), 0.025, (0.003, 0.007), 4), hair.bun(b)]), "hair", "grey hair", 0.0, 70, ("hair", "bun", "tied back", "elderly")),  # noqa: E501
    Spec("eyebrows", "face", face.eyebrows, "hair", "dark brown hair", 0.0, 5, ("eyebrows",), False),  # noqa: E501
    Spec("eyebrows-blond", "face", face.eyebrows, "hair", "blond hair", 0.0, 5, ("eyebrows", "blond"), False),  # noqa: E501
    Spec("eyebrows-black", "face", face.eyebrows, "hair", "black hair", 0.0, 5, ("eyebrows", "black"), False),  # noqa: E501
    Spec("eyelashes", "face", lambda b: face.eyelashes(b, EYELASH_GROUPS), "hair", "black hair", 0.0, 5, ("eyelashes",), False),  # noqa: E501
    Spec("beard-short", "beard", face.beard, "hair", "dark brown", 0.0, 6, ("beard", "facial hair", "men"), look=facial_hair.beard_material),  # noqa: E501
    Spec("moustache", "beard", face.moustache, "hair", "dark brown", 0.0, 6, ("moustache", "mustache", "facial hair", "men"), look=facial_hair.beard_material),  # noqa: E501
    Spec("stubble", "beard", face.stubble, "hair", "black hair", 0.0, 4, ("stubble", "facial hair", "men"), False, look=facial_hair.stubble_material),  # noqa: E501
]  # fmt: skip

BY_NAME = {s.name: s for s in SPECS}


def build(spec: Spec, body: AuthoringBody, texture_size: int = 1024,
          piece: Piece | None = None) -> Garment:  # fmt: skip
    """A built-in Garment from its recipe on the authoring body; ``piece``: its already cut
    piece (``spec.make(body)``), e.g. one shared with its fabric/colour variants."""
    return assemble(spec, spec.make(body) if piece is None else piece, body, texture_size)


def _swing_below(spec: Spec, body: AuthoringBody) -> float | None:
    """m: the height on the authored mesh below which a garment's skin weights are carried
    down its cloth (``weights.swing``): a skirt's from the hip joints, a hanging top's from
    the waist (above the reach of the thighs' weights: at the hip joints they still made
    half of a cardigan's hem weight there, its back hem 2.5 cm askew mid-stride)."""
    if spec.hang:
        return float(body.marks.waist_z)
    return float(body.marks.hip[:, 2].mean()) if spec.swing else None


def look(spec: Spec, layout, texture_size: int = 1024) -> Material:
    """The Material of a built-in in ``spec``'s fabric and colour; ``layout``: its piece's
    panel layout (``Piece.layout``, None for a tiled fabric). A fabric or colour variant is
    ``look(dataclasses.replace(spec, fabric=..., colour=...), layout)``: no geometry."""
    if layout is not None:
        # A panel texture covers the whole garment once (not a tile): twice the texels.
        return tailored.material(spec.name, spec.fabric, spec.colour, layout,
                                 min(2 * texture_size, 4096))  # fmt: skip
    if spec.look is not None:
        return spec.look(spec, texture_size)
    if spec.category in ("hair", "face"):
        return textures.hair_material(spec, texture_size)
    return fabrics.material(spec.fabric, spec.colour, texture_size, name=spec.name)


def assemble(spec: Spec, piece: Piece, body: AuthoringBody, texture_size: int = 1024) -> Garment:
    """A built-in Garment from its already cut ``piece`` (``spec.make(body)``)."""
    material = look(spec, piece.layout, texture_size)
    # Face proxies are drawn on the skin; holes there would show through, so they hide nothing.
    delete = covered_skin(body, piece.mesh) if spec.collide else np.zeros(0, np.int32)
    return Garment(
        name=spec.name,
        mesh=piece.mesh,
        binding=piece.binding,
        material=material,
        z_depth=spec.z_depth,
        delete_verts=delete,
        thickness=spec.thickness,
        clearance=CLEARANCE if spec.clearance is None else spec.clearance,
        collide=spec.collide,
        category=spec.category,
        tags=spec.tags,
        source="builtin",
        licence="CC0 (generated by Avatar from MakeHuman's CC0 base mesh)",
        swing_below=_swing_below(spec, body),
        fly_share=fly_share(body, piece.mesh) if spec.fly else None,
    )

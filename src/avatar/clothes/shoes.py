"""Shoes built from the foot: a leather upper, a rubber sole with a heel block, a toe cap
and laces, all generated on the authoring body and bound to it, so they fit every foot.

Parts, per foot (``x > 0`` is the body's left):

- upper: the ``helper-tights`` faces of the foot and ankle, eased off the skin, its
  opening smoothed into a curve, the toe box drawn out past the toes and sloping down to
  its tip, the bottom edge drawn down to just above the ground;
- sole: a thin edge (``_sole_edge``) round the upper's bottom edge, out by a welt, down to
  a tread a little below the foot, taller at the heel (a heel block), lifted under the
  arch and curling up at the toe (toe spring), closed underneath;
- toe cap: the front of the upper again, sewn flat on it (under a millimetre out);
- laces: bars across the instep, lying on the upper.

The four share one material: an atlas (``looks.atlas``) whose rows hold leather, toe-cap
leather, rubber and lace cord, each piece's UVs laid out inside its row.
"""

from __future__ import annotations

import numpy as np

from avatar.clothes import regions
from avatar.clothes.authoring import AuthoringBody, Piece, bound, cut, join
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
WELT = 0.003
ARCH = 0.006  # m the tread is lifted between heel block and ball of the foot
SPRING = 0.012  # m the tread curls up at the tip of the toe box (toe spring)
CAP_EASE = EASE + 0.0012  # a toe cap sewn flat on the vamp, not a shell over it
# The upper's faces end OPEN_BOTTOM m above the foot's lowest point, then its bottom
# edge is drawn down to EDGE m above it (the sole covers it): left where the faces ended
# it wandered 2.5-15 mm above the ground, and the sole's edge with it (a clog's slab);
# cutting the faces lower let the toes' bumps through the leather.
OPEN_BOTTOM = 0.012
EDGE = 0.002
SOCK_ROOM = 0.001  # m a smoothed toe box may sink inside the cut (a sock is 2 mm inside)
DRAWN_CLEAR = 0.003  # m over the ease the drawn edge keeps: room for a sock where the foot flares
LACES = 5  # bars across the instep

# Atlas rows (v0, v1) in the shoe material: leather upper, toe cap, sole rubber, laces.
ROWS = {"upper": (0.5, 1.0), "cap": (0.3, 0.5), "sole": (0.1, 0.3), "laces": (0.0, 0.1)}


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
    return bound(body, _planar_uvs(mesh, "upper"), faces)


def _drawn_down(body: AuthoringBody, foot: Foot, mesh: Mesh, ease: float = EASE) -> Mesh:
    """The upper with its bottom edge drawn straight down to EDGE m above the ground, the
    tip curling up with the sole's toe spring (the sole can only curl as far as the edge
    it covers), still ``ease`` + DRAWN_CLEAR off the skin."""
    v = mesh.vertices.astype(np.float64)
    loop = _lowest_loop(mesh)
    loop = loop[v[loop, 2] < foot.ground + OPEN_BOTTOM + 0.01]  # a toe cap's back edge stays
    spring = SPRING * np.clip((foot.along(v[loop]) - 0.84) / 0.2, 0, 1) ** 2
    v[loop, 2] = np.minimum(v[loop, 2], foot.ground + EDGE + spring)
    v[loop] = _at_least(body, v[loop], ease + DRAWN_CLEAR)
    return Mesh(v.astype(np.float32), mesh.faces, mesh.uvs, mesh.face_uvs)


def toe_cap(body: AuthoringBody, foot: Foot) -> Piece:
    faces = body.group_faces("helper-tights")
    centre = body.vertices[faces].mean(axis=1)
    keep = _shoe_faces(body, foot, faces) & (foot.along(centre) > 0.78)
    mesh = cut(body, faces, keep, CAP_EASE, relax=8)
    mesh = _toe_box(body, foot, mesh, CAP_EASE)  # drawn down too, a sock showed at its corner
    return bound(body, _planar_uvs(mesh, "cap"), faces)


def _toe_box(body: AuthoringBody, foot: Foot, mesh: Mesh, ease: float) -> Mesh:
    """A shoe's shape, not the foot's: toes' bumps smoothed away (Laplacian passes over the
    shell, then every vertex at least ``ease`` off the skin again), the front drawn out a
    centimetre past the toes into a rounded box."""
    v = mesh.vertices.astype(np.float64)
    v0 = v.copy()
    a = mesh.faces.reshape(-1)
    b = np.roll(mesh.faces, -1, axis=1).reshape(-1)
    degree = np.bincount(a, minlength=len(v)) + np.bincount(b, minlength=len(v))
    from avatar.geometry.shell import boundary_edges

    edges, _ = boundary_edges(mesh.faces)
    rim = np.zeros(len(v), bool)
    rim[edges.ravel()] = True  # the opening and the bottom edge keep their curves
    t = foot.along(v)
    weight = np.clip((t - 0.55) / 0.25, 0, 1)[:, None]  # smooth the forefoot most
    for _ in range(12):
        total = np.zeros_like(v)
        np.add.at(total, a, v[b])
        np.add.at(total, b, v[a])
        average = total / np.maximum(degree, 1)[:, None]
        v = np.where(rim[:, None], v, v + 0.6 * (0.3 + 0.7 * weight) * (average - v))
    front = np.clip((t - 0.6) / 0.4, 0, 1) ** 2
    v[:, 1] -= 0.016 * front  # the toe box reaches past the toes
    # ... and slopes down to its tip (a last's toe, not a clog's blunt dome): in front of
    # the toes the height over the sole taken down by up to 40% (over the toes it pushed
    # the bumps of the toes back into the leather, and a sock through it).
    tip = np.clip((t - 0.93) / 0.15, 0, 1) ** 2
    v[:, 2] -= 0.4 * tip * np.clip(v[:, 2] - foot.ground - 0.008, 0, None)
    # Smoothing pulls the convex parts in (the little toe's joint), where the shell stands
    # well off the skin: a sock cut from the shell showed through. Each vertex stays within
    # SOCK_ROOM inside the cut's own surface, and ``ease`` off the skin.
    normal0 = body.outward(v0)
    inward = np.einsum("nd,nd->n", v - v0, normal0)
    v += np.clip(-SOCK_ROOM - inward, 0, None)[:, None] * normal0
    v = _at_least(body, v, ease)
    # Fill the hollows between toes: smoothing that only ever moves a vertex outwards.
    normal = body.outward(v)
    for _ in range(10):
        total = np.zeros_like(v)
        np.add.at(total, a, v[b])
        np.add.at(total, b, v[a])
        rise = np.einsum("nd,nd->n", total / np.maximum(degree, 1)[:, None] - v, normal)
        v = np.where(rim[:, None], v, v + (np.clip(rise, 0, None) * weight[:, 0])[:, None] * normal)
    return Mesh(v.astype(np.float32), mesh.faces)


def _at_least(body: AuthoringBody, points: np.ndarray, gap: float) -> np.ndarray:
    """(N, 3) points pushed out along the nearest skin vertex's normal to ``gap`` m off it."""
    _, i = body.skin_tree.query(points, k=8)
    out = points.copy()
    for k in range(i.shape[1]):  # the worst of the nearest skin vertices decides
        skin, n = body.vertices[i[:, k]], body.skin_normals[i[:, k]].astype(np.float64)
        d = np.einsum("nd,nd->n", out - skin, n)
        out += np.clip(gap - d, 0, None)[:, None] * n * (d > -0.02)[:, None]
    return out


def sole(body: AuthoringBody, foot: Foot, top: Piece) -> Piece:
    """The sole under an upper: its lowest boundary loop extruded out and down, capped."""
    loop = _lowest_loop(top.mesh)
    ring = top.mesh.vertices[loop].astype(np.float64)
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
    ring = ring.copy()
    ring[:, :2] += extra[:, None] * out
    t = foot.along(ring)
    edge, tread = _sole_edge(ring, t, foot)
    rings = [
        np.column_stack([ring[:, :2] - 0.001 * out - extra[:, None] * out,
                         edge + 0.001]),  # tucked under the upper's edge
        np.column_stack([ring[:, :2] + WELT * out, edge]),  # welt top
        np.column_stack([ring[:, :2] + WELT * out, tread + 0.002]),
        np.column_stack([ring[:, :2] + (WELT - 0.0015) * out, tread]),  # the edge rounded
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
    faces += [[bottom + (i + 1) % n, bottom + i, middle, middle] for i in range(n)]
    mesh = Mesh(points.astype(np.float32), np.array(faces, np.int32))
    mesh = _facing_out(mesh, centre + [0, 0, 0.02])
    return bound(body, _planar_uvs(mesh, "sole"), body.group_faces("helper-tights"))


def _sole_edge(ring: np.ndarray, t: np.ndarray, foot: Foot) -> tuple[np.ndarray, np.ndarray]:
    """(top (n,), tread (n,)) z of the sole's edge round the ``ring`` (n, 3) of the upper's
    bottom edge at ``t`` (n,) along the foot: the top COVER over the upper's edge (smoothed
    round the ring, at least HEEL above the ground behind the heel's breast); the tread
    flat under heel and ball, lifted ARCH under the arch and SPRING at the toe's tip."""
    top = ring[:, 2] + COVER
    for _ in range(6):  # the upper's edge follows whole helper faces: a ragged line
        smooth = 0.5 * top + 0.25 * (np.roll(top, 1) + np.roll(top, -1))
        top = np.maximum(ring[:, 2] + COVER, smooth)
    heel = np.clip((0.3 - t) / 0.06, 0, 1)  # the heel block ends at its breast, t ~ 0.27
    top = np.maximum(top, foot.ground + HEEL * heel)
    arch = ARCH * np.clip(1 - np.abs(t - 0.45) / 0.15, 0, 1) ** 0.5
    spring = SPRING * np.clip((t - 0.84) / 0.2, 0, 1) ** 2
    tread = foot.ground - UNDER + arch + spring
    return top, np.minimum(tread, top - 0.004)


def laces(body: AuthoringBody, foot: Foot, top: Piece) -> Piece:
    """Bars across the instep, each a strip 5 mm wide lying 1.5 mm over the upper."""
    v = top.mesh.vertices.astype(np.float64)
    t = foot.along(v)
    strips = []
    for k in range(LACES):
        at = 0.48 + 0.22 * k / (LACES - 1)  # from the ankle's front towards the toes
        band = np.abs(t - at) < 0.03
        if not band.any():
            continue
        highest = v[band][np.argmax(v[band][:, 2])]
        across = np.linspace(-0.014, 0.014, 7)
        y = highest[1]
        points = []
        for dx in across:
            x = highest[0] + dx
            near = np.hypot(v[:, 0] - x, v[:, 1] - y) < 0.008
            z = v[near, 2].max() if near.any() else highest[2]
            points.append([x, y, z + 0.0015])
        centre = np.array(points)
        # Crossed, as laced shoes are: each bar slants a little, alternating.
        slant = 0.004 * (1 if k % 2 else -1) * np.linspace(-1, 1, len(centre))
        front = centre + np.column_stack([np.zeros(len(centre)), -0.0025 + slant,
                                          np.zeros(len(centre))])  # fmt: skip
        back = centre + np.column_stack([np.zeros(len(centre)), 0.0025 + slant,
                                         np.full(len(centre), 0.0005)])  # fmt: skip
        strips.append(_strip(front, back))
    mesh = _merge(strips)
    return bound(body, _planar_uvs(mesh, "laces"), body.group_faces("helper-tights"))


def shoes(body: AuthoringBody, top: float = 0.96) -> Piece:
    """Both shoes, every piece bound to the body's ``helper-tights`` shell; ``top``: how
    far up the leg the upper reaches (``upper``)."""
    pieces = []
    for side in (0, 1):
        foot = Foot(body, side)
        top_piece = upper(body, foot, top)
        pieces += [top_piece, toe_cap(body, foot), sole(body, foot, top_piece),
                   laces(body, foot, top_piece)]
    return join(pieces)


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


def _planar_uvs(mesh: Mesh, row: str) -> Mesh:
    """Per-corner UVs inside the atlas row: the piece seen from its side (y, z) for the
    upper, toe cap and sole, from above (x, y) for laces, scaled to fit the row."""
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
    uvs = np.stack([0.02 + 0.96 * u, v0 + (v1 - v0) * (0.05 + 0.9 * w)], -1).reshape(-1, 2)
    face_uvs = np.arange(mesh.faces.size, dtype=np.int32).reshape(mesh.faces.shape)
    return Mesh(mesh.vertices, mesh.faces, uvs.astype(np.float32), face_uvs)

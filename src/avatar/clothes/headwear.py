"""A baseball cap: a six-panel crown with a button on top and a stiff, curved brim.

- crown: a dome over the skull, each point a fixed ease off the scalp along its direction
  from the head's centre (the scalp's bumps smoothed away, as a structured crown is), its
  rim a sweatband running above the brows and ears and down to the back of the head;
  six gores meet at the top; their seams, top-stitching and stitched eyelets are painted
  in the texture (``looks.tailored``), the rim carries a raised band;
- button: a cloth-covered dome where the gores meet;
- brim: a separate plate with thickness, curved down at its sides, its outline rounded by
  a half tube, stitched in rows parallel to its edge.

Every piece is bound to the skin, so the cap follows every head; UVs share one texture:
v in [0.3, 1] the crown (u around the head, v from the rim up to the button), v in [0, 0.28]
the brim (u across, v out to its edge).
"""

from __future__ import annotations

import numpy as np

from avatar.body.model import BODY_VERTICES
from avatar.clothes.authoring import AuthoringBody, Piece, banded, bound, join
from avatar.looks.tailored import Layout, Mark
from avatar.mesh import Mesh

EASE = 0.007  # m between scalp and crown: a snug sweatband (hair is fitted under it)
GORES = 6
MERIDIANS = 72  # around the crown (a multiple of GORES: seams fall on meridians)
RINGS = 16  # from the rim up to the button
BRIM_REACH = 0.075  # m the brim stands out in front
BRIM_THICK = 0.004
# The brim's top meets the crown's band (the band's lower edge BRIM_SEAT m into it) and
# its plate runs BRIM_TUCK m on under the crown, as a brim is sewn inside the sweatband:
# attached 2 mm below the rim, under a band standing 1.5 mm proud, it left a slit that
# rendered as a dark line between band and brim.
BRIM_SEAT, BRIM_TUCK = 0.0015, 0.0035
BRIM_SPAN = 68.0  # degrees either side of the front the brim is attached over (temple to temple)
UV_PER_METRE = 2.0  # the cap's texture: roughly 0.5 m of cloth across it


def _frame(body: AuthoringBody) -> tuple[np.ndarray, float, np.ndarray]:
    """(skull centre (3,), eye height z, head skin points (N, 3) above the ears' bottom)."""
    head = body.vertices[:BODY_VERTICES][body.part[:BODY_VERTICES] == "head"]
    left, right = body.centre("helper-l-eye"), body.centre("helper-r-eye")
    eye_z = float((left[2] + right[2]) / 2)
    centre = np.array([0.0, (head[:, 1].min() + head[:, 1].max()) / 2, eye_z + 0.01])
    return centre, eye_z, head[head[:, 2] > eye_z - 0.04]


def rim_height(phi: np.ndarray, eye_z: float) -> np.ndarray:
    """(N,) z of the crown's rim at angles ``phi`` (radians, 0 the front, + the left):
    above the brows in front, over the ears' tops, and at the back down to the ear-top
    line under the occipital bulge (a cap is held by the back of the skull, not perched
    on its crown)."""
    facing = np.cos(phi)
    return eye_z + 0.042 * np.maximum(facing, 0) + 0.034 * (1 - np.abs(facing)) \
        - 0.006 * np.maximum(-facing, 0) ** 2


def _direction(phi: np.ndarray, z: np.ndarray, centre: np.ndarray, radius: float):
    """Unit directions from ``centre`` towards angle phi at height z on a sphere of radius."""
    up = np.clip((z - centre[2]) / radius, -0.95, 0.95)
    flat = np.sqrt(1 - up**2)
    return np.stack([flat * np.sin(phi), -flat * np.cos(phi), up], -1)


def _scalp_distance(directions: np.ndarray, centre: np.ndarray, head: np.ndarray,
                    cone: float = 12.0) -> np.ndarray:  # fmt: skip
    """(N,) how far the scalp reaches from ``centre`` along each direction: the farthest
    head point within ``cone`` degrees of it, projected on it (a smooth, hull-like reach)."""
    rel = head - centre
    dist = np.linalg.norm(rel, axis=1)
    unit = rel / dist[:, None]
    out = np.empty(len(directions))
    for i, d in enumerate(directions):
        cos = unit @ d
        near = cos > np.cos(np.radians(cone))
        out[i] = float((dist[near] * cos[near]).max()) if near.any() else float(dist.max())
    return out


def crown(body: AuthoringBody) -> tuple[Mesh, np.ndarray]:
    """The crown's surface (own UVs) and its (MERIDIANS,) rim vertex indices."""
    centre, eye_z, head = _frame(body)
    top_z = float(head[:, 2].max())
    radius = top_z - centre[2]
    phi = np.linspace(-np.pi, np.pi, MERIDIANS, endpoint=False) + np.pi / MERIDIANS * 0
    rim_z = rim_height(phi, eye_z)
    # Meridians from the rim (s = 0) to near the top (s = 1), evenly in angle.
    s = np.linspace(0, 1, RINGS)
    rim_elev = np.arcsin(np.clip((rim_z - centre[2]) / radius, -0.95, 0.95))
    elev = rim_elev[None, :] + (np.radians(84) - rim_elev[None, :]) * s[:, None] ** 0.9
    flat = np.cos(elev)
    dirs = np.stack([flat * np.sin(phi)[None], -flat * np.cos(phi)[None], np.sin(elev)], -1)
    reach = _scalp_distance(dirs.reshape(-1, 3), centre, head).reshape(RINGS, MERIDIANS)
    # The lowest rings follow the skull under the occipital bulge and over the temples
    # (a narrow cone, no hull bridging the nape): the band sits on the head all round.
    low = 3
    reach[:low] = _scalp_distance(dirs[:low].reshape(-1, 3), centre, head, 5.0).reshape(
        low, MERIDIANS)  # fmt: skip
    for _ in range(6):  # a structured crown: smooth the reach around and up
        reach = 0.5 * reach + 0.25 * (np.roll(reach, 1, 1) + np.roll(reach, -1, 1))
        reach[1:-1] = 0.5 * reach[1:-1] + 0.25 * (reach[:-2] + reach[2:])
    points = centre + dirs * (reach + EASE)[..., None]
    pole = centre + np.array([0, 0, 1.0]) * (float(reach[-1].mean()) + EASE + 0.002)
    vertices = np.concatenate([points.reshape(-1, 3), pole[None]])
    grid = np.arange(RINGS * MERIDIANS).reshape(RINGS, MERIDIANS)
    quads = []
    for r in range(RINGS - 1):
        for m in range(MERIDIANS):
            n = (m + 1) % MERIDIANS
            quads.append([grid[r, m], grid[r, n], grid[r + 1, n], grid[r + 1, m]])
    top = len(vertices) - 1
    quads += [[grid[-1, m], grid[-1, (m + 1) % MERIDIANS], top, top] for m in range(MERIDIANS)]
    faces = np.asarray(quads, np.int32)
    # UVs: u around (unwrapped at the back), v from the rim (0.32) to the button (0.97).
    u_vertex = np.concatenate([np.tile((phi + np.pi) / (2 * np.pi), RINGS), [0.5]])
    v_vertex = np.concatenate([np.repeat(0.32 + 0.6 * s, MERIDIANS), [0.97]])
    fu = u_vertex[faces]
    wrapped = (fu.max(axis=1, keepdims=True) - fu) > 0.5
    fu = np.where(wrapped, fu + 1.0, fu)
    m_of_face = np.arange(len(faces)) % MERIDIANS
    pole_corner = faces == top
    fu[pole_corner] = ((m_of_face[:, None] + 0.5) / MERIDIANS * np.ones(4))[pole_corner]
    uv = np.stack([fu * 0.98 + 0.01, v_vertex[faces]], -1).reshape(-1, 2)
    face_uvs = np.arange(faces.size, dtype=np.int32).reshape(faces.shape)
    # Faces out: the winding that makes the front's normal point forward.
    probe = vertices[faces[MERIDIANS // 2 + (RINGS // 3) * MERIDIANS]]
    if np.cross(probe[2] - probe[0], probe[3] - probe[1]) @ (probe.mean(0) - centre) < 0:
        faces, uv = faces[:, ::-1].copy(), uv.reshape(-1, 4, 2)[:, ::-1].reshape(-1, 2)
    mesh = Mesh(vertices.astype(np.float32), faces, uv.astype(np.float32), face_uvs)
    return mesh, grid[0]


def button(body: AuthoringBody, mesh: Mesh, radius: float = 0.008) -> Mesh:
    """A cloth-covered dome on the crown's top (UVs at the crown's top row)."""
    pole = mesh.vertices[-1].astype(np.float64)
    rings, segments = 5, 12
    theta = np.linspace(0, np.pi / 2, rings)  # from the base up to the top
    a = np.linspace(0, 2 * np.pi, segments, endpoint=False)
    pts = [pole + [radius * np.cos(t) * np.cos(b), radius * np.cos(t) * np.sin(b),
                   0.45 * radius * np.sin(t) - 0.001] for t in theta for b in a]  # fmt: skip
    pts.append(pole + [0, 0, 0.45 * radius - 0.001])
    grid = np.arange(rings * segments).reshape(rings, segments)
    faces = [[grid[r, m], grid[r, (m + 1) % segments], grid[r + 1, (m + 1) % segments],
              grid[r + 1, m]] for r in range(rings - 1) for m in range(segments)]  # fmt: skip
    top = len(pts) - 1
    faces += [[grid[-1, m], grid[-1, (m + 1) % segments], top, top] for m in range(segments)]
    f = np.asarray(faces, np.int32)
    probe = np.asarray(pts)[f[segments]]  # a face of the second ring
    if np.cross(probe[2] - probe[0], probe[3] - probe[1]) @ (probe.mean(0) - pole) < 0:
        f = f[:, ::-1].copy()
    uv = np.tile([[0.5, 0.96]], (f.size, 1)).astype(np.float32)
    return Mesh(np.asarray(pts, np.float32), f, uv,
                np.arange(f.size, dtype=np.int32).reshape(f.shape))  # fmt: skip


def brim(body: AuthoringBody, crown_mesh: Mesh, rim: np.ndarray) -> Mesh:
    """The visor: a plate BRIM_THICK thick attached along the crown's front rim, reaching
    forward (not out round the head: a brim reaching out radially stood 2.7 cm past each
    side of the head, a bucket's), BRIM_REACH at the middle, its outline a rounded D as
    wide as the crown's front, curved down towards its sides, its outer edge a rounded
    half tube."""
    v = crown_mesh.vertices.astype(np.float64)
    centre, eye_z, _ = _frame(body)
    rel = v[rim] - centre
    phi = np.arctan2(rel[:, 0], -rel[:, 1])
    order = np.argsort(phi)
    front = order[np.abs(phi[order]) < np.radians(BRIM_SPAN)]
    inner = v[rim][front] + [0, 0, BRIM_SEAT]
    inward = centre[:2] - inner[:, :2]
    inward /= np.linalg.norm(inward, axis=1, keepdims=True)
    tuck = inner.copy()
    tuck[:, :2] += BRIM_TUCK * inward
    x_half = float(np.abs(inner[:, 0]).max())
    # The outline in plan: BRIM_REACH ahead of the rim's middle, rounding back to the
    # rim at the ends (a squarish D); each rim point reaches straight forward to it.
    forward = np.array([0.0, -1.0, 0.0])
    nose = float(inner[np.argmin(np.abs(inner[:, 0])), 1])
    outline = nose - BRIM_REACH * np.clip(1 - (inner[:, 0] / x_half) ** 2, 0, 1) ** 0.35
    reach = np.clip(inner[:, 1] - outline, 0, None)
    steps = np.linspace(0, 1, 8)
    rows = [tuck]  # under the crown, then from the crown's rim out to the edge
    for t in steps:
        pt = inner + (reach * t)[:, None] * forward
        # Curved down at the sides (pre-bent), tipped a little down at the front.
        pt[:, 2] -= 0.018 * (pt[:, 0] / x_half) ** 2 * t + 0.01 * t**1.5
        rows.append(pt)
    top_rows = np.stack(rows)  # (R, N, 3)
    bottom_rows = top_rows - [0, 0, BRIM_THICK]
    # The outer edge: a half tube from the top sheet round to the bottom sheet, bulging
    # out square to the outline in plan.
    tangent = np.gradient(top_rows[-1][:, :2], axis=0)
    edge_out = np.column_stack([-tangent[:, 1], tangent[:, 0], np.zeros(len(tangent))])
    edge_out /= np.maximum(np.linalg.norm(edge_out, axis=1, keepdims=True), 1e-12)
    edge_out *= np.where(edge_out[:, 1] > 0, -1.0, 1.0)[:, None]  # away from the head
    arc = []
    for a in np.linspace(0, np.pi, 6)[1:-1]:
        arc.append(top_rows[-1] + edge_out * (BRIM_THICK / 2) * np.sin(a)
                   - [0, 0, BRIM_THICK / 2 * (1 - np.cos(a))])  # fmt: skip
    sheets = [*top_rows, *arc, *bottom_rows[::-1]]
    grid = np.stack(sheets)  # (S, N, 3): top from the crown out, round the edge, back in
    n = grid.shape[1]
    index = np.arange(grid.shape[0] * n).reshape(grid.shape[0], n)
    faces = [[index[r, i], index[r, i + 1], index[r + 1, i + 1], index[r + 1, i]]
             for r in range(grid.shape[0] - 1) for i in range(n - 1)]  # fmt: skip
    # Close the two ends and the inner seam under the crown (hidden, but a closed solid).
    faces += [[index[-1, i], index[-1, i + 1], index[0, i + 1], index[0, i]] for i in range(n - 1)]
    # The two ends: each cross-section loop fanned to its middle (the plate is closed).
    points = grid.reshape(-1, 3)
    rows = grid.shape[0]
    ends: list[np.ndarray] = []
    for i, sign in ((0, 1), (n - 1, -1)):
        loop = index[:, i]
        middle = len(points) + len(ends)
        ends.append(points[loop].mean(axis=0))
        faces += [[loop[r], loop[(r + 1) % rows], middle, middle][::sign] for r in range(rows)]
    points = np.concatenate([points, ends])
    f = np.asarray(faces, np.int32)
    # One strip round the plate, so one winding: outward if the top sheet faces up.
    p0 = points[f[0]]
    if np.cross(p0[2] - p0[0], p0[3] - p0[1])[2] < 0:
        f = f[:, ::-1].copy()
    # UVs: u across the brim, v out to the edge (top) then back in (underside).
    u = (points[:, 0] + x_half) / (2 * x_half)
    r_of = np.concatenate([np.repeat(np.arange(grid.shape[0]), n), [0, 0]])
    tops = len(top_rows)
    out_frac = np.where(r_of < tops, np.clip(r_of - 1, 0, None) / (tops - 2), 1.0)
    uv_v = 0.02 + 0.24 * out_frac
    uv = np.stack([0.05 + 0.9 * u, uv_v], -1)[f.ravel()].astype(np.float32)
    corners = np.arange(f.size, dtype=np.int32).reshape(f.shape)
    return Mesh(points.astype(np.float32), f, uv, corners)


def cap_marks(body: AuthoringBody) -> list[Mark]:
    """Gore seams with top-stitching either side, an eyelet in each gore, the sweatband's
    stitching, and rows of stitching on the brim parallel to its edge."""
    marks = []
    v_rim, v_top = 0.32 + 0.045, 0.93
    for k in range(GORES):
        u = 0.01 + 0.98 * k / GORES
        line = np.stack([np.full(20, u), np.linspace(v_rim - 0.04, v_top, 20)], -1)
        marks.append(Mark("seam", line))
        marks += [Mark("stitch", line + [du, 0], 0.0007) for du in (-0.006, 0.006)]
        eye = np.array([u + 0.49 / GORES, 0.32 + 0.6 * 0.72])
        t = np.linspace(0, 2 * np.pi, 14)
        ring = eye + 0.007 * np.stack([np.cos(t), 2 * np.sin(t)], -1)
        marks += [Mark("stitch", ring, 0.0012), Mark("edge", ring * 0.5 + eye * 0.5)]
    around = np.stack([np.linspace(0, 1, 40), np.full(40, v_rim)], -1)
    marks += [Mark("stitch", around, 0.0007), Mark("seam", around - [0, 0.006])]
    for j in range(5):  # brim: rows following the outline (v runs out to the edge)
        v = 0.02 + 0.24 * (0.45 + 0.12 * j)
        row = np.stack([np.linspace(0.08, 0.92, 40), np.full(40, v)], -1)
        marks.append(Mark("stitch", row, 0.0008))
    return marks


def cap(body: AuthoringBody) -> Piece:
    """The whole cap, bound to the skin, with its texture layout (``Piece.layout``)."""
    crown_mesh, rim = crown(body)
    banded_crown = banded(crown_mesh, 0.014, 0.0015)
    pieces = [Mesh(banded_crown.vertices, banded_crown.faces, banded_crown.uvs,
                   banded_crown.face_uvs),  # fmt: skip
              button(body, crown_mesh), brim(body, crown_mesh, rim)]
    bound_pieces = [bound(body, m, body.skin_faces) for m in pieces]
    piece = join(bound_pieces)
    layout = Layout(UV_PER_METRE, tuple(cap_marks(body)), "cream",
                    extras={"panels": ["crown", "brim"]})  # fmt: skip
    return Piece(piece.mesh, piece.binding, layout)


# Hair under the crown keeps between the fitting's clearance and HAIR_UNDER off the scalp:
# the crown's inside is EASE out, and the fitting stacks a garment LAYER_GAP (1.5 mm) over
# the highest layer below it, so hair standing higher would push the whole cap up off the
# head (it sat 1.5 cm high over short hair).
HAIR_UNDER = 0.004
HAIR_FLOOR = 0.002  # m: fitting.CLEARANCE, the least any hair keeps off the skin
PRESS_BELOW = (0.025, 0.05)  # m below the rim: pressed fully down to, back to its own by


def pressed_hair(body: AuthoringBody, hair: Piece) -> Piece:
    """Scalp hair as it lies under the cap: every point under the crown, and down to
    ``PRESS_BELOW[0]`` under its rim (the band's skin), flattened along the skin's normal
    into ``HAIR_FLOOR``..``HAIR_UNDER`` off the scalp (a soft squash: the highest layers
    come down most, the order of layers is kept), easing back to the hair's own height by
    ``PRESS_BELOW[1]`` below the rim, so it shows below the band at the back and sides.
    Rebound to the skin. Heights are the fitting's: distances to the closest point of the
    skin's surface (a nearest vertex's tangent plane reads the sparse crown several
    millimetres low)."""
    from avatar.geometry import collision

    centre, eye_z, _ = _frame(body)
    v = hair.mesh.vertices.astype(np.float64)
    rel = v - centre
    below = rim_height(np.arctan2(rel[:, 0], -rel[:, 1]), eye_z) - v[:, 2]
    t = np.clip((below - PRESS_BELOW[0]) / (PRESS_BELOW[1] - PRESS_BELOW[0]), 0, 1)
    press = 1 - t * t * (3 - 2 * t)  # 1 under the crown, 0 from PRESS_BELOW[1] down
    base = body.base
    surface = collision.skin_surface(base.faces[base.face_groups["body"]])
    skin = body.vertices[:BODY_VERTICES]
    room = HAIR_UNDER - HAIR_FLOOR
    wanted = None
    for _ in range(2):  # the closest point moves a little as the hair comes down
        q = collision.query(skin, surface, v, k=4)
        off = q.distance.astype(np.float64)
        if wanted is None:  # each point's pressed height, from its own height
            squashed = HAIR_FLOOR + room * np.tanh(np.maximum(off - HAIR_FLOOR, 0) / room)
            wanted = np.minimum(off, press * squashed + (1 - press) * off)
        v = v + np.minimum(wanted - off, 0)[:, None] * q.normal
    mesh = Mesh(v.astype(np.float32), hair.mesh.faces, hair.mesh.uvs, hair.mesh.face_uvs)
    return bound(body, mesh, body.skin_faces)


__all__ = ["brim", "button", "cap", "cap_marks", "crown", "pressed_hair", "rim_height"]

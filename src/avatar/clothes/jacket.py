"""A jacket's construction: its surface unrolled into the panels a jacket is sewn from,
and the seams, zip, pockets, bands and topstitching painted where a tailor puts them.

The jacket's geometry is the open top cut from ``helper-tights`` (``builtin``); this
module only gives it its own UV layout and a ``tailored.Layout`` (as jeans have), so its
maps carry the construction at 2K instead of a tiling leather that read as a plain shiny
blouse. Panels (``tailoring.Panels`` charts, u: metres across, z: metres up):

- four body panels (left/right front, left/right back) unrolled round the body's
  vertical axis (``tailoring.panel_coordinates``): their shared edges are the side seams,
  the shoulder seams and the centre-back seam; each front's inner edge is the opening;
- one panel per sleeve unrolled round the arm's chain (shoulder, elbow, wrist): u the
  arc from the arm's top towards its front, z the negative distance down the arm; cut
  (its seam) underneath; where it meets the body panels is the armhole seam.

Two rows in one texture (body panels above, sleeves below) keep ~1.3 px a millimetre at
2K (one row of charts gave 1.0).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from avatar.clothes import tailoring
from avatar.clothes.authoring import AuthoringBody, Piece
from avatar.clothes.tailoring import Panel
from avatar.looks.tailored import Layout, Mark
from avatar.mesh import Mesh, vertex_normals

PANELS = (*tailoring.TROUSER_PANELS,  # left front, left back, right front, right back
          Panel("left sleeve", 1, False), Panel("right sleeve", -1, False))
BODY, SLEEVES = (0, 1, 2, 3), (4, 5)
ZIP_TOOTH = 0.0035  # m between zip teeth
COLLAR_REACH = 0.075  # m round the neck from the front opening (or centre back) to the shoulder
# Topstitching in a mid-grey thread and bright nickel teeth: in charcoal (0.06) on black
# leather (0.03) the stitching was 1.25x the leather's lightness in the map and vanished in
# a render, and the zip read as a dull line; grey thread is what leather jackets use.
THREAD = (0.2, 0.2, 0.205)
ZIP_METAL = (0.75, 0.75, 0.77)  # nickel zip teeth and pulls (linear RGB)
ALLOWANCE = 0.6  # strength of the ridge a pressed seam allowance raises under the leather


def _unwrapped(angle: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """(F, C) corner angles brought within pi of their face's angle (F,): a face across a
    chart's cut keeps its corners together instead of spanning the whole chart."""
    return centre[:, None] + np.mod(angle - centre[:, None] + np.pi, 2 * np.pi) - np.pi


class JacketPanels(tailoring.Panels):
    """``tailoring.Panels`` for a jacket: four body panels in the top row, the two
    sleeves in the row under it (see the module docstring)."""

    def __init__(self, body: AuthoringBody, mesh: Mesh):
        self.mesh, self.panels = mesh, PANELS
        v = mesh.vertices.astype(np.float64)
        f = mesh.faces
        centre = v[f].mean(axis=1)
        corners = v[f]
        side = np.where(centre[:, 0] >= 0, 1, -1)
        sleeve = _on_sleeve(body, centre)
        axis = self.axis = tailoring.body_axis(body.marks)
        back = centre[:, 1] > axis(side, centre[:, 2])[:, 1]
        # Over the shoulders front and back meet along the ridge (the cloth's highest line
        # at each distance out from the neck), not the hips' plane: split there, the
        # shoulder seam zig-zagged across the front of the shoulder.
        high = (centre[:, 2] > body.marks.shoulder[0, 2] - 0.03) & (np.abs(centre[:, 0]) > 0.07)
        back = np.where(high, centre[:, 1] > _ridge_y(v, np.abs(centre[:, 0])), back)
        c = f.shape[1]
        body_uz = tailoring.panel_coordinates(corners.reshape(-1, 3), np.repeat(side, c),
                                              np.repeat(back, c), axis).reshape(f.shape + (2,))
        # Sleeves: the angle round the arm from its top, towards the front.
        arm_c, _, _ = _arm_angle(body, centre, side)
        arm, arm_r, down = _arm_angle(body, corners.reshape(-1, 3), np.repeat(side, f.shape[1]))
        arm = _unwrapped(arm.reshape(f.shape), arm_c)
        sleeve_uz = np.stack([arm * arm_r.reshape(f.shape), -down.reshape(f.shape)], -1)
        self.corner_uz = np.where(sleeve[:, None, None], sleeve_uz, body_uz)
        body_panel = np.where(side > 0, 0, 2) + back
        self.face_panel = np.where(sleeve, np.where(side > 0, 4, 5), body_panel)
        self.lo = np.array([self.corner_uz[self.face_panel == k].reshape(-1, 2).min(0)
                            for k in range(len(PANELS))])  # fmt: skip
        self.hi = np.array([self.corner_uz[self.face_panel == k].reshape(-1, 2).max(0)
                            for k in range(len(PANELS))])  # fmt: skip
        self._lay_out_rows()

    def _lay_out_rows(self) -> None:
        """Body charts side by side in the top row, sleeves in the row under it."""
        gap = tailoring.GAP
        widths = self.hi[:, 0] - self.lo[:, 0] + gap
        heights = self.hi[:, 1] - self.lo[:, 1] + gap
        rows = (np.array(BODY), np.array(SLEEVES))
        row_height = [float(heights[r].max()) for r in rows]
        self.scale = 1.0 / max(float(widths[rows[0]].sum()), float(widths[rows[1]].sum()),
                               sum(row_height))  # fmt: skip
        self.u0 = np.zeros(len(PANELS))
        self.z_lo = np.zeros(len(PANELS))  # each chart's own vertical offset
        base = 0.0
        for r, tall in zip(rows[::-1], row_height[::-1], strict=True):  # sleeves at v = 0
            starts = np.concatenate([[0], np.cumsum(widths[r])[:-1]])
            self.u0[r] = self.lo[r, 0] - gap / 2 - starts
            self.z_lo[r] = self.lo[r, 1] - gap / 2 - base
            base += tall
        self.z0 = 0.0

    def uv(self, panel: int, uz: np.ndarray) -> np.ndarray:
        uz = np.atleast_2d(np.asarray(uz, np.float64))
        return np.stack([(uz[:, 0] - self.u0[panel]) * self.scale,
                         (uz[:, 1] - self.z_lo[panel]) * self.scale], -1)  # fmt: skip

    def top(self, panel: int, u: np.ndarray) -> np.ndarray:
        """(N,) z of a chart's top edge at u (the highest corner within 1.5 cm)."""
        uz = self.corner_uz[self.face_panel == panel].reshape(-1, 2)
        out = np.empty(len(u))
        for i, x in enumerate(np.atleast_1d(u)):
            near = np.abs(uz[:, 0] - x) < 0.015
            out[i] = uz[near, 1].max() if near.any() else self.hi[panel, 1]
        return out


def _ridge_y(v: np.ndarray, across: np.ndarray, step: float = 0.01) -> np.ndarray:
    """(N,) y of the cloth's highest vertex within ``step`` m of each distance ``across``
    (N,) from the midline (the ridge over the shoulders)."""
    bins = np.round(np.abs(v[:, 0]) / step).astype(int)
    out = np.empty(len(across))
    for i, b in enumerate(np.round(across / step).astype(int)):
        near = np.abs(bins - b) <= 1
        out[i] = v[near][np.argmax(v[near, 2]), 1] if near.any() else 0.0
    return out


def _on_sleeve(body: AuthoringBody, centre: np.ndarray) -> np.ndarray:
    """(F,) bool: faces of a sleeve: past the plane through the shoulder joint across the
    upper arm, within ARMHOLE_RADIUS of the arm's chain (the armhole). The skin's part
    labels follow the bones' weights: the shoulder blades count as arm."""
    side = np.where(centre[:, 0] >= 0, 1, -1)
    down, radial, _ = _arm_frame(body, centre, side)
    return (down > 0.0) & (np.linalg.norm(radial, axis=1) < ARMHOLE_RADIUS)


ARMHOLE_RADIUS = 0.085  # m round the arm's chain a sleeve reaches (the armpit lies further)


def _arm_frame(body: AuthoringBody, points: np.ndarray, side: np.ndarray):
    """(distance down the arm (N,), radial offset (N, 3), axis direction (N, 3)) of points
    from their own arm's chain (shoulder, elbow, wrist)."""
    marks = body.marks
    down = np.zeros(len(points))
    radial = np.zeros_like(points)
    direction = np.zeros_like(points)
    for s in (0, 1):
        mine = side == (1 if s == 0 else -1)
        a, b, c = marks.shoulder[s], marks.elbow[s], marks.wrist[s]
        p = points[mine]
        upper_len = np.linalg.norm(b - a)
        t1 = np.clip((p - a) @ (b - a) / upper_len**2, -0.5, 1.0)
        t2 = np.clip((p - b) @ (c - b) / np.linalg.norm(c - b) ** 2, 0.0, 1.5)
        lower = t1 >= 1.0  # past the elbow: on the forearm's segment
        foot = np.where(lower[:, None], b + t2[:, None] * (c - b), a + t1[:, None] * (b - a))
        down[mine] = np.where(lower, upper_len + t2 * np.linalg.norm(c - b), t1 * upper_len)
        d = np.where(lower[:, None], (c - b) / np.linalg.norm(c - b), (b - a) / upper_len)
        radial[mine] = p - foot
        direction[mine] = d
    return down, radial, direction


def _arm_angle(body: AuthoringBody, points: np.ndarray, side: np.ndarray):
    """(angle round the arm from its top, towards the front, in (-pi, pi] (N,), radius
    (N,), distance down the arm (N,))."""
    down, radial, d = _arm_frame(body, points, side)
    up = np.array([0.0, 0.0, 1.0]) - d[:, 2:3] * d
    up /= np.linalg.norm(up, axis=1, keepdims=True)
    front = np.cross(d, up) * np.where(side > 0, 1.0, -1.0)[:, None]  # -y on both arms
    angle = np.arctan2(np.einsum("nd,nd->n", radial, front), np.einsum("nd,nd->n", radial, up))
    return angle, np.linalg.norm(radial, axis=1), down


# ---------------------------------------------------------------------------- marks


def _line(panels: JacketPanels, k: int, u, z) -> np.ndarray:
    u, z = np.broadcast_arrays(np.atleast_1d(u).astype(float), np.atleast_1d(z).astype(float))
    return panels.uv(k, np.stack([u, z], -1))


def _edge(panels: JacketPanels, k: int, z: np.ndarray, outer: bool) -> np.ndarray:
    return panels.edge(k, np.atleast_1d(z), outer)


def _across(panels: JacketPanels, k: int, z: float, inset: float = 0.0) -> np.ndarray:
    lo = _edge(panels, k, np.array([z]), False)[0] + inset
    hi = _edge(panels, k, np.array([z]), True)[0] - inset
    return _line(panels, k, np.linspace(lo, hi, 24), z)


def _box(centre: np.ndarray, width: float, height: float, tilt: float) -> np.ndarray:
    """(4, 2) corners of a ``width`` x ``height`` rectangle round ``centre``, tilted."""
    c, s = np.cos(tilt), np.sin(tilt)
    corners = np.array([[-1, 1], [1, 1], [1, -1], [-1, -1]]) * [width / 2, height / 2]
    return centre + corners @ np.array([[c, s], [-s, c]])


def topstitched_seams(panels: JacketPanels, offset: float = 0.005, keep=None) -> list[Mark]:
    """The panels' seams (``Panels.seams``, those ``keep`` picks) and a row of topstitching
    ``offset`` m beside each, on the panel's own side (leather seams are pressed open and
    topstitched)."""
    seams = panels.seams(keep)
    if not seams:
        return []
    segments = seams[0].points  # (M, 2, 2) uv, both sides of every seam
    uv_faces = np.concatenate([panels.uv(k, panels.corner_uz[i].mean(0, keepdims=True))
                               for i, k in enumerate(panels.face_panel)])  # fmt: skip
    from scipy.spatial import cKDTree

    mid = segments.mean(axis=1)
    _, inside = cKDTree(uv_faces).query(mid)  # the face each side belongs to
    along = segments[:, 1] - segments[:, 0]
    normal = np.stack([-along[:, 1], along[:, 0]], -1)
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-12)
    towards = np.sign(np.einsum("md,md->m", uv_faces[inside] - mid, normal))[:, None]
    shift = (towards * normal * offset * panels.scale)[:, None, :]
    # The seam allowance folded under the topstitching: a ridge between seam and stitches.
    ridge = Mark("fold", segments + 0.5 * shift, 0.0025, ALLOWANCE)
    return [*seams, ridge, Mark("stitch", segments + shift, 0.0008)]


def jacket_marks(panels: JacketPanels, marks) -> list[Mark]:
    """A zip-front jacket: topstitched side, shoulder, centre-back, armhole and underarm
    seams; a zip down each front's opening; two lower welt pockets and a chest pocket; a
    back yoke; a hem band, cuffs and a collar band, each sewn on and topstitched."""
    # The armhole, side and shoulder seams are drawn as the smooth lines their faces'
    # staircase follows (1-4 cm faces: drawn along them they zig-zagged), each in the
    # charts of both panels it joins (each shows it where its faces are).
    out = topstitched_seams(panels, keep=lambda fa, fb: ~_drawn_along_lines(panels, fa, fb))
    for k in SLEEVES:
        out += _armhole_along(panels, k, smooth_loop(armhole_ring(panels, k)))
    for side in (1, -1):
        for path in seam_paths(panels, side):
            out += _seam_along(panels, smooth_path(path), side)
    for k in BODY:
        hem = float(panels.lo[k, 1])
        band = hem + 0.045  # the hem band's seam
        out += [Mark("seam", _across(panels, k, band)),
                Mark("stitch", _across(panels, k, band + 0.005), 0.0008),
                Mark("stitch", _across(panels, k, hem + 0.008), 0.0008)]  # fmt: skip
        # The collar band: sewn on 4 cm below the neckline, topstitched both sides, round
        # the neck only (COLLAR_REACH m from the front opening or the centre back), along
        # the neckline smoothed (it steps with the faces).
        start = panels.lo[k, 0] + 0.004
        u = np.linspace(start, start + COLLAR_REACH, 24)
        top = panels.top(k, u)
        top = np.polyval(np.polyfit(u, top, 2), u)
        out += [Mark("seam", _line(panels, k, u, top - 0.04)),
                Mark("stitch", _line(panels, k, u, top - 0.035), 0.0008),
                Mark("stitch", _line(panels, k, u, top - 0.007), 0.0008)]
        inner = lambda z, k=k: _edge(panels, k, np.array([z]), False)[0]  # noqa: E731
        outer = lambda z, k=k: _edge(panels, k, np.array([z]), True)[0]  # noqa: E731
        if PANELS[k].back:
            yoke = marks.chest_z + 0.1
            out += [Mark("seam", _across(panels, k, yoke)),
                    Mark("stitch", _across(panels, k, yoke - 0.005), 0.0008)]
            continue
        out += _zip(panels, k, band, float(top[0]))
        # Welt pockets: a raised lip 2.2 cm tall, slanting down towards the side seam.
        z = band + 0.09
        centre = np.array([inner(z) + 0.5 * (outer(z) - inner(z)) + 0.01, z])
        out += _welt(panels, k, centre, 0.14, 0.022, -0.2)
        if PANELS[k].side > 0:  # the chest pocket, wearer's left, a hand below the shoulder
            z = marks.shoulder[0, 2] - 0.13
            centre = np.array([inner(z) + 0.075, z])
            out += _welt(panels, k, centre, 0.1, 0.016, 0.12)
    for k in SLEEVES:  # cuffs: a band 5 cm deep at the wrist, topstitched; the underarm seam
        end = float(panels.lo[k, 1])
        out += [Mark("seam", _across(panels, k, end + 0.05)),
                Mark("stitch", _across(panels, k, end + 0.055), 0.0008),
                Mark("stitch", _across(panels, k, end + 0.008), 0.0008)]  # fmt: skip
        down = np.linspace(end + 0.01, float(panels.hi[k, 1]) - 0.03, 60)
        out += [Mark("stitch", _line(panels, k, _edge(panels, k, down, outer) + d, down),
                     0.0008)
                for outer, d in ((False, 0.005), (True, -0.005))]  # fmt: skip
    return out


def _drawn_along_lines(panels: JacketPanels, fa: np.ndarray, fb: np.ndarray) -> np.ndarray:
    """(M,) bool: face pairs across a seam drawn along a smooth line instead: a front/back
    seam of one side (side, shoulder seams) or the armhole (sleeve and body)."""
    pa, pb = panels.face_panel[fa], panels.face_panel[fb]
    body_a, body_b = pa < SLEEVES[0], pb < SLEEVES[0]
    return (body_a & body_b & (pa // 2 == pb // 2) & (pa != pb)) | (body_a != body_b)


def seam_paths(panels: JacketPanels, side: int) -> list[np.ndarray]:
    """The (N, 3) vertex paths along which side's front and back panels meet, one per
    seam (the side seam, the shoulder seam), each ordered from one end to the other."""
    front = 0 if side > 0 else 2
    return _meeting_paths(panels, (front,), (front + 1,))


def armhole_ring(panels: JacketPanels, k: int) -> np.ndarray:
    """(N, 3) the vertex loop along which sleeve k meets the body panels, in order."""
    body = (0, 1) if PANELS[k].side > 0 else (2, 3)
    return max(_meeting_paths(panels, (k,), body), key=len)


def _meeting_paths(panels: JacketPanels, one: tuple, other: tuple) -> list[np.ndarray]:
    """(N, 3) vertex paths along the edges between faces of panels ``one`` and ``other``."""
    f = panels.mesh.faces
    a, b = f.reshape(-1), np.roll(f, -1, axis=1).reshape(-1)
    face = np.repeat(np.arange(len(f)), f.shape[1])
    in_one = np.isin(panels.face_panel[face], one)
    mine = in_one | np.isin(panels.face_panel[face], other)
    key = np.minimum(a, b).astype(np.int64) * len(panels.mesh.vertices) + np.maximum(a, b)
    keys, inverse = np.unique(key[mine], return_inverse=True)
    both = np.zeros((len(keys), 2), bool)
    both[inverse, (~in_one[mine]).astype(int)] = True
    edges = np.stack(np.divmod(keys[both.all(axis=1)], len(panels.mesh.vertices)), -1)
    paths, left = [], {tuple(e) for e in edges.tolist()}
    neighbours: dict[int, list[int]] = {}
    for i, j in left:
        neighbours.setdefault(i, []).append(j)
        neighbours.setdefault(j, []).append(i)
    seen: set[int] = set()
    for start in sorted(neighbours, key=lambda v: len(neighbours[v])):  # ends first
        if start in seen:
            continue
        path = [start]
        seen.add(start)
        while nxt := [n for n in neighbours[path[-1]] if n not in seen]:
            path.append(nxt[0])
            seen.add(nxt[0])
        if len(path) > 2:
            paths.append(panels.mesh.vertices[np.array(path)].astype(np.float64))
    return paths


def smooth_path(points: np.ndarray, step: float = 0.004) -> np.ndarray:
    """(M, 3) the line a staircase vertex path (N, 3) follows, every ``step`` m from one
    end to the other: a line fitted to its points over SEAM_SMOOTH m along the seam's chord,
    each weighted by how far it runs along it (a sideways step, a face wide, adds
    nothing; blurred along the path it still bent the line by a cm)."""
    run = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])
    fine = np.stack([np.interp(np.arange(0.0, run[-1], 0.001), run, points[:, i])
                     for i in range(3)], -1)  # fmt: skip
    chord = (points[-1] - points[0]) / np.linalg.norm(points[-1] - points[0])
    t = fine @ chord
    along = np.abs(np.gradient(t)) + 1e-5
    at = np.linspace(t[0], t[-1], max(int(abs(t[-1] - t[0]) / step), 2))
    apart = t[None] - at[:, None]
    w = np.exp(-0.5 * (apart / SEAM_SMOOTH) ** 2) * along[None]
    # A line fitted locally, not a mean: a mean's window is one-sided at an end and
    # pulled the seam's ends 1.5 cm short of the armhole, hem and collar.
    s0, s1, s2 = w.sum(axis=1), (w * apart).sum(axis=1), (w * apart**2).sum(axis=1)
    mean, slope = w @ fine, (w * apart) @ fine
    return (s2[:, None] * mean - s1[:, None] * slope) / (s0 * s2 - s1**2)[:, None]


def smooth_loop(points: np.ndarray, step: float = 0.004) -> np.ndarray:
    """(M, 3) the closed line a staircase vertex loop (N, 3) follows (its first point
    repeated last): as ``smooth_path``, averaged over SEAM_SMOOTH m round the loop's
    angle in its plane, each point weighted by how far it turns it."""
    closed = np.concatenate([points, points[:1]])
    run = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(closed, axis=0), axis=1))])
    fine = np.stack([np.interp(np.arange(0.0, run[-1], 0.001), run, closed[:, i])
                     for i in range(3)], -1)  # fmt: skip
    centre = fine.mean(axis=0)
    basis = np.linalg.svd(fine - centre, full_matrices=False)[2][:2]
    flat = (fine - centre) @ basis.T
    angle = np.unwrap(np.arctan2(flat[:, 1], flat[:, 0]))
    turn = np.abs(np.gradient(angle)) + 1e-5
    sigma = SEAM_SMOOTH / float(np.linalg.norm(flat, axis=1).mean())
    at = angle[0] + np.sign(angle[-1] - angle[0]) * np.linspace(0, 2 * np.pi, int(run[-1] / step))
    apart = np.mod(at[:, None] - angle[None] + np.pi, 2 * np.pi) - np.pi
    w = np.exp(-0.5 * (apart / sigma) ** 2) * turn[None]
    return (w @ fine) / w.sum(axis=1, keepdims=True)


def _armhole_along(panels: JacketPanels, k: int, line: np.ndarray,
                   offset: float = 0.005) -> list[Mark]:  # fmt: skip
    """Sleeve k's armhole seam along a closed 3D line (M, 3), its allowance's ridge and
    topstitching ``offset`` m towards the sleeve, drawn in the sleeve's chart and the body
    panels' both (each shows it where its faces are: under the arm the sleeve's chart
    flares, drawn there alone it had to stop 8 cm short)."""
    across = _across_seam(panels, line)
    plane = np.linalg.svd(line - line.mean(axis=0), full_matrices=False)[2][2]
    towards_arm = plane * np.sign(plane[0] * PANELS[k].side)  # the arm runs out in x
    across *= np.sign(across @ towards_arm)[:, None]
    out = []
    for kind, d, width, strength in (("seam", 0.0, 0.002, 1.0),
                                     ("fold", 0.5, 0.0025, ALLOWANCE),
                                     ("stitch", 1.0, 0.0008, 1.0)):  # fmt: skip
        points = line + across * d * offset
        for chart in (k, *((0, 1) if PANELS[k].side > 0 else (2, 3))):
            segments = _in_chart_segments(panels, chart, points)
            if len(segments):
                out.append(Mark(kind, segments, width, strength))
    return out


def _across_seam(panels: JacketPanels, line: np.ndarray) -> np.ndarray:
    """(M, 3) unit directions across a line (M, 3) on the jacket, in its surface."""
    from scipy.spatial import cKDTree

    v = panels.mesh.vertices.astype(np.float64)
    _, nearest = cKDTree(v).query(line)
    normal = vertex_normals(v, panels.mesh.faces)[nearest]
    across = np.cross(np.gradient(line, axis=0), normal)
    return across / np.maximum(np.linalg.norm(across, axis=1, keepdims=True), 1e-12)


def _seam_along(panels: JacketPanels, line: np.ndarray, side: int,
                offset: float = 0.005) -> list[Mark]:  # fmt: skip
    """A pressed-open seam along a 3D line (M, 3) between side's front and back: the seam,
    its allowance's ridges and topstitching ``offset`` m either side, each drawn in both
    charts where that chart's faces are."""
    across = _across_seam(panels, line)
    out = []
    for kind, d, width, strength in (("seam", 0.0, 0.002, 1.0),
                                     ("fold", 0.5, 0.0025, ALLOWANCE),
                                     ("fold", -0.5, 0.0025, ALLOWANCE),
                                     ("stitch", 1.0, 0.0008, 1.0),
                                     ("stitch", -1.0, 0.0008, 1.0)):  # fmt: skip
        points = line + across * d * offset
        for k in (0, 1) if side > 0 else (2, 3):
            segments = _in_chart_segments(panels, k, points)
            if len(segments):
                out.append(Mark(kind, segments, width, strength))
    return out


def _in_chart_segments(panels: JacketPanels, k: int, points: np.ndarray) -> np.ndarray:
    """(S, 2, 2) uv segments of a 3D polyline (M, 3) mapped into chart k through the faces
    it lies on (``_chart_points``): those with an end on one of chart k's faces (the other
    end mapped through the same face's plane, a few mm past the edge), less any across a
    sleeve's cut (its two sides lie a chart apart)."""
    uz, inside = _chart_points(panels, k, points)
    step = np.linalg.norm(np.diff(points, axis=0), axis=1)
    jump = np.linalg.norm(np.diff(uz, axis=0), axis=1) > 2 * step
    pick = np.flatnonzero((inside[:-1] | inside[1:]) & ~jump)
    uv = panels.uv(k, uz)
    return np.stack([uv[pick], uv[pick + 1]], 1)


def _chart_points(panels: JacketPanels, k: int, points: np.ndarray, near: int = 8):
    """((M, 2) uz, (M,) bool inside) of 3D points near the jacket in chart k: each point
    dropped onto the plane of the nearest of chart k's triangles it falls in (or nearly:
    the one whose barycentric weights are least negative) and its weights applied to the
    corners' chart coordinates. Not ``panel_coordinates`` of the point: a line smoothed
    in 3D leaves the surface by a few mm (the waist curves in), which moved it off both
    charts."""
    from scipy.spatial import cKDTree

    v = panels.mesh.vertices.astype(np.float64)
    mine = np.flatnonzero(panels.face_panel == k)
    quads, uz = panels.mesh.faces[mine], panels.corner_uz[mine]
    tri, tri_uz = (np.concatenate([q[:, [0, 1, 2]], q[:, [0, 2, 3]]]) for q in (quads, uz))
    corner = v[tri]  # (T, 3, 3)
    _, cand = cKDTree(corner.mean(axis=1)).query(points, min(near, len(tri)))
    a = corner[cand, 0]
    e1, e2 = corner[cand, 1] - a, corner[cand, 2] - a
    d = points[:, None] - a  # (M, K, 3)
    g11, g12, g22 = (np.einsum("mkd,mkd->mk", x, y) for x, y in ((e1, e1), (e1, e2), (e2, e2)))
    b1, b2 = np.einsum("mkd,mkd->mk", d, e1), np.einsum("mkd,mkd->mk", d, e2)
    det = np.maximum(g11 * g22 - g12**2, 1e-18)
    s, t = (g22 * b1 - g12 * b2) / det, (g11 * b2 - g12 * b1) / det
    weight = np.stack([1 - s - t, s, t], -1)  # (M, K, 3)
    gap = np.linalg.norm(d - s[..., None] * e1 - t[..., None] * e2, axis=-1)
    score = weight.min(axis=-1) - (gap > 0.01)  # off the plane by a cm: another layer
    best = np.argmax(score, axis=1)
    rows = np.arange(len(points))
    out = np.einsum("mc,mcd->md", weight[rows, best], tri_uz[cand[rows, best]])
    inside = score[rows, best] >= 0
    if k in SLEEVES:  # not where the sleeve's top row squashes the cloth under the arm
        # (2 cm of it in 2 mm): a line drawn there showed as a smear a face away.
        fair = _stretch(corner, tri_uz)[cand[rows, best]]
        inside &= (fair > 0.25) & (fair < 4.0)
    return out, inside


def _stretch(corner: np.ndarray, uz: np.ndarray) -> np.ndarray:
    """(T,) how much each triangle (T, 3, 3 corners; T, 3, 2 chart points) is stretched
    the most in its chart, as a ratio under 1 (squashed) or over (stretched): the one of
    its chart map's singular values furthest from 1."""
    e1, e2 = corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0]
    x = e1 / np.maximum(np.linalg.norm(e1, axis=1, keepdims=True), 1e-12)
    y = e2 - np.einsum("td,td->t", e2, x)[:, None] * x
    y /= np.maximum(np.linalg.norm(y, axis=1, keepdims=True), 1e-12)
    flat = np.stack([np.stack([np.einsum("td,td->t", e, x), np.einsum("td,td->t", e, y)], -1)
                     for e in (e1, e2)], -1)  # (T, 2, 2): columns the edges in-plane
    chart = np.stack([uz[:, 1] - uz[:, 0], uz[:, 2] - uz[:, 0]], -1)
    det = flat[:, 0, 0] * flat[:, 1, 1] - flat[:, 0, 1] * flat[:, 1, 0]
    flat_inv = np.stack([np.stack([flat[:, 1, 1], -flat[:, 0, 1]], -1),
                         np.stack([-flat[:, 1, 0], flat[:, 0, 0]], -1)], -2)
    jac = chart @ (flat_inv / np.where(np.abs(det) > 1e-12, det, 1e-12)[:, None, None])
    sv = np.linalg.svd(jac, compute_uv=False)
    return np.where(sv[:, 1] < 1 / sv[:, 0], sv[:, 1], sv[:, 0])


SEAM_SMOOTH = 0.02  # m along a seam (side, shoulder, armhole) its staircase is blurred over


def _zip(panels: JacketPanels, k: int, bottom: float, top: float) -> list[Mark]:
    """Half a zip along a front's opening: the tape's edge, a row of metal teeth 3 mm in
    and the tape's topstitching 1.2 cm in; the pull on the wearer's left."""
    z = np.linspace(bottom - 0.04, top - 0.01, 80)
    edge = _edge(panels, k, z, False)
    edge = np.polyval(np.polyfit(z, edge, 3), z)  # one sweep (the faces step)
    out = [Mark("edge", _line(panels, k, edge + 0.007, z)),
           Mark("stitch", _line(panels, k, edge + 0.012, z), 0.0008)]
    teeth = np.arange(z[0], z[-1], ZIP_TOOTH)
    at = np.interp(teeth, z, edge) + 0.003
    out += [Mark("rivet", _line(panels, k, u, t), 0.0024) for u, t in zip(at, teeth, strict=True)]
    if PANELS[k].side > 0:
        pull = np.array([[at[-1] + 0.002, top - 0.03], [at[-1] + 0.004, top - 0.065]])
        out.append(Mark("stitch", panels.uv(k, pull), 0.006))
        out.append(Mark("rivet", panels.uv(k, pull[:1]), 0.009))
    return out


def _welt(panels: JacketPanels, k: int, centre: np.ndarray, width: float, height: float,
          tilt: float) -> list[Mark]:  # fmt: skip
    """A welt pocket: a raised lip, its opening's edge along the top, stitched round."""
    box = _box(centre, width, height, tilt)
    inset = _box(centre, width - 0.006, height - 0.006, tilt)
    opening = box[[0, 1]]
    # The pocket bag under the cloth: a faint outline below the welt.
    bag = _box(centre - [0, 0.07], width + 0.01, 0.13, tilt)
    return [Mark("patch", panels.uv(k, box)),
            Mark("edge", panels.uv(k, opening)),
            Mark("stitch", panels.uv(k, np.concatenate([inset, inset[:1]])), 0.0008),
            Mark("fold", panels.uv(k, np.concatenate([bag[1:], bag[:1]])), 0.003, 0.25)]


def tailored(body: AuthoringBody, piece: Piece) -> Piece:
    """The jacket ``piece`` (cut, banded and bound: ``builtin``) with panel UVs and its
    construction layout; its vertices, faces and binding unchanged."""
    panels = JacketPanels(body, piece.mesh)
    layout = Layout(panels.scale, tuple(jacket_marks(panels, body.marks)), THREAD, ZIP_METAL,
                    extras={"panels": [p.name for p in PANELS]})  # fmt: skip
    return replace(piece, mesh=panels.textured(), layout=layout)


__all__ = ["PANELS", "JacketPanels", "armhole_ring", "jacket_marks", "seam_paths",
           "smooth_loop", "smooth_path", "tailored", "topstitched_seams"]  # fmt: skip

"""Tailored bottoms: jeans, trousers and a skirt cut as cloth panels, with their seams,
pockets, waistband, belt loops and hems.

A pair of trousers is sewn from four panels (left and right, front and back), a skirt from
two (front and back). ``Panels`` unrolls a garment surface into those charts: each face goes
to the panel its centre lies on, and each corner gets panel coordinates (u: metres around
the leg's axis, or the body's for a skirt, 0 at the panel's middle and positive towards its
outer side; z: height), laid side by side in one texture (``looks.tailored``). The panel
edges are where the garment's real seams run (outseam, inseam, centre seam), so they are
painted there, and everything else (pockets, fly, yoke, creases, folds, worn dye) is placed
in panel coordinates from the garment's own extent, so it lands where a tailor puts it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from avatar.body.model import BODY_VERTICES
from avatar.clothes.authoring import AuthoringBody, Piece, bound, join
from avatar.clothes.regions import Landmarks
from avatar.geometry.shell import boundary_edges
from avatar.looks.tailored import Layout, Mark
from avatar.mesh import Mesh

GAP = 0.03  # m of texture between charts (padding against bleeding)
Axis = Callable[[np.ndarray, np.ndarray], np.ndarray]  # (side (N,), z (N,)) -> (N, 2) xy


@dataclass(frozen=True)
class Panel:
    name: str
    side: int  # +1 left (x > 0), -1 right, 0 a skirt's (both)
    back: bool


TROUSER_PANELS = (Panel("left front", 1, False), Panel("left back", 1, True),
                  Panel("right front", -1, False), Panel("right back", -1, True))  # fmt: skip
SKIRT_PANELS = (Panel("front", 0, False), Panel("back", 0, True))


def leg_axis(marks: Landmarks) -> Axis:
    """Each leg's axis (hip, knee, ankle joints; vertical above the hip) at heights z."""
    chains = []
    for s in (0, 1):
        joints = np.stack([marks.ankle[s], marks.knee[s], marks.hip[s]])
        chains.append(joints)

    def axis(side: np.ndarray, z: np.ndarray) -> np.ndarray:
        out = np.empty((len(z), 2))
        for s, joints in enumerate(chains):
            m = side == (1 if s == 0 else -1)
            for k in (0, 1):
                out[m, k] = np.interp(z[m], joints[:, 2], joints[:, k])
        return out

    return axis


def body_axis(marks: Landmarks) -> Axis:
    """The vertical axis through the middle of the hips (a skirt's)."""
    centre = marks.hip[:, :2].mean(axis=0)
    return lambda side, z: np.tile(centre, (len(z), 1))


def panel_coordinates(points: np.ndarray, side: np.ndarray, back: np.ndarray,
                      axis: Axis) -> np.ndarray:  # fmt: skip
    """(N, 2) (u, z) metres of points (N, 3) on panels of ``side`` (N,) and ``back`` (N,)."""
    a = axis(side, points[:, 2])
    outward = np.where(side < 0, -1.0, 1.0)
    dx = (points[:, 0] - a[:, 0]) * outward
    forward = (a[:, 1] - points[:, 1]) * np.where(back, -1.0, 1.0)
    theta = np.arctan2(dx, forward)
    return np.stack([theta * np.hypot(dx, forward), points[:, 2]], -1)


class Panels:
    """A garment surface unrolled into its panels' charts (see the module docstring).

    mesh: the surface (faces (F, C)); panels: ``TROUSER_PANELS`` or ``SKIRT_PANELS``;
    axis: ``leg_axis`` or ``body_axis``.
    """

    def __init__(self, mesh: Mesh, panels: tuple[Panel, ...], axis: Axis):
        self.mesh, self.panels, self.axis = mesh, panels, axis
        v = mesh.vertices.astype(np.float64)
        centre = v[mesh.faces].mean(axis=1)
        two_sides = any(p.side for p in panels)
        side = np.where(centre[:, 0] >= 0, 1, -1) if two_sides else np.zeros(len(centre), int)
        back = centre[:, 1] > axis(side, centre[:, 2])[:, 1]
        self.face_panel = np.array([next(i for i, p in enumerate(panels)
                                         if p.side == s and p.back == b)
                                    for s, b in zip(side, back, strict=True)])  # fmt: skip
        corners = v[mesh.faces].reshape(-1, 3)
        c = mesh.faces.shape[1]
        self.corner_uz = panel_coordinates(corners, np.repeat(side, c), np.repeat(back, c),
                                           axis).reshape(len(centre), c, 2)  # fmt: skip
        # Charts side by side, one texture: u across, z up, GAP between.
        lo = np.array([self.corner_uz[self.face_panel == k].reshape(-1, 2).min(0)
                       for k in range(len(panels))])  # fmt: skip
        hi = np.array([self.corner_uz[self.face_panel == k].reshape(-1, 2).max(0)
                       for k in range(len(panels))])  # fmt: skip
        widths = hi[:, 0] - lo[:, 0] + GAP
        self.z0 = float(lo[:, 1].min()) - GAP / 2
        height = float(hi[:, 1].max()) - self.z0 + GAP / 2
        self.scale = 1.0 / max(float(widths.sum()), height)  # UV units per metre
        self.u0 = lo[:, 0] - GAP / 2 - np.concatenate([[0], np.cumsum(widths)[:-1]])
        self.lo, self.hi = lo, hi

    def uv(self, panel: int, uz: np.ndarray) -> np.ndarray:
        """(N, 2) texture UVs of panel coordinates (N, 2) on one panel."""
        uz = np.atleast_2d(np.asarray(uz, np.float64))
        return np.stack([(uz[:, 0] - self.u0[panel]) * self.scale,
                         (uz[:, 1] - self.z0) * self.scale], -1)  # fmt: skip

    def textured(self) -> Mesh:
        """The mesh with per-corner UVs in the panel texture."""
        f = self.mesh.faces
        uvs = np.concatenate([self.uv(k, self.corner_uz[i]) for i, k in enumerate(self.face_panel)])
        face_uvs = np.arange(f.size, dtype=np.int32).reshape(f.shape)
        return Mesh(self.mesh.vertices, f, uvs.astype(np.float32), face_uvs)

    def edge(self, panel: int, z: np.ndarray, outer: bool) -> np.ndarray:
        """(N,) u of a panel's outer (or inner) edge at heights z: the extreme u of its
        corners within 2.5 cm of each 1 cm step (a ring of the mesh is not level, so a
        thinner slice would miss part of it)."""
        uz = self.corner_uz[self.face_panel == panel].reshape(-1, 2)
        steps = np.arange(self.lo[panel, 1], self.hi[panel, 1] + 0.01, 0.01)
        pick = np.full(len(steps), np.nan)
        for i, zb in enumerate(steps):
            values = uz[np.abs(uz[:, 1] - zb) < 0.025, 0]
            if len(values):
                pick[i] = values.max() if outer else values.min()
        known = ~np.isnan(pick)
        return np.interp(z, steps[known], pick[known])

    def seams(self, keep=None) -> list[Mark]:
        """Seams along the edges where two panels meet (outseams, inseams, centre seams),
        drawn on both sides of each; ``keep(face_a, face_b)`` (index arrays) -> bool mask,
        if given, picks which of those edges (a garment drawing some seams its own way)."""
        f = self.mesh.faces
        c = f.shape[1]
        a, b = f.reshape(-1), np.roll(f, -1, axis=1).reshape(-1)
        face = np.repeat(np.arange(len(f)), c)
        corner = np.tile(np.arange(c), len(f))
        key = np.minimum(a, b).astype(np.int64) * len(self.mesh.vertices) + np.maximum(a, b)
        order = np.argsort(key, kind="stable")
        same = key[order][1:] == key[order][:-1]
        first, second = order[:-1][same], order[1:][same]
        cross = self.face_panel[face[first]] != self.face_panel[face[second]]
        if keep is not None:
            cross &= keep(face[first], face[second])
        segments = []
        for half in (first[cross], second[cross]):
            fi, ci = face[half], corner[half]
            p0 = self.corner_uz[fi, ci]
            p1 = self.corner_uz[fi, (ci + 1) % c]
            for k in np.unique(self.face_panel[fi]):
                m = self.face_panel[fi] == k
                segments.append(np.stack([self.uv(k, p0[m]), self.uv(k, p1[m])], 1))
        return [Mark("seam", np.concatenate(segments))] if segments else []


def _line(panels: Panels, k: int, u: np.ndarray, z: np.ndarray) -> np.ndarray:
    return panels.uv(k, np.stack([u, z], -1))


def _across(panels: Panels, k: int, z: float, inset: float = 0.0, samples: int = 24,
            wobble: float = 0.0, phase: float = 0.0) -> np.ndarray:  # fmt: skip
    """UV polyline across panel k at height z, from edge to edge (``inset`` m in)."""
    lo = panels.edge(k, np.array([z]), False)[0] + inset
    hi = panels.edge(k, np.array([z]), True)[0] - inset
    u = np.linspace(lo, hi, samples)
    return _line(panels, k, u, z + wobble * np.sin(u * 45 + phase))


@dataclass(frozen=True)
class Heights:
    """Where a garment's parts are (m): its top edge, waistband seam, crotch, knee, hem."""

    top: float
    band: float
    crotch: float
    knee: float
    hem: float


def heights(mesh: Mesh, marks: Landmarks, band: float) -> Heights:
    v = mesh.vertices
    middle = np.abs(v[:, 0]) < 0.015
    crotch = float(v[middle, 2].min()) if middle.any() else float(marks.hip[0, 2] - 0.1)
    top = float(np.percentile(v[:, 2], 99.5))
    return Heights(top, top - band, crotch, float(marks.knee[:, 2].mean()), float(v[:, 2].min()))


def _double(panels: Panels, k: int, u: np.ndarray, z: np.ndarray, du: float = 0.0,
            dz: float = 0.0, gap: float = 0.006) -> list[Mark]:  # fmt: skip
    """Two stitch rows ``gap`` apart (offset along u by du, along z by dz per row)."""
    return [Mark("stitch", _line(panels, k, u + du * i * gap / 0.006, z + dz * i * gap / 0.006),
                 0.0007) for i in (1, 2)]  # fmt: skip


def jeans_marks(panels: Panels, h: Heights) -> list[Mark]:
    """Five-pocket jeans: waistband, front scoop pockets with rivets, a coin pocket, the fly's
    J-stitch, back yoke and patch pockets, felled inseams, hems; whiskers, worn knees and
    seat, faded seams, waistband and hem edges (where wear rubs the dye off first), folds
    behind the knees and stacked at the hems."""
    marks = panels.seams()
    # Seam ridges wear first: a light line along every seam, broken by the blotches.
    marks += [Mark("wash", m.points, 0.0035, 0.45) for m in marks if m.kind == "seam"]
    for k, panel in enumerate(panels.panels):
        def inner(z, k=k):
            return panels.edge(k, np.atleast_1d(z), False)

        def outer(z, k=k):
            return panels.edge(k, np.atleast_1d(z), True)

        marks += [Mark("seam", _across(panels, k, h.band)),
                  Mark("stitch", _across(panels, k, h.top - 0.005), 0.0007),
                  Mark("stitch", _across(panels, k, h.band + 0.004), 0.0007),
                  Mark("edge", _across(panels, k, h.hem + 0.024)),
                  Mark("stitch", _across(panels, k, h.hem + 0.016), 0.0008),
                  Mark("wash", _across(panels, k, h.top - 0.002), 0.004, 0.5),
                  Mark("wash", _across(panels, k, h.hem + 0.024), 0.004, 0.5)]  # fmt: skip
        # Felled inseam and rise: double stitches beside the inner edge.
        z = np.linspace(h.hem + 0.03, h.band - 0.003, 60)
        marks += _double(panels, k, inner(z), z, du=0.006)
        rng = np.random.default_rng(k)
        for j, zz in enumerate((h.hem + 0.055, h.hem + 0.1, h.hem + 0.15)):  # stacking
            line = _across(panels, k, zz, 0.004, 30, 0.006, rng.uniform(0, 6))
            keep = slice(int(rng.integers(0, 8)), 30 - int(rng.integers(0, 10)))  # part-way
            marks.append(Mark("fold", line[keep], 0.004, 0.45 - 0.1 * j))
        mid = lambda z, k=k: (inner(z) + outer(z)) / 2  # noqa: E731
        if not panel.back:
            t = np.linspace(0, np.pi / 2, 24)  # the front pocket's scoop
            zz = h.band - 0.085 * np.sin(t)
            marks.append(Mark("edge", _line(panels, k, outer(zz) - 0.095 * np.cos(t), zz)))
            zz = h.band - 0.077 * np.sin(t)
            marks += _double(panels, k, outer(zz) - 0.087 * np.cos(t), zz, du=0.004, gap=0.005)
            marks += [Mark("rivet", _line(panels, k, outer(h.band - 0.006) - 0.093,
                                          np.array([h.band - 0.006])), 0.007),
                      Mark("rivet", _line(panels, k, outer(h.band - 0.083) - 0.003,
                                          np.array([h.band - 0.083])), 0.007)]  # fmt: skip
            if panel.side < 0:  # coin pocket, wearer's right
                u0, u1 = outer(h.band - 0.02)[0] - 0.07, outer(h.band - 0.02)[0] - 0.028
                box = np.array([[u0, h.band - 0.003], [u1, h.band - 0.003],
                                [u1, h.band - 0.045], [u0, h.band - 0.045]])  # fmt: skip
                marks += [Mark("patch", panels.uv(k, box)),
                          Mark("stitch", panels.uv(k, box[[3, 2]] + [0, 0.004]), 0.0007)]
            else:  # the fly's J-stitch and the button, wearer's left
                z = np.linspace(h.band - 0.002, h.crotch + 0.075, 20)
                hook = np.linspace(0, np.pi / 2, 10)
                zj = np.concatenate([z, h.crotch + 0.075 - 0.04 * np.sin(hook)])
                uj = np.concatenate([inner(z) + 0.036,
                                     inner(h.crotch + 0.05) + 0.036 * np.cos(hook)])
                marks += [Mark("stitch", _line(panels, k, uj, zj), 0.0008),
                          Mark("stitch", _line(panels, k, uj + 0.006, zj + np.r_[np.zeros(20),
                               0.002 * np.sin(hook)]), 0.0008),  # fmt: skip
                          Mark("button", _line(panels, k, inner(h.top - 0.02) + 0.014,
                                               np.array([h.top - 0.02])), 0.016)]  # fmt: skip
            for j in range(5):  # whiskers fanning from the fly towards the hip
                start = np.array([inner(h.crotch + 0.03)[0] + 0.045 + 0.01 * j,
                                  h.crotch + 0.025 + 0.018 * j])
                end = start + [0.09 + 0.015 * j, 0.035 + 0.01 * j]
                t = np.linspace(0, 1, 12)[:, None]
                bow = np.array([0.0, -0.008]) * np.sin(np.pi * t)  # a slight sag
                line = panels.uv(k, start + t * (end - start) + bow)
                # Faded most in the middle, tapering to nothing at both ends.
                marks += [Mark("fold", line[2:-2], 0.003, 0.6),
                          Mark("wash", line[1:-1], 0.0045, 0.3),
                          Mark("wash", line[3:-3], 0.006, 0.45)]
            thigh = (h.crotch + h.knee) / 2
            marks += [Mark("wash", _line(panels, k, mid(h.knee + 0.03), np.array([h.knee + 0.03])),
                           0.09, 0.6),
                      Mark("wash", _line(panels, k, mid(thigh), np.array([thigh])), 0.11, 0.5)]
        else:
            uy = np.linspace(inner(h.band - 0.07)[0], outer(h.band - 0.03)[0], 20)
            zy = np.linspace(h.band - 0.07, h.band - 0.03, 20)
            marks += [Mark("seam", _line(panels, k, uy, zy))]
            marks += _double(panels, k, uy, zy, dz=-0.004, gap=0.005)
            uc = float(mid(h.band - 0.1)[0]) - 0.01
            top = float(np.interp(uc, uy, zy)) - 0.014
            pocket = np.array([[uc - 0.066, top], [uc + 0.066, top], [uc + 0.06, top - 0.12],
                               [uc, top - 0.145], [uc - 0.06, top - 0.12]])  # fmt: skip
            inset = pocket + (np.array([uc, top - 0.07]) - pocket) * 0.06
            t = np.linspace(0.15, np.pi - 0.15, 16)  # the arcuate's double curve
            arc = np.stack([uc - 0.045 * np.cos(t), top - 0.045 - 0.025 * np.sin(t)], -1)
            marks += [Mark("patch", panels.uv(k, pocket)),
                      Mark("stitch", panels.uv(k, np.concatenate([inset, inset[:1]])), 0.0007),
                      Mark("stitch", panels.uv(k, arc), 0.0007),
                      Mark("stitch", panels.uv(k, arc - [0, 0.006]), 0.0007),
                      Mark("wash", panels.uv(k, np.array([[uc, top - 0.07]])), 0.08, 0.3)]
            for j in range(4):  # folds behind the knee
                u = np.linspace(-0.06, 0.06, 12) + mid(h.knee)[0]
                z = h.knee - 0.035 + 0.024 * j + 0.012 * ((u - u.mean()) / 0.06) ** 2
                marks.append(Mark("fold", _line(panels, k, u, z), 0.0045, 1.0 - 0.15 * j))
            u = np.linspace(-0.07, 0.07, 12) + mid(h.crotch - 0.02)[0]
            marks.append(Mark("fold", _line(panels, k, u, h.crotch - 0.025 + 0 * u), 0.005, 0.6))
    return marks


def trouser_marks(panels: Panels, h: Heights) -> list[Mark]:
    """Tailored trousers: waistband, slanted side pockets, pressed creases front and back,
    back welt pockets with a button, a blind hem and a break over the shoe."""
    marks = panels.seams()
    for k, panel in enumerate(panels.panels):
        def inner(z, k=k):
            return panels.edge(k, np.atleast_1d(z), False)

        def outer(z, k=k):
            return panels.edge(k, np.atleast_1d(z), True)

        marks += [Mark("seam", _across(panels, k, h.band)),
                  Mark("stitch", _across(panels, k, h.band + 0.003), 0.0005),
                  Mark("edge", _across(panels, k, h.hem + 0.04))]  # fmt: skip
        low = h.crotch - 0.04 if panel.back else h.band - 0.01
        z = np.linspace(h.hem + 0.005, low, 60)
        centre = (inner(np.minimum(z, h.crotch)) + outer(np.minimum(z, h.crotch))) / 2
        # A pressed crease runs in one sweep: the panel's edges step with the helper
        # mesh's faces (the crease between them jogged 8-10 mm sideways at the knee).
        centre = np.polyval(np.polyfit(z, centre, 2), z)
        marks.append(Mark("crease", _line(panels, k, centre, z), 0.0025, 1.3))
        marks.append(Mark("fold", _across(panels, k, h.hem + 0.07, 0.02, 30, 0.004, k)[6:22],
                          0.006, 0.35 if not panel.back else 0.2))  # the break over the shoe
        if not panel.back:
            start = np.array([outer(h.band)[0] - 0.045, h.band])
            end = np.array([outer(h.band - 0.17)[0], h.band - 0.17])
            line = np.linspace(start, end, 10)
            marks += [Mark("edge", panels.uv(k, line)),
                      Mark("stitch", panels.uv(k, line + [0.006, 0]), 0.0005)]
            if panel.side > 0:
                marks.append(Mark("button", _line(panels, k, inner(h.top - 0.018) + 0.012,
                                                  np.array([h.top - 0.018])), 0.013))  # fmt: skip
        else:
            uc = float((inner(h.band - 0.08) + outer(h.band - 0.08))[0] / 2)
            u = np.linspace(uc - 0.065, uc + 0.065, 10)
            marks += [Mark("edge", _line(panels, k, u, np.full(10, h.band - 0.075))),
                      Mark("edge", _line(panels, k, u, np.full(10, h.band - 0.085))),
                      Mark("button", _line(panels, k, np.array([uc]),
                                           np.array([h.band - 0.097])), 0.011)]  # fmt: skip
            for j in range(3):
                u = np.linspace(-0.06, 0.06, 12) + uc
                z = h.knee - 0.02 + 0.03 * j + 0.01 * ((u - uc) / 0.06) ** 2
                marks.append(Mark("fold", _line(panels, k, u, z), 0.005, 0.5))
    return marks


def skirt_marks(panels: Panels, h: Heights) -> list[Mark]:
    """A skirt: side seams, waistband, a centre-back zip, a stitched hem and soft flare
    folds falling from the hips."""
    marks = panels.seams()
    for k, panel in enumerate(panels.panels):
        marks += [Mark("seam", _across(panels, k, h.band)),
                  Mark("stitch", _across(panels, k, h.band - 0.004), 0.0006),
                  Mark("stitch", _across(panels, k, h.top - 0.004), 0.0006),
                  Mark("stitch", _across(panels, k, h.hem + 0.014), 0.0007)]  # fmt: skip
        lo, hi = panels.edge(k, np.array([h.hem + 0.05]), False)[0], panels.edge(
            k, np.array([h.hem + 0.05]), True)[0]  # fmt: skip
        for j in range(6):  # flare folds, fanning out towards the hem
            u_hem = lo + (hi - lo) * (j + 0.5) / 6
            start = [u_hem * 0.55, h.band - 0.09]
            line = panels.uv(k, np.linspace(start, [u_hem, h.hem + 0.02], 10))
            marks.append(Mark("fold", line, 0.012, 0.7 if j % 2 else -0.5))
        if panel.back:
            z = np.linspace(h.band - 0.18, h.top, 12)
            marks += [Mark("seam", _line(panels, k, np.zeros(12), z))]
            marks += [Mark("stitch", _line(panels, k, np.full(12, d), z), 0.0006)
                      for d in (-0.007, 0.007)]  # fmt: skip
    return marks


# ---------------------------------------------------------------------------- geometry


def straight_legs(body: AuthoringBody, points: np.ndarray, hang: float, start: float = 0.5,
                  taper: float = 0.9, gap: float = 0.006) -> np.ndarray:  # fmt: skip
    """(N, 3) trouser-leg points below the knee laid on a straight, gently tapered tube
    round the leg's axis: ``hang`` times the leg's radius at the knee there, narrowing to
    ``taper`` times that at the ankle, and never closer than ``gap`` m to the skin (the
    calf's bulge shows through at the back, as it does under real cloth). A tailored leg
    falls from the knee instead of following the calf and ankle, and does not flare: the
    ease growing down the leg (``flare``) bells the hem out to twice the ankle's width
    (9 cm round a man's leg against 7.4 cm at the knee), and a bell swings away from the
    shin in a stride."""
    from avatar.clothes.regions import limb_coordinates

    marks = body.marks
    _, leg = limb_coordinates(points, marks)
    out = points.copy()
    for s in (0, 1):
        sign = 1 if s == 0 else -1
        mine = np.flatnonzero((np.sign(points[:, 0]) == sign) & (leg > start - 0.05)
                              & (leg < 1.2))  # fmt: skip
        knee, ankle = marks.knee[s], marks.ankle[s]
        direction = (ankle - knee) / np.linalg.norm(ankle - knee)
        rel = points[mine] - knee
        along = rel @ direction
        radial = rel - along[:, None] * direction
        r = np.linalg.norm(radial, axis=1)
        ring = np.abs(leg[mine] - start) < 0.03
        if not ring.any():
            continue
        down = np.clip((leg[mine] - start) / (1 - start), 0, 1)
        tube = hang * float(np.median(r[ring])) * (1 - (1 - taper) * down)
        off, _ = skin_offset(body, points[mine])
        floor = r - off + gap  # the radius that keeps ``gap`` off the skin here
        t = np.clip((leg[mine] - start) / 0.15, 0, 1)
        weight = t * t * (3 - 2 * t)  # the knee's own shape blends into the tube
        goal = weight * np.maximum(tube, floor) + (1 - weight) * r
        out[mine] = knee + along[:, None] * direction + radial * (goal / np.maximum(r, 1e-9))[
            :, None]  # fmt: skip
    return out


def skin_offset(body: AuthoringBody, points: np.ndarray, k: int = 6,
                ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """((N,) signed metres off the skin, (N, 3) unit outward directions) of points (N, 3):
    the distance above the tangent planes of the ``k`` nearest skin vertices, weighted by
    nearness (smooth where one nearest vertex would step from vertex to vertex)."""
    dist, i = body.skin_tree.query(points, k=k)
    w = 1.0 / (dist + 0.005)
    w /= w.sum(axis=1, keepdims=True)
    n = body.skin_normals[i].astype(np.float64)
    above = np.einsum("nkd,nkd->nk", points[:, None] - body.vertices[i], n)
    normal = np.einsum("nk,nkd->nd", w, n)
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-9)
    return np.einsum("nk,nk->n", w, above), normal


def hug_skin(body: AuthoringBody, points: np.ndarray, gap: float,
             deepest: float = 0.004) -> np.ndarray:  # fmt: skip
    """(N, 3) points laid ``gap`` m off the skin: a stretch garment (a swimsuit, leggings)
    cut from ``helper-tights`` otherwise keeps that shell's own 5-6 mm off the skin and
    reads as loose cloth, baggy over the seat. Each point moves in along the normal at its
    closest skin point (the exact surface: the tangent planes of nearby vertices read
    2.5 mm where the skin of a buttock was 5 mm away), by at most ``deepest`` m, so cloth
    bridging a cleft dips into it a little instead of lining it."""
    from avatar.geometry import collision

    surface = collision.skin_surface(body.skin_faces)
    q = collision.query(body.vertices[:BODY_VERTICES], surface, points, k=6)
    move = np.clip(q.distance.astype(np.float64) - gap, 0, deepest)
    return points - move[:, None] * q.normal.astype(np.float64)


def sit_on_hips(body: AuthoringBody, points: np.ndarray, ease: float, hip_z: float,
                fall: float = 0.12, under: np.ndarray | None = None,
                gap: float = 0.004, edge_gap: float = 0.0025,
                edge: float = 0.025) -> np.ndarray:  # fmt: skip
    """(N, 3) skirt points with everything above ``hip_z`` laid ``ease`` m off the skin
    (the waist and hips carry a skirt: it sits on them), easing over ``fall`` m below
    ``hip_z`` back to the points' own, flared positions, so the flare starts below the
    hip instead of standing out from the waist (a helper skirt stands 1.5-3 cm off the
    hips of slim and heavy bodies, a ridge and pleats round the hips). ``under``: (M, 3)
    points of a layer the skirt lies over (a dress's bodice): the skirt keeps ``gap`` m
    outside the nearest of them, closing to ``edge_gap`` m over its top ``edge`` m, so
    its top edge meets the layer under it as a seam does, not as a ledge."""
    out = points.astype(np.float64).copy()
    t = np.clip((hip_z - out[:, 2]) / fall, 0, 1)
    w = 1 - t * t * (3 - 2 * t)  # 1 above the hip, smoothly 0 a ``fall`` below it
    moving = w > 0
    floor = np.zeros(int(moving.sum()))
    hug_top = np.full(int(moving.sum()), np.inf)
    if under is not None and len(under):
        from scipy.spatial import cKDTree

        under_off, _ = skin_offset(body, under.astype(np.float64))
        reach, nearest = cKDTree(under).query(out[moving])
        over = (reach < 0.06) & (out[moving, 2] > under[:, 2].min() - 0.01)
        top = _top_edge_at(out, out[moving])  # the helper skirt's top dips at the front
        s = np.clip((out[moving, 2] - (top - edge)) / edge, 0, 1)
        here = gap + (edge_gap - gap) * s * s * (3 - 2 * s)
        floor = np.where(over, under_off[nearest] + here, 0.0)
        # At the edge the skirt closes onto the layer under it, hug or not.
        closing = over & (s > 0)
        hug_top = np.where(closing, floor, np.inf)
    for _ in range(2):  # a second pass corrects the first's error on curved skin
        off, normal = skin_offset(body, out[moving])
        target = np.maximum(np.minimum(w[moving] * ease + (1 - w[moving]) * off, hug_top),
                            floor)  # fmt: skip
        out[moving] += (target - off)[:, None] * normal
    return out


def _top_edge_at(points: np.ndarray, at: np.ndarray, sectors: int = 36) -> np.ndarray:
    """(M,) z of the top edge of a tube of ``points`` (N, 3) round its vertical axis,
    at the angles of ``at`` (M, 3): the highest point in each sector, interpolated round.
    A skirt's top edge is not level (2.5 cm lower at the front than at the back)."""
    centre = points[:, :2].mean(axis=0)
    width = 2 * np.pi / sectors

    def angle(p):
        return np.arctan2(p[:, 0] - centre[0], -(p[:, 1] - centre[1])) + np.pi

    sector = (angle(points) / width).astype(int) % sectors
    highest = np.full(sectors, -np.inf)
    np.maximum.at(highest, sector, points[:, 2])
    known = np.isfinite(highest)
    middles = (np.arange(sectors) + 0.5) * width
    return np.interp(angle(at), middles[known], highest[known], period=2 * np.pi)


def belt_loops(body: AuthoringBody, mesh: Mesh, h: Heights, surface_faces: np.ndarray,
               angles=(25, 80, 140, 180, -140, -80, -25)) -> Piece:  # fmt: skip
    """Belt loops: strips 1.1 cm wide standing 3 mm off the waistband from its top edge to
    below its seam, at ``angles`` (degrees round the waist from the front, + to the left),
    each textured like the waistband under it."""
    assert mesh.uvs is not None and mesh.face_uvs is not None
    v = mesh.vertices.astype(np.float64)
    corner_uv = np.zeros((len(v), 2))
    corner_uv[mesh.faces.ravel()] = mesh.uvs[mesh.face_uvs.ravel()]
    rim = np.unique(boundary_edges(mesh.faces)[0])
    rim = rim[v[rim, 2] > h.top - 0.03]
    centre = v[rim].mean(axis=0)
    pieces = []
    for angle in angles:
        a = np.radians(angle)
        want = np.array([np.sin(a), -np.cos(a)])
        d = v[rim, :2] - centre[:2]
        score = (d @ want) / np.linalg.norm(d, axis=1)
        top = v[rim[np.argmax(score)]]
        normal = body.outward(top[None])[0]
        normal[2] = 0
        normal /= np.linalg.norm(normal)
        tangent = np.cross([0.0, 0.0, 1.0], normal)
        rows = np.array([top[2] + 0.003, top[2] - 0.012, h.band - 0.003, h.band - 0.009])
        points, faces = [], []
        for z in rows:
            base = top + (z - top[2]) * np.array([0, 0, 1.0])
            # The loop stands off the band where the band is: follow the nearest cloth.
            near = v[np.argmin(np.linalg.norm(v - base, axis=1))]
            base = base + ((near - base) @ normal) * normal
            for depth in (0.0, 0.003):
                for c in (-0.0055, 0.0055):
                    points.append(base + c * tangent + depth * normal)
        idx = np.arange(len(rows) * 4).reshape(len(rows), 2, 2)  # (row, depth, column)
        for r_i in range(len(rows) - 1):
            a0, a1 = idx[r_i], idx[r_i + 1]
            faces += [[a0[1, 0], a0[1, 1], a1[1, 1], a1[1, 0]],  # front
                      [a0[0, 0], a0[1, 0], a1[1, 0], a1[0, 0]],  # sides
                      [a0[1, 1], a0[0, 1], a1[0, 1], a1[1, 1]]]  # fmt: skip
        faces += [[idx[0, 0, 0], idx[0, 0, 1], idx[0, 1, 1], idx[0, 1, 0]],  # top
                  [idx[-1, 1, 0], idx[-1, 1, 1], idx[-1, 0, 1], idx[-1, 0, 0]]]  # fmt: skip
        p = np.asarray(points)
        f = np.asarray(faces, np.int32)
        uv = corner_uv[np.argmin(np.linalg.norm(v[None] - p[:, None], axis=2), axis=1)]
        uvs = uv[f.ravel()].astype(np.float32)
        corners = np.arange(f.size, dtype=np.int32).reshape(f.shape)
        loop = Mesh(p.astype(np.float32), f, uvs, corners)
        pieces.append(bound(body, _facing(loop, top - 0.05 * normal), surface_faces))
    return join(pieces)


def _facing(mesh: Mesh, inside: np.ndarray) -> Mesh:
    """Faces turned away from ``inside`` (a point behind the loop)."""
    v = mesh.vertices[mesh.faces].astype(np.float64)
    n = np.cross(v[:, 2] - v[:, 0], v[:, 3] - v[:, 1])
    flip = np.einsum("fd,fd->f", n, v.mean(axis=1) - inside) < 0
    faces, face_uvs = mesh.faces.copy(), mesh.face_uvs.copy()  # type: ignore[union-attr]
    faces[flip], face_uvs[flip] = faces[flip][:, ::-1], face_uvs[flip][:, ::-1]
    return Mesh(mesh.vertices, faces, mesh.uvs, face_uvs)


# Buttons and rivets: jeans' copper (Layout's default); tailored trousers' horn buttons, as
# dark as the wool (copper read as jeans rivets on a grey suit).
HORN = (0.035, 0.028, 0.022)


def layout(panels: Panels, marks: list[Mark], thread: str, metal=None) -> Layout:
    names = [p.name for p in panels.panels]
    extra = {} if metal is None else {"metal": metal}
    return Layout(panels.scale, tuple(marks), thread, extras={"panels": names}, **extra)


__all__ = [
    "SKIRT_PANELS",
    "TROUSER_PANELS",
    "Heights",
    "Panel",
    "Panels",
    "belt_loops",
    "body_axis",
    "heights",
    "hug_skin",
    "jeans_marks",
    "layout",
    "leg_axis",
    "panel_coordinates",
    "sit_on_hips",
    "skin_offset",
    "skirt_marks",
    "straight_legs",
    "trouser_marks",
]


def blend_sides(body: AuthoringBody, piece: Piece, group: str, pelvis: float = 0.5,
                reach: float = 0.18) -> Piece:  # fmt: skip
    """A skirt that swings as one: each vertex re-bound to its dominant reference, that
    reference's mirror image across the body's midline and a vertex of the skirt's top at
    the same angle, with weights (1 - m - pelvis, m, pelvis), m = (1 - pelvis) / 2 at the
    midline (the two legs alike) and 0 ``reach`` m out to the side. The offsets absorb the
    change, so the skirt sits exactly where it was on the authoring body; skin weights
    transferred through the binding then mix both legs and the hips, so the front does not
    split with the legs in a stride.
    ``group``: the helper group the piece is bound to."""
    from scipy.spatial import cKDTree

    b = piece.binding
    x = body.vertices.astype(np.float64)
    members = np.asarray(body.base.groups[group])
    tree = cKDTree(x[members])
    dominant = b.indices[np.arange(len(b)), np.argmax(np.abs(b.weights), axis=1)]
    mirrored = x[dominant] * [-1, 1, 1]
    mirror = members[tree.query(mirrored)[1]]
    top_z = x[members, 2].max()
    ring = members[x[members, 2] > top_z - 0.03]
    angle = np.arctan2(x[dominant, 0], -x[dominant, 1])
    ring_angle = np.arctan2(x[ring, 0], -x[ring, 1])
    nearest = np.argmin(np.abs(np.angle(np.exp(1j * (angle[:, None] - ring_angle[None])))),
                        axis=1)  # fmt: skip
    top = ring[nearest]
    # Half of what the pelvis leaves at the midline, so both legs weigh the same there:
    # with m = 0.5 beside pelvis = 0.5 a vertex just left of the midline followed the right
    # leg alone and its neighbour just right of it the left leg, the front crossing itself
    # mid-stride (a 14-33 mm deep dark notch between the legs).
    m = 0.5 * (1 - pelvis) * np.clip(1 - np.abs(x[dominant, 0]) / reach, 0, 1)
    weights = np.stack([1 - m - pelvis, m, np.full(len(m), pelvis)], 1)
    indices = np.stack([dominant, mirror, top], 1).astype(np.int32)
    position = piece.mesh.vertices.astype(np.float64)
    offsets = position - np.einsum("nk,nkc->nc", weights, x[indices])
    from avatar.clothes.binding import make_binding

    binding = make_binding(indices, weights, offsets, b.scale_refs, b.scale_lengths,
                           np.zeros(len(b), bool))  # fmt: skip
    return Piece(piece.mesh, binding, piece.layout)

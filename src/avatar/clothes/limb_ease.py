"""Ease that scales with the limb it goes round, not with the whole body.

A binding's offset scales with the body along each axis (MakeHuman's reference pairs:
hand to hand, front to back, head to foot). A child's limbs are thinner for their size
than an adult's: at age 0.15 the body's scale was 0.82-0.89 of the authoring body's, the
calf's and the forearm's 0.5-0.8. Eased by the body's scale, the child's trouser legs
stood 1.7-1.9 times the girth of the leg from the knee down (an adult's 1.4-1.8), 2.5 at a
toddler's shin: wide bags ending in a bell round the ankle.

``across_the_limbs`` re-anchors the cloth round the limbs on the limb itself: each vertex
as its nearest shell vertex plus a share of the shell's own diameter through it (the
vector to the vertex across the limb), so the ease grows and shrinks with that limb's
girth on every body. On the authoring body the garment is unchanged.
"""

from __future__ import annotations

import numpy as np

from avatar.clothes.authoring import AuthoringBody
from avatar.clothes.binding import Binding, axis_scale, make_binding
from avatar.clothes.regions import limb_coordinates

# Chain coordinates (0 shoulder or hip joint, 0.5 elbow or knee, 1 wrist or ankle) over
# which the ease hands over from the body's scale to the limb's (legs, arms): the top of
# the thigh and the upper arm stay with the body's (the crotch, the seat and the armpit
# span between parts there; on the heavy man's upper arm, pressed to his side, the ring
# across the arm took in the side of the chest and his jacket's sleeve shrank by a tenth),
# the limb's own from above the knee and at the elbow down.
LEG_FROM, LEG_TO = 0.2, 0.35
ARM_FROM, ARM_TO = 0.35, 0.5
SLAB = 0.01  # m either side of a vertex along the limb: the shell's ring about it


def across_the_limbs(body: AuthoringBody, points: np.ndarray, binding: Binding) -> Binding:
    """``binding`` of points (N, 3) (on the authoring body) with the points round the arms
    and legs re-anchored on the limb under them (``limb_share``): weights (1 + t - s, -t,
    s) on their nearest reference ``a``, the shell vertex ``b`` across the limb from it and
    another reference ``c`` of their triangle, so the ease ``t (X[a] - X[b])`` scales with
    the limb's own diameter; what the two directions leave (along the limb, and the share
    handed to the body's scale) stays an offset."""
    v = np.asarray(points, dtype=np.float64)
    x = body.vertices.astype(np.float64)
    share = limb_share(body, v, binding)
    pick = np.flatnonzero(share > 0)
    if len(pick) == 0:
        return binding
    refs = binding.indices[pick]
    order = np.argsort(-binding.weights[pick], axis=1)
    a = np.take_along_axis(refs, order[:, :1], 1)[:, 0]
    across = _across(body, x, a, v[pick], np.unique(binding.indices))
    r = v[pick] - x[a]
    u = x[a] - x[across]
    # The other corner that explains more of the way round the limb.
    c1, c2 = (np.take_along_axis(refs, order[:, k:k + 1], 1)[:, 0] for k in (1, 2))
    t1, s1, rest1 = _fit_two(r, u, x[c1] - x[a])
    t2, s2, rest2 = _fit_two(r, u, x[c2] - x[a])
    first = np.linalg.norm(rest1, axis=1) <= np.linalg.norm(rest2, axis=1)
    c, t, s = np.where(first, c1, c2), np.where(first, t1, t2), np.where(first, s1, s2)
    rest = np.where(first[:, None], rest1, rest2)
    f = share[pick]
    kept = f * t  # the limb's share of the ease; the body's share stays in the offset
    rest = rest + ((1 - f) * t)[:, None] * u
    indices, weights = binding.indices.copy(), binding.weights.copy()
    offsets = binding.offsets.copy()
    indices[pick] = np.stack([a, across, c], axis=1)
    weights[pick] = np.stack([1 + kept - s, -kept, s], axis=1)
    offsets[pick] = rest / axis_scale(binding, x)
    return make_binding(indices, weights, offsets, binding.scale_refs, binding.scale_lengths)


def limb_share(body: AuthoringBody, points: np.ndarray, binding: Binding) -> np.ndarray:
    """(N,) 0..1: how much of each point's ease follows the limb under it: 0 off the arms
    and legs (by the part of its nearest reference) and above ``LEG_FROM`` / ``ARM_FROM``
    along them, 1 from ``LEG_TO`` / ``ARM_TO`` down, a smoothstep between."""
    arm, leg = limb_coordinates(points, body.marks)
    part = body.part[binding.indices[np.arange(len(points)), np.argmax(binding.weights, 1)]]
    on_arm = np.clip((arm - ARM_FROM) / (ARM_TO - ARM_FROM), 0, 1)
    on_leg = np.clip((leg - LEG_FROM) / (LEG_TO - LEG_FROM), 0, 1)
    t = np.where(part == "arm", on_arm, np.where(part == "leg", on_leg, 0.0))
    return t * t * (3 - 2 * t)


def _across(body: AuthoringBody, x: np.ndarray, a: np.ndarray, cloth: np.ndarray,
            shell: np.ndarray) -> np.ndarray:  # fmt: skip
    """(P,) for each cloth point (P, 3) over its nearest shell vertex a (P,) the vertex of
    shell (the surface's vertex ids) on the same limb across from it: through the centre of
    the limb's ring about a (that limb's vertices within ``SLAB`` along its axis), as far
    on the other side, so that ``X[a] - X[b]`` points the way the cloth stands off."""
    m = body.marks
    out = np.empty(len(a), np.int64)
    p = x[a]
    arm, leg = limb_coordinates(p, m)
    part = body.part[a]
    for limb, joints, along in (("arm", (m.shoulder, m.elbow, m.wrist), arm),
                                ("leg", (m.hip, m.knee, m.ankle), leg)):  # fmt: skip
        for side, sign in ((0, 1.0), (1, -1.0)):
            rows = np.flatnonzero((part == limb) & (np.sign(p[:, 0]) == sign))
            if len(rows) == 0:
                continue
            upper = along[rows] < 0.5
            top = np.where(upper[:, None], joints[0][side], joints[1][side])
            end = np.where(upper[:, None], joints[1][side], joints[2][side])
            axis = (end - top) / np.linalg.norm(end - top, axis=1, keepdims=True)
            ids = _limb_vertices(body, x, shell, limb, sign)
            out[rows] = _opposite(x, p[rows], cloth[rows], axis, ids)
    return out


def _limb_vertices(body: AuthoringBody, x: np.ndarray, shell: np.ndarray, limb: str,
                   sign: float) -> np.ndarray:  # fmt: skip
    """The ids of shell (V,) on one limb (a part name) on one side (sign of x)."""
    return shell[(body.part[shell] == limb) & (np.sign(x[shell, 0]) == sign)]


def _opposite(x: np.ndarray, p: np.ndarray, cloth: np.ndarray, axis: np.ndarray,
              ids: np.ndarray) -> np.ndarray:  # fmt: skip
    """(P,) the vertex of ids across the limb from each shell point p (P, 3): nearest to
    the point as far from the centre of p's ring (the ids within ``SLAB`` of p along its
    axis (P, 3)) as p, on the side away from its cloth point (P, 3)."""
    q = x[ids]
    rel = q[None, :, :] - p[:, None, :]  # (P, M, 3)
    ring = np.abs(np.einsum("pmd,pd->pm", rel, axis)) < SLAB
    ring[np.arange(len(p)), np.argmin(np.linalg.norm(rel, axis=2), axis=1)] = True
    centre = np.einsum("pm,md->pd", ring, q) / ring.sum(axis=1, keepdims=True)
    out = cloth - centre
    out -= np.einsum("pd,pd->p", out, axis)[:, None] * axis  # across the limb only
    out /= np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-12)
    far = centre - out * np.linalg.norm(p - centre, axis=1, keepdims=True)
    return ids[np.argmin(np.linalg.norm(q[None, :, :] - far[:, None, :], axis=2), axis=1)]


def _fit_two(r: np.ndarray, u: np.ndarray, e: np.ndarray):
    """Least squares r (P, 3) ~ t u + s e: (t (P,), s (P,), what is left (P, 3))."""
    uu, ue, ee = (np.einsum("pd,pd->p", a, b) for a, b in ((u, u), (u, e), (e, e)))
    ru, re = np.einsum("pd,pd->p", r, u), np.einsum("pd,pd->p", r, e)
    det = uu * ee - ue * ue
    ok = np.abs(det) > 1e-18
    safe = np.where(ok, det, 1.0)
    t = np.where(ok, (ru * ee - re * ue) / safe, ru / np.maximum(uu, 1e-18))
    s = np.where(ok, (re * uu - ru * ue) / safe, 0.0)
    return t, s, r - t[:, None] * u - s[:, None] * e

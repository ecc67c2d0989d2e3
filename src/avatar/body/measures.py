"""Body measurements as a tailor takes them, and measurement-driven shaping.

Girths are the perimeter of the convex hull of the torso's horizontal cross-section (a tape
measure spans concavities): ``chest`` at nipple height, ``waist`` the narrowest girth between
the pelvis and the chest, ``hips`` the widest between the crotch and the waist. ``height`` is
the top of the head above the floor (MakeHuman's ``joint-ground`` helper). Metres.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from avatar.body import assets
from avatar.body.model import BODY_VERTICES
from avatar.errors import ParameterError
from avatar.mesh import Mesh

NIPPLES = (8451, 1779)  # the default rig's breast tails: MakeHuman's nipple vertices


@dataclass(frozen=True)
class Landmarks:
    """Heights used to place the girths, from the joint helper cubes."""

    ground: float
    pelvis: float
    waist_low: float
    navel: float
    chest: float


def landmarks(vertices: np.ndarray, groups: Mapping[str, np.ndarray]) -> Landmarks:
    z = lambda g: float(vertices[groups[g], 2].mean())  # noqa: E731
    return Landmarks(
        ground=z("joint-ground"),
        pelvis=z("joint-pelvis"),
        waist_low=z("joint-spine-4"),
        navel=z("joint-spine-3"),
        chest=float(vertices[list(NIPPLES), 2].mean()),
    )


def girth(vertices: np.ndarray, triangles: np.ndarray, height: float) -> float:
    """Convex-hull perimeter of the torso cross-section at ``height`` (metres)."""
    pts, loop = _cut(vertices, triangles, height)
    if len(pts) < 3:
        return 0.0
    return _hull_perimeter(pts[loop == _torso_loop(pts, loop)])


def _cut(v: np.ndarray, tri: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """Points (n, 2) where mesh edges cross the plane z = h, and the loop id of each.

    Each crossed triangle joins its two crossed edges; loops are the connected components
    of the edge graph), so arms, hands and the torso come apart exactly.
    """
    z = v[tri, 2] - h
    crossing = (z.min(axis=1) < 0) & (z.max(axis=1) >= 0)
    t = tri[crossing].astype(np.int64)
    below = v[t, 2] < h  # (T, 3)
    keys = []
    for a, b in ((0, 1), (1, 2), (2, 0)):
        k = np.minimum(t[:, a], t[:, b]) * 1_000_000 + np.maximum(t[:, a], t[:, b])
        keys.append(np.where(below[:, a] != below[:, b], k, -1))
    keys_arr = np.stack(keys, axis=1)
    pairs = np.sort(keys_arr, axis=1)[:, 1:]  # the two crossed edges of each triangle
    uniq, inv = np.unique(pairs, return_inverse=True)
    inv = inv.reshape(-1, 2)
    graph = coo_matrix((np.ones(len(inv)), (inv[:, 0], inv[:, 1])), shape=(len(uniq),) * 2)
    _, parent = connected_components(graph, directed=False)
    a, b = uniq // 1_000_000, uniq % 1_000_000
    s = (h - v[a, 2]) / (v[b, 2] - v[a, 2])
    pts = v[a, :2] + s[:, None] * (v[b, :2] - v[a, :2])
    return pts, parent


def _torso_loop(pts: np.ndarray, loop: np.ndarray) -> int:
    """The largest loop spanning x = 0 (arms do not; the navel's pit is small)."""
    best, best_size = int(loop[0]), -1.0
    for r in np.unique(loop):
        x = pts[loop == r]
        if x[:, 0].min() <= 0 <= x[:, 0].max():
            size = float(np.ptp(x[:, 0]) * np.ptp(x[:, 1]))
            if size > best_size:
                best, best_size = int(r), size
    return best


def _hull_perimeter(p: np.ndarray) -> float:
    """Perimeter of the 2-D convex hull (Andrew's monotone chain)."""
    p = np.unique(np.round(p, 6), axis=0)
    if len(p) < 3:
        return 0.0

    def turn(a: np.ndarray, b: np.ndarray) -> float:
        # The 2-D cross product written out: numpy 2.5+ (Blender 5.x) rejects 2-vectors.
        return float(a[0] * b[1] - a[1] * b[0])

    def half(points: np.ndarray) -> list[np.ndarray]:
        out: list[np.ndarray] = []
        for q in points:
            while len(out) >= 2 and turn(out[-1] - out[-2], q - out[-2]) <= 0:
                out.pop()
            out.append(q)
        return out

    hull = np.array(half(p)[:-1] + half(p[::-1])[:-1])
    return float(np.sum(np.linalg.norm(np.roll(hull, -1, axis=0) - hull, axis=1)))


def measure(vertices: np.ndarray, mesh: Mesh | None = None) -> dict[str, float]:
    """height, chest, waist and hips (metres) of a body's vertices (19158, 3)."""
    if mesh is None:
        mesh = assets.load().base
    tri = mesh.with_vertices(vertices).subset(mesh.face_groups["body"]).triangles()
    body = vertices[:BODY_VERTICES]
    lm = landmarks(vertices, mesh.groups)
    hips_z = np.linspace(lm.pelvis - 0.06, lm.navel, 9)
    waist_z = np.linspace(lm.waist_low, lm.chest - 0.06, 9)
    return {
        "height": float(body[:, 2].max() - lm.ground),
        "chest": girth(body, tri, lm.chest),
        "waist": min(girth(body, tri, h) for h in waist_z),
        "hips": max(girth(body, tri, h) for h in hips_z),
    }


# Which parameter drives each measurement when solving for it.
DRIVERS = {
    "height": "height",
    "chest": "measure/measure-bust-circ-decr|incr",
    "waist": "measure/measure-waist-circ-decr|incr",
    "hips": "measure/measure-hips-circ-decr|incr",
}


def fit(
    model,
    targets: Mapping[str, float],
    params: Mapping[str, float] | None = None,
    iterations: int = 8,
    tolerance: float = 0.002,
    reach: float | None = 0.01,
) -> tuple[dict[str, float], dict[str, float]]:
    """Solve for parameters giving target measurements (metres: height, chest, waist, hips).

    Damped Gauss-Newton over the ``DRIVERS`` of the requested measurements, starting from
    ``params``; parameters stay within their ranges. A target the solve ends further than
    ``reach`` metres from is unreachable: ParameterError naming the range its driver spans
    (the other measurements as solved); ``reach=None`` keeps the nearest reachable value
    instead. Non-finite or non-positive targets are ParameterErrors too.
    Returns (parameters, achieved measurements).
    """
    unknown = set(targets) - set(DRIVERS)
    if unknown:
        raise ParameterError(f"cannot fit {', '.join(sorted(unknown))}; use {', '.join(DRIVERS)}")
    for name, value in targets.items():
        if not np.isfinite(value) or value <= 0:
            raise ParameterError(f"measurement {name} must be a positive length, got {value:g} m")
    names = list(targets)
    drivers = [DRIVERS[n] for n in names]
    values = dict(model.resolve(params))
    want = np.array([targets[n] for n in names], dtype=np.float64)

    def evaluate(x: np.ndarray) -> np.ndarray:
        got = measure(model.shape(values | dict(zip(drivers, x.tolist(), strict=True))), model.base)
        return np.array([got[n] for n in names])

    lo = np.array([model.parameters[d].minimum for d in drivers])
    hi = np.array([model.parameters[d].maximum for d in drivers])
    x = np.array([values.get(d, model.parameters[d].default) for d in drivers], dtype=np.float64)
    current = evaluate(x)
    for _ in range(iterations):
        if np.max(np.abs(current - want)) < tolerance:
            break
        jac = np.empty((len(names), len(names)))
        for k in range(len(names)):
            step = np.zeros_like(x)
            step[k] = 0.05 if x[k] + 0.05 <= hi[k] else -0.05
            jac[:, k] = (evaluate(x + step) - current) / step[k]
        delta = np.linalg.lstsq(jac, want - current, rcond=None)[0]
        x = np.clip(x + np.clip(delta, -0.5, 0.5), lo, hi)
        current = evaluate(x)
    values |= dict(zip(drivers, x.tolist(), strict=True))
    if reach is not None:
        for k in np.flatnonzero(np.abs(current - want) > reach):
            ends = []
            for bound in (lo[k], hi[k]):  # the driver at each end of its range
                probe = x.copy()
                probe[k] = bound
                ends.append(float(evaluate(probe)[k]))
            low, high = min(ends), max(ends)
            raise ParameterError(
                f"{names[k]} {want[k] * 100:g} cm is out of reach: this body's {names[k]} "
                f"ranges {low * 100:.1f}-{high * 100:.1f} cm (parameter {drivers[k]} "
                f"{lo[k]:g}..{hi[k]:g}; the closest is {current[k] * 100:.1f} cm)"
            )
    return values, dict(zip(names, current.tolist(), strict=True))

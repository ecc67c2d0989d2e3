"""A flared hem pushed by a leg mid-stride (issue 14, seventh pass): measured on the posed
dress, as exports have it."""

from __future__ import annotations

import numpy as np
import pytest

from avatar.human import Human
from avatar.rig import kinematics, skinning

CHILD = {"gender": 0.3, "age": 0.15}


def _same_layer_pairs(faces: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    """(P,), (P,) the faces of every edge shared by two faces of one cloth layer (the
    inner layer's vertices are the first ``count``)."""
    inner, outer = (faces < count).all(axis=1), (faces >= count).all(axis=1)
    edges = np.sort(np.stack([faces, np.roll(faces, -1, axis=1)], -1).reshape(-1, 2), axis=1)
    owner = np.repeat(np.arange(len(faces)), faces.shape[1])
    order = np.lexsort(edges.T[::-1])
    edges, owner = edges[order], owner[order]
    shared = np.all(edges[1:] == edges[:-1], axis=1)
    a, b = owner[:-1][shared], owner[1:][shared]
    same = (inner[a] & inner[b]) | (outer[a] & outer[b])
    return a[same], b[same]


def _fold_degrees(v: np.ndarray, faces: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    q = v[faces]
    n = np.cross(q[:, 2] - q[:, 0], q[:, -1] - q[:, 1])
    n /= np.maximum(np.linalg.norm(n, axis=1), 1e-12)[:, None]
    return np.degrees(np.arccos(np.clip(np.einsum("nd,nd->n", n[a], n[b]), -1, 1)))


def test_a_hem_pushed_by_the_calf_bends_round_it_not_at_one_point():
    """The back leg's calf sweeps into a child's flared hem early in the stride; each hem
    point was pushed out of it on its own (8 and 15 mm) while its neighbours stayed, and
    two faces of the cloth turned 43 and 56 degrees against each other from rest (a
    faceted flap at the hem; 33 and 41 now). Each point's push is now shared with the
    cloth round it: within 12 cm of the hem no two faces of one layer turn more than 48
    degrees against each other from rest."""
    human = Human(CHILD).dressed("dress")
    fitted = human.outfit.garments[0]
    count = len(fitted.garment.mesh.vertices)
    faces = fitted.mesh.faces
    a, b = _same_layer_pairs(faces, count)
    rest = fitted.mesh.vertices.astype(np.float64)
    low = rest[faces[a]][:, :, 2].mean(axis=1) < rest[:count, 2].min() + 0.12
    at_rest = _fold_degrees(rest, faces, a, b)
    walk = human.walk(seconds=1.0, fps=24)
    for frame in (3, 4):
        world = kinematics.forward(human.skeleton, walk.rotations[frame:frame + 1],
                                   walk.translations[frame:frame + 1])  # fmt: skip
        matrices = kinematics.skinning_matrices(human.skeleton, world)[0]
        body = skinning.linear_blend(human.vertices, human.weights, matrices)
        v = human.outfit.frame(body, matrices, exact=True)[0].astype(np.float64)
        turn = (_fold_degrees(v, faces, a, b) - at_rest)[low]
        assert turn.max() < 48, (frame, turn.max())


def _hem_loop(faces: np.ndarray, v: np.ndarray) -> np.ndarray:
    """(H,) the lowest open edge loop of a mesh, in order round it."""
    edges = np.sort(np.stack([faces, np.roll(faces, -1, axis=1)], -1).reshape(-1, 2), axis=1)
    edges, n = np.unique(edges, axis=0, return_counts=True)
    ring: dict[int, list[int]] = {}
    for a, b in edges[n == 1]:
        ring.setdefault(int(a), []).append(int(b))
        ring.setdefault(int(b), []).append(int(a))
    loops, seen = [], set()
    for start in ring:
        if start in seen:
            continue
        loop, prev = [start], -1
        seen.add(start)
        while True:
            nxt = [n for n in ring[loop[-1]] if n != prev and n not in seen]
            if not nxt:
                break
            prev = loop[-1]
            loop.append(nxt[0])
            seen.add(nxt[0])
        loops.append(np.array(loop))
    return min(loops, key=lambda loop: v[loop, 2].mean())


def _turning_degrees(points: np.ndarray) -> np.ndarray:
    """(H,) degrees the closed polyline ``points`` (H, 3) turns at each of its points."""
    d = np.roll(points, -1, axis=0) - points
    d /= np.linalg.norm(d, axis=1)[:, None]
    return np.degrees(np.arccos(np.clip(np.einsum("nd,nd->n", d, np.roll(d, 1, axis=0)), -1, 1)))


@pytest.mark.parametrize(("name", "limit"), [("dress", 31), ("skirt", 28)])
def test_a_skirt_hem_bends_as_one_curve_over_the_knees_through_the_walk(name, limit):
    """A skirt's weights came from the body through its binding: they switched from thigh
    to shin within two rows above the knee and from one leg to both at a corner of the
    sides' blend, and the frames' 4-influence cut dropped a 5% shin weight on one hem
    vertex but not the next. Mid-stride the hem folded there (a notch over the knee): the
    dress's hem turned 48 degrees between two neighbouring vertices, the skirt's 39 (26
    and 30 at rest; 36 and 31 with its weights ramped from the hips down,
    ``weights.swing``). Then the hem followed one leg at the sides and both at the back,
    and the calf of the back leg pushed two hem points 4.4 cm out of their row and the
    next 1.7 cm: a notch at the back. Now the hips' and thighs' weights reach the hem and
    the calf's push is shared along the cloth, and its rows are rounded in plan below the
    hips (``clothes.hems``): 28 and 25.5 degrees (21 and 20 at rest)."""
    human = Human({"gender": 0.0, "age": 0.5}).dressed(name)
    fitted = human.outfit.garments[0]
    count = len(fitted.garment.mesh.vertices)
    hem = _hem_loop(fitted.garment.mesh.faces, fitted.mesh.vertices[:count])
    walk = human.walk(seconds=1.0, fps=24)
    worst = 0.0
    for frame in range(0, 12):
        world = kinematics.forward(human.skeleton, walk.rotations[frame:frame + 1],
                                   walk.translations[frame:frame + 1])  # fmt: skip
        matrices = kinematics.skinning_matrices(human.skeleton, world)[0]
        body = skinning.linear_blend(human.vertices, human.weights, matrices)
        v = human.outfit.frame(body, matrices, exact=True)[0].astype(np.float64)
        worst = max(worst, float(_turning_degrees(v[hem]).max()))
    assert worst < limit, worst


@pytest.mark.parametrize("name", ["dress", "skirt"])
def test_skirt_weights_ramp_down_its_length(name):
    """No bone's weight changes by more than 0.2 across one edge of the skirt below the
    hips (it changed by 0.45, thigh to shin, between two rows above the knee)."""
    from avatar.clothes.library import authoring_body

    human = Human({"gender": 0.0, "age": 0.5}).dressed(name)
    garment = human.outfit.garments[0].garment
    hips = float(authoring_body().marks.hip[:, 2].mean())
    w = human.outfit.surface_weights[0]
    n = len(garment.mesh.vertices)
    dense = np.zeros((n, len(human.skeleton.names)))
    np.add.at(dense, (np.repeat(np.arange(n), w.indices.shape[1]), w.indices.ravel()),
              w.weights.ravel())  # fmt: skip
    faces = garment.mesh.faces
    edges = np.unique(np.sort(np.stack([faces, np.roll(faces, -1, axis=1)], -1)
                              .reshape(-1, 2), axis=1), axis=0)  # fmt: skip
    low = (garment.mesh.vertices[edges, 2] < hips).all(axis=1)
    step = np.abs(dense[edges[low, 0]] - dense[edges[low, 1]]).max(axis=1)
    assert step.max() < 0.2, step.max()  # 0.38 before
    np.testing.assert_allclose(dense.sum(axis=1), 1, atol=1e-5)

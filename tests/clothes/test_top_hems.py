"""A loose top's hem mid-stride (issue 14, eleventh pass): the cardigan's, the hoodie's and
the jacket's hem, measured along the fold of the hem band on the posed garment, as exports
have it."""

from __future__ import annotations

import numpy as np
import pytest

from avatar.human import Human
from avatar.rig import kinematics, skinning

WOMAN = {"gender": 0.0, "age": 0.45}
HEAVY_MAN = {"gender": 1.0, "weight": 0.9, "age": 0.6}
CHILD = {"age": 0.15}
OUTFITS = {"cardigan": ("tshirt", "cardigan", "skirt", "leggings"),
           "hoodie": ("hoodie", "sweatpants"),
           "jacket": ("tshirt", "jacket", "jeans")}  # fmt: skip
STRIDE = (4, 6, 8, 16, 18, 20)  # frames of 24 into the built-in walk: legs apart
LIP = 0.0015  # m: ``authoring.banded`` joins each hem point to its lifted twin this far out
STEP = 0.025  # m between the points the hem is resampled at (a few rows of stitches)


def _hem_fold(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(H,) the garment's lowest fold line (the open edge its hem band is turned over at:
    the vertices joined to their lifted twins by the band's lip, ``LIP`` long on the
    authored mesh ``vertices`` (N, 3)), in order along it."""
    a, b = faces.reshape(-1), np.roll(faces, -1, axis=1).reshape(-1)
    lip = np.abs(np.linalg.norm(vertices[a] - vertices[b], axis=1) - LIP) < 1e-4
    fold = set(np.minimum(a[lip], b[lip]).tolist())
    lip_faces = faces[np.unique(np.repeat(np.arange(len(faces)), faces.shape[1])[lip])]
    ring: dict[int, set[int]] = {}
    for face in lip_faces.tolist():
        for p, q in zip(face, face[1:] + face[:1], strict=True):
            if p in fold and q in fold and p != q:
                ring.setdefault(p, set()).add(q)
                ring.setdefault(q, set()).add(p)
    lines, seen = [], set()
    for start in sorted(ring, key=lambda i: len(ring[i])):  # an open line's end first
        if start in seen:
            continue
        line = [start]
        seen.add(start)
        while nxt := [n for n in ring[line[-1]] if n not in seen]:
            line.append(nxt[0])
            seen.add(nxt[0])
        lines.append(np.array(line))
    return min(lines, key=lambda line: vertices[line, 2].min())


def _hem_run(fold: np.ndarray, authored: np.ndarray) -> np.ndarray:
    """(R,) the fold's vertices along the bottom hem, in order, from the corner where it
    meets an open front to the other (or all round, closed): those within 10 cm of its
    lowest height whose second neighbours on the fold either way lie more across than
    above one another on the ``authored`` mesh (N, 3) (the same on every body), and the
    corner beyond each end."""
    p = authored[fold]
    d = np.roll(p, -2, axis=0) - np.roll(p, 2, axis=0)
    keep = (np.abs(d[:, 2]) < 0.5 * np.hypot(d[:, 0], d[:, 1])) & (p[:, 2] < p[:, 2].min() + 0.1)
    if keep.all():
        return np.append(fold, fold[0])  # a closed hem, round to its start
    start = np.flatnonzero(keep & ~np.roll(keep, 1))[0]  # the run after a gap
    order = np.roll(np.arange(len(fold)), -start)
    run = order[np.cumprod(keep[order]).astype(bool)]
    return fold[np.arange(run[0] - 1, run[0] + len(run) + 1) % len(fold)]


def _kinks(points: np.ndarray) -> float:
    """Degrees: the largest change of slope (up or down the body) between consecutive
    chords of a polyline (P, 3) resampled every ``STEP`` m along it."""
    along = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])
    at = np.arange(0.0, along[-1], STEP)
    q = np.stack([np.interp(at, along, points[:, k]) for k in range(3)], axis=1)
    d = np.diff(q, axis=0)
    slope = np.degrees(np.arctan2(d[:, 2], np.hypot(d[:, 0], d[:, 1])))
    return float(np.abs(np.diff(slope)).max())


def _back_tilt(v: np.ndarray, run: np.ndarray, rest: np.ndarray) -> float:
    """m: how much higher the back hem hangs 6-14 cm to the left of the midline than to
    the right (run: hem vertices, v and rest (N, 3) posed and at rest)."""
    back = run[rest[run, 1] > 0]
    x = rest[back, 0]
    left, right = back[(x > 0.06) & (x < 0.14)], back[(x < -0.06) & (x > -0.14)]
    return float(v[left, 2].mean() - v[right, 2].mean())


@pytest.mark.parametrize("name", ["cardigan", "hoodie", "jacket"])
@pytest.mark.parametrize("params", [WOMAN, HEAVY_MAN, CHILD], ids=["woman", "heavy", "child"])
def test_loose_top_hems_swing_as_one_piece_mid_stride(name, params):
    """Bound to the skin under it, a loose top's hem took 80% of its weights from the
    thighs: mid-stride its back hem hung 25-52 mm higher on one side than the other (a
    diagonal that looked torn), and it zig-zagged where the thighs' weights gave way to
    the spine's (the cardigan's front corners) or where the frames' four bones kept one
    thigh of the hoodie's back midline but not the other (a notch): its slope changed by
    up to 45-48 degrees between 2.5 cm chords (the hoodie's 3-5 at rest); the open
    cardigan's hem, not levelled at all, already by 20-29 at rest on the woman and the
    heavy man. Now the top hangs from the waist and its open hem is levelled: the back
    hem stays within 15 mm of level side to side, and its slope changes by under 20
    degrees, at rest and through the stride. The jacket, open in front and cut as long,
    had the same diagonal (30-35 mm) and kinks (42-45 degrees)."""
    human = Human(params).dressed(*OUTFITS[name])
    at = [g.name for g in human.outfit].index(name)
    fitted = human.outfit[at]
    count = len(fitted.garment.mesh.vertices)
    rest = fitted.mesh.vertices[:count].astype(np.float64)
    authored = fitted.garment.mesh.vertices.astype(np.float64)
    run = _hem_run(_hem_fold(authored, fitted.garment.mesh.faces), authored)
    assert len(run) > 20
    kinks, tilts = [_kinks(rest[run])], []
    walk = human.walk(seconds=1.0, fps=24)
    for frame in STRIDE:
        world = kinematics.forward(human.skeleton, walk.rotations[frame:frame + 1],
                                   walk.translations[frame:frame + 1])  # fmt: skip
        matrices = kinematics.skinning_matrices(human.skeleton, world)[0]
        body = skinning.linear_blend(human.vertices, human.weights, matrices)
        v = human.outfit.frame(body, matrices, exact=True)[at][:count].astype(np.float64)
        kinks.append(_kinks(v[run]))
        tilts.append(abs(_back_tilt(v, run, rest)))
    report = (np.round(kinks, 1), np.round(np.array(tilts) * 1000, 1))  # rest + STRIDE; mm
    assert max(kinks) < 20, report
    assert max(tilts) < 0.015, report

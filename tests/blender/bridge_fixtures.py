"""Tiny synthetic characters for bridge tests: a branching skeleton and a skinned box."""

from __future__ import annotations

import numpy as np

from avatar.mesh import Mesh
from avatar.rig.skeleton import Animation, Skeleton


def bone_matrix(head: np.ndarray, tail: np.ndarray, roll_axis: np.ndarray) -> np.ndarray:
    """(4, 4) rest matrix: Y along head->tail, Z as close to ``roll_axis`` as possible."""
    y = (tail - head) / np.linalg.norm(tail - head)
    x = np.cross(y, roll_axis)
    x /= np.linalg.norm(x)
    z = np.cross(x, y)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = x, y, z, head
    return m


def skeleton(rng: np.random.Generator) -> Skeleton:
    """Six bones: root -> spine -> (left arm -> hand, right arm), random directions and rolls."""
    parents = np.array([-1, 0, 1, 2, 1, 0], dtype=np.int32)
    names = ("root", "spine", "arm.L", "hand.L", "arm.R", "leg.L")
    heads = np.zeros((6, 3))
    tails = np.zeros((6, 3))
    heads[0] = [0.0, 0.0, 1.0]
    for j, p in enumerate(parents):
        if p >= 0:
            heads[j] = tails[p]
        tails[j] = heads[j] + rng.normal(size=3) * 0.2 + [0, 0, 0.15]
    rest = np.stack(
        [bone_matrix(h, t, rng.normal(size=3)) for h, t in zip(heads, tails, strict=True)]
    )
    return Skeleton(names, parents, rest, tails)


def random_animation(skel: Skeleton, rng: np.random.Generator, frames: int = 4) -> Animation:
    """Random unit quaternions on every bone, root translation."""
    q = rng.normal(size=(frames, len(skel.names), 4))
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    t = np.zeros((frames, len(skel.names), 3))
    t[:, 0] = rng.normal(size=(frames, 3)) * 0.3
    return Animation(q, t, 30.0, skel.names)


def grid_mesh(n: int = 4, size: float = 1.0) -> Mesh:
    """An n x n quad grid in the XZ plane (facing -Y) with per-corner UVs."""
    u, v = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1))
    verts = np.stack([u.ravel() * size, np.zeros(u.size), v.ravel() * size + 0.5], -1)
    idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    faces = np.stack(
        [idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel(), idx[1:, :-1].ravel()],
        -1,
    ).astype(np.int32)
    uvs = np.stack([u.ravel(), v.ravel()], -1).astype(np.float32)
    return Mesh(verts.astype(np.float32), faces, uvs, faces.copy())


def identity_quaternions(frames: int, joints: int) -> np.ndarray:
    q = np.zeros((frames, joints, 4))
    q[..., 0] = 1.0
    return q


def box_mesh(lo, hi) -> Mesh:
    """An axis-aligned box of 6 outward-facing quads with a simple UV per corner."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    verts = np.array(
        [[x, y, z] for z in (z0, z1) for y in (y0, y1) for x in (x0, x1)], dtype=np.float32
    )
    faces = np.array(
        [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]],
        dtype=np.int32,
    )
    uvs = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=np.float32)
    return Mesh(verts, faces, uvs, np.tile(np.arange(4, dtype=np.int32), (6, 1)))


def figure(rng: np.random.Generator, name: str = "figure"):
    """A skinned box on a random skeleton: a minimal Character for render tests."""
    from avatar.blender.scene import Character
    from avatar.part import MeshPart as Part

    skel = skeleton(rng)
    body = box_mesh((-0.2, -0.12, 0.0), (0.2, 0.12, 1.7))
    weights = (np.zeros((8, 1), np.int32), np.ones((8, 1)))
    head = box_mesh((-0.1, -0.1, 1.72), (0.1, 0.1, 1.95))
    return Character(
        name, [Part("body", body, skin=weights), Part("head", head, skin=weights)], skel
    )

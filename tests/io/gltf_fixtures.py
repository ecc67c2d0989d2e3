"""Tiny synthetic scenes for the glTF tests: skinned boxes, a three-bone skeleton, a clip."""

from __future__ import annotations

import numpy as np

from avatar.material import Material
from avatar.mesh import Mesh
from avatar.part import MeshPart
from avatar.rig import quaternion
from avatar.rig.skeleton import Animation, Skeleton

# A unit cube's 8 corners and 6 outward quads; every face has its own 4 UVs (all seams).
CUBE_CORNERS = np.array(
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]],
    dtype=np.float32,
)
CUBE_QUADS = np.array(
    [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
)


def box(lo, hi, uv_offset=0.0) -> Mesh:
    """A box mesh (8 vertices, 6 quads) with a UV square per face, packed in a strip."""
    lo, hi = np.asarray(lo, np.float32), np.asarray(hi, np.float32)
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32) * 0.15
    uvs = np.concatenate([square + [0.02 + 0.16 * f, uv_offset] for f in range(6)])
    return Mesh(
        vertices=lo + CUBE_CORNERS * (hi - lo),
        faces=CUBE_QUADS.astype(np.int32),
        uvs=uvs.astype(np.float32),
        face_uvs=np.arange(24, dtype=np.int32).reshape(6, 4),
    )


def two_boxes() -> Mesh:
    """Two stacked boxes (a 'limb' 2 m tall) as one mesh of 16 vertices and 12 quads."""
    a, b = (
        box([-0.1, -0.1, 0.0], [0.1, 0.1, 1.0], 0.1),
        box([-0.1, -0.1, 1.0], [0.1, 0.1, 2.0], 0.5),
    )
    return Mesh(
        vertices=np.concatenate([a.vertices, b.vertices]),
        faces=np.concatenate([a.faces, b.faces + 8]).astype(np.int32),
        uvs=np.concatenate([a.uvs, b.uvs]),
        face_uvs=np.concatenate([a.face_uvs, b.face_uvs + 24]).astype(np.int32),
    )


def bone_matrix(head, tail, roll: float) -> np.ndarray:
    """(4, 4) Blender-style rest matrix: Y along head->tail, X/Z turned by ``roll``."""
    head, tail = np.asarray(head, float), np.asarray(tail, float)
    y = (tail - head) / np.linalg.norm(tail - head)
    x = np.cross(y, [0.0, 0.0, 1.0]) if abs(y[2]) < 0.9 else np.cross(y, [0.0, -1.0, 0.0])
    x /= np.linalg.norm(x)
    z = np.cross(x, y)
    c, s = np.cos(roll), np.sin(roll)
    x, z = c * x - s * z, s * x + c * z
    m = np.eye(4)
    m[:3, :3] = np.stack([x, y, z], axis=1)
    m[:3, 3] = head
    return m


def skeleton() -> Skeleton:
    """root (0,0,0)->(0,0,1); spine (0,0,1)->(0,0,2); arm (0,0,1.5)->(0.6,0,1.5), rolled."""
    heads = [(0, 0, 0), (0, 0, 1), (0, 0, 1.5)]
    tails = [(0, 0, 1), (0, 0, 2), (0.6, 0, 1.5)]
    rolls = [0.0, 0.3, -1.2]
    rest = np.stack([bone_matrix(h, t, r) for h, t, r in zip(heads, tails, rolls, strict=True)])
    return Skeleton(
        ("root", "spine", "arm"),
        np.array([-1, 0, 1], np.int32),
        rest,
        np.array(tails, float),
        {"name": "Rig"},
    )


def chain(count: int) -> Skeleton:
    """``count`` bones stacked along +Z, 0.25 m each, rolls varying."""
    heads = np.stack([np.zeros(count), np.zeros(count), 0.25 * np.arange(count)], axis=1)
    tails = heads + (0.0, 0.0, 0.25)
    rest = np.stack(
        [bone_matrix(h, t, 0.4 * i) for i, (h, t) in enumerate(zip(heads, tails, strict=True))]
    )
    parents = np.arange(count, dtype=np.int32) - 1
    return Skeleton(tuple(f"bone{i}" for i in range(count)), parents, rest, tails)


def skin_weights(mesh: Mesh, k: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """(V, k) influences blending root->spine along Z, a little 'arm', zero-padded to k."""
    z = mesh.vertices[:, 2] / 2.0
    w = np.stack([1.0 - z, z, 0.1 * z], axis=1)
    idx = np.tile(np.arange(3), (len(z), 1))
    if k > 3:  # spread the same weights over duplicated and extra slots
        idx = np.concatenate([idx, idx[:, : k - 3]], axis=1)
        w = np.concatenate([w * 0.5, w[:, : k - 3] * 0.5], axis=1)
        w[:, : k - 3] *= 1.0  # first copies keep half, duplicates carry the other half
    return idx.astype(np.int32), w


def many_influences(count: int, k: int = 7, joints: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """(count, k) random influences, joints repeating within a vertex when k > joints."""
    rng = np.random.default_rng(1)
    return rng.integers(0, joints, (count, k)).astype(np.int32), rng.random((count, k)) + 0.05


def clip(sk: Skeleton, frames: int = 12, fps: float = 24.0) -> Animation:
    """A bend-and-twist clip with root motion; some quaternions have w < 0 on purpose."""
    t = np.arange(frames) / fps
    axes = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.2], [0.3, 0.0, 1.0]])
    angles = np.stack([np.sin(3 * t), 2.5 * np.sin(2 * t) + 3.5, 0.8 * np.cos(4 * t)], axis=1)
    rotations = quaternion.from_axis_angle(np.broadcast_to(axes, (frames, 3, 3)), angles)
    translations = np.zeros((frames, 3, 3))
    translations[:, 0] = np.stack([0.1 * t, 0.5 * t, 0.02 * np.sin(5 * t)], axis=1)
    return Animation(rotations, translations, fps, sk.names)


def checker(size: int = 64, channels: int = 3) -> np.ndarray:
    """(size, size, channels) uint8 checkerboard with a gradient (compressible, non-trivial)."""
    y, x = np.mgrid[:size, :size]
    board = ((x // 8 + y // 8) % 2) * 120 + (x * 2) % 100
    image = np.stack([board, (y * 3) % 256, 255 - board] + [np.full_like(board, 200)] * 2, -1)
    return image[..., :channels].astype(np.uint8)


def scene() -> tuple[list[MeshPart], Skeleton, Animation]:
    """A skinned, morphing, textured limb plus a rigid textured box; the skeleton; a clip."""
    sk = skeleton()
    limb = two_boxes()
    bulge = np.zeros_like(limb.vertices)
    bulge[8:, :2] = limb.vertices[8:, :2] * 0.5
    poke = np.zeros_like(limb.vertices)
    poke[3] = (0.0, 0.0, 0.05)
    skin_mat = Material(
        "skin",
        base_color_texture=checker(64),
        roughness=0.6,
        roughness_texture=checker(32, 1)[..., 0],
        extras={"subsurface": 0.1},
    )
    parts = [
        MeshPart(
            "limb",
            limb,
            skin_mat,
            skin_weights(limb),
            {"bulge": bulge, "poke": poke, "nothing": np.zeros_like(poke)},
        ),
        MeshPart(
            "crate",
            box([1, 1, 0], [1.5, 1.5, 0.5]),
            Material(
                "crate",
                (1.0, 0.9, 0.8, 1.0),
                checker(16, 4),
                checker(16),
                alpha_mode="MASK",
                double_sided=True,
            ),
        ),
    ]
    return parts, sk, clip(sk)

"""Place a rig's joints on a shaped mesh, as MPFB/MakeHuman do.

Each bone end (head/tail) in a rig file names a strategy: ``CUBE`` (centre of a
``joint-*`` helper cube), ``VERTEX`` (one vertex), ``MEAN`` (mean of listed vertices) or
``XYZ`` (x, y, z taken from three vertices), plus an optional ``offset``. Rolls become
rest matrices with Blender's own ``vec_roll_to_mat3``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from avatar.errors import FormatError
from avatar.rig.quaternion import from_axis_angle, to_matrix
from avatar.rig.skeleton import Skeleton


@dataclass(frozen=True)
class RigDefinition:
    """A rig file compiled to index arrays, so placing it is a few array operations.

    ends: 2J bone ends (heads then tails), each the mean of up to P vertex coordinates:
    ``vertex[e, p]`` and ``axis[e, p]`` (which coordinate each term feeds; -1 pads) with
    ``count[e, axis]`` terms per axis.
    """

    name: str
    names: tuple[str, ...]
    parents: np.ndarray
    rolls: np.ndarray
    vertex: np.ndarray
    axis: np.ndarray
    offsets: np.ndarray
    defaults: np.ndarray  # (2J, 3) stored default_position (heads then tails)

    @classmethod
    def from_json(cls, name: str, bones: dict, groups: dict[str, np.ndarray]) -> RigDefinition:
        order = _topological(bones, name)
        index = {b: i for i, b in enumerate(order)}
        ends = [bones[b][k] for k in ("head", "tail") for b in order]
        terms = [_terms(e, groups, name) for e in ends]
        width = max(len(t) for t in terms)
        vertex = np.zeros((len(ends), width), dtype=np.int64)
        axis = np.full((len(ends), width), -1, dtype=np.int64)
        for e, t in enumerate(terms):
            for p, (v, a) in enumerate(t):
                vertex[e, p], axis[e, p] = v, a
        return cls(
            name=name,
            names=tuple(order),
            parents=np.array(
                [index.get(bones[b].get("parent") or "", -1) for b in order], np.int32
            ),
            rolls=np.array([float(bones[b].get("roll", 0.0)) for b in order]),
            vertex=vertex,
            axis=axis,
            offsets=np.array([e.get("offset", (0.0, 0.0, 0.0)) for e in ends], dtype=np.float64),
            defaults=np.array(
                [e.get("default_position", (0.0, 0.0, 0.0)) for e in ends], np.float64
            ),
        )

    @cached_property
    def _weights(self) -> np.ndarray:
        """(2J, P, 3) averaging weights: 1/count on the axis each term feeds."""
        w = np.zeros(self.vertex.shape + (3,))
        for a in range(3):
            hit = (self.axis == a) | (self.axis == 3)
            w[..., a] = hit / np.maximum(hit.sum(axis=1, keepdims=True), 1)
        return w

    def joint_positions(self, vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Heads (J, 3) and tails (J, 3) on ``vertices`` (V, 3) or a batch (..., V, 3)."""
        v = np.asarray(vertices)[..., self.vertex, :].astype(np.float64)  # (..., 2J, P, 3)
        ends = np.sum(v * self._weights, axis=-2) + self.offsets
        j = len(self.names)
        return ends[..., :j, :], ends[..., j:, :]

    def skeleton(self, vertices: np.ndarray) -> Skeleton:
        """The rig placed on a shaped mesh (V, 3), in rest pose."""
        heads, tails = self.joint_positions(vertices)
        return Skeleton(self.names, self.parents, rest_matrices(heads, tails, self.rolls), tails)


def _topological(bones: dict, rig: str) -> list[str]:
    """Bone names with parents first (stable: file order among siblings)."""
    order: list[str] = []
    placed: set[str] = set()

    def visit(b: str, depth: int = 0) -> None:
        if b in placed:
            return
        if depth > len(bones):
            raise FormatError(f"rig.{rig}.json", 0, f"cycle in the bone hierarchy at {b!r}")
        parent = bones[b].get("parent")
        if parent:
            if parent not in bones:
                raise FormatError(f"rig.{rig}.json", 0, f"bone {b!r} has unknown parent {parent!r}")
            visit(parent, depth + 1)
        placed.add(b)
        order.append(b)

    for b in bones:
        visit(b)
    return order


def _terms(end: dict, groups: dict[str, np.ndarray], rig: str) -> list[tuple[int, int]]:
    """(vertex, axis) terms of a bone end; axis 3 means all three coordinates."""
    strategy = end.get("strategy")
    try:
        if strategy == "CUBE":
            return [(int(v), 3) for v in groups[end["cube_name"]]]
        if strategy == "VERTEX":
            return [(int(end["vertex_index"]), 3)]
        if strategy == "MEAN":
            return [(int(v), 3) for v in end["vertex_indices"]]
        if strategy == "XYZ":
            return [(int(v), a) for a, v in enumerate(end["vertex_indices"][:3])]
    except KeyError as exc:
        raise FormatError(f"rig.{rig}.json", 0, f"bone end {end} lacks {exc}") from None
    raise FormatError(f"rig.{rig}.json", 0, f"unknown placement strategy {strategy!r}")


def rest_matrices(heads: np.ndarray, tails: np.ndarray, rolls: np.ndarray) -> np.ndarray:
    """(..., J, 4, 4) bone rest matrices from heads, tails (..., J, 3) and rolls (J,).

    Blender's ``vec_roll_to_mat3_normalized`` (armature.cc), vectorised: the rotation taking
    +Y to the bone direction by the shortest arc, then the roll about the bone.
    """
    vec = tails - heads
    nor = vec / np.maximum(np.linalg.norm(vec, axis=-1, keepdims=True), 1e-12)
    x, y, z = nor[..., 0], nor[..., 1], nor[..., 2]
    theta = 1.0 + y
    theta_alt = x * x + z * z
    theta = np.where(theta <= 6.1e-3, theta_alt * 0.5 + theta_alt**2 * 0.125, theta)
    degenerate = (1.0 + y <= 6.1e-3) & (theta_alt <= 2.5e-4**2)
    theta = np.where(degenerate, 1.0, theta)
    b = np.zeros(nor.shape[:-1] + (3, 3))
    b[..., :, 0] = np.stack([1 - x * x / theta, -x, -x * z / theta], -1)
    b[..., :, 1] = nor
    b[..., :, 2] = np.stack([-x * z / theta, -z, 1 - z * z / theta], -1)
    b[degenerate] = np.diag([-1.0, -1.0, 1.0])

    roll = to_matrix(from_axis_angle(nor, np.broadcast_to(rolls, nor.shape[:-1])))
    out = np.zeros(nor.shape[:-1] + (4, 4))
    out[..., :3, :3] = roll @ b
    out[..., :3, 3] = heads
    out[..., 3, 3] = 1.0
    return out


def roll_from_matrix(rest: np.ndarray) -> np.ndarray:
    """Inverse of ``rest_matrices`` for the roll: (..., 4, 4) -> (...,) radians."""
    nor = rest[..., :3, 1]
    zero = rest_matrices(np.zeros_like(nor), nor, np.zeros(nor.shape[:-1]))
    b = zero[..., :3, :3]
    r = rest[..., :3, :3] @ np.swapaxes(b, -1, -2)  # the roll rotation about nor
    cos = np.clip((np.trace(r, axis1=-2, axis2=-1) - 1) / 2, -1, 1)
    sin_axis = np.stack([r[..., 2, 1] - r[..., 1, 2], r[..., 0, 2] - r[..., 2, 0],
                         r[..., 1, 0] - r[..., 0, 1]], -1) / 2  # fmt: skip
    return np.arctan2(np.sum(sin_axis * nor, axis=-1), cos)

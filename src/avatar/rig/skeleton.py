"""Skeleton and animation records (Blender's bone conventions)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from avatar.errors import unknown_name


@dataclass(frozen=True)
class Skeleton:
    """A bone hierarchy in rest pose.

    names: J bone names; parents precede children.
    parents: (J,) int32 parent index, -1 for a root.
    rest: (J, 4, 4) float64 bone-to-world rest matrices in metres. As in Blender, the bone's
        local Y axis runs from head to tail, the roll turns X/Z about it, and the translation
        is the head.
    tails: (J, 3) float64 tail positions (metres).
    """

    names: tuple[str, ...]
    parents: np.ndarray
    rest: np.ndarray
    tails: np.ndarray
    extra: dict[str, object] = field(default_factory=dict, compare=False)

    @property
    def heads(self) -> np.ndarray:
        """(J, 3) head positions."""
        return self.rest[:, :3, 3]

    @property
    def lengths(self) -> np.ndarray:
        """(J,) bone lengths (metres)."""
        return np.linalg.norm(self.tails - self.heads, axis=-1)

    def index(self, name: str) -> int:
        """Index of a bone by name; raises ParameterError listing close matches."""
        try:
            return self.names.index(name)
        except ValueError:
            raise unknown_name("bone", name, self.names) from None

    def local_rest(self) -> np.ndarray:
        """(J, 4, 4) rest matrices relative to the parent's rest frame."""
        out = self.rest.copy()
        has = self.parents >= 0
        out[has] = np.linalg.inv(self.rest[self.parents[has]]) @ self.rest[has]
        return out


@dataclass(frozen=True)
class Animation:
    """Per-frame bone rotations and root motion, relative to a skeleton's rest pose.

    rotations: (T, J, 4) float64 unit quaternions (w, x, y, z) in each bone's rest frame,
        exactly Blender's pose-bone ``rotation_quaternion``.
    translations: (T, J, 3) float64 offsets in each bone's rest frame (Blender's pose-bone
        ``location``); usually zero except on the root.
    fps: frames per second.
    bone_names: the J names the arrays refer to (matching a Skeleton).
    """

    rotations: np.ndarray
    translations: np.ndarray
    fps: float
    bone_names: tuple[str, ...]

    @property
    def frames(self) -> int:
        return int(self.rotations.shape[0])

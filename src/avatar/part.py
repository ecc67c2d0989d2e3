"""MeshPart: one mesh with its material, skin weights and morph targets, as exporters take it."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from avatar.material import Material
from avatar.mesh import Mesh


@dataclass(frozen=True, eq=False)
class MeshPart:
    """A named mesh ready to export (body, eyes, one garment, ...).

    name: object name in the exported file.
    mesh: the geometry (Avatar frame: metres, Z-up, facing -Y), with UVs when textured.
    material: its material, or None for a default grey one.
    skin: ``(indices (V, K) int, weights (V, K) float)`` per mesh vertex into the skeleton's
        joints, any K; or None for a rigid part.
    morphs: name -> (V, 3) position deltas in metres (blend shapes).
    normals: (V, 3) unit vertex normals, or None to compute area-weighted ones.
    """

    name: str
    mesh: Mesh
    material: Material | None = None
    skin: tuple[np.ndarray, np.ndarray] | None = None
    morphs: dict[str, np.ndarray] = field(default_factory=dict)
    normals: np.ndarray | None = None

    def __post_init__(self) -> None:
        count = len(self.mesh.vertices)
        if self.skin is not None:
            idx, w = self.skin
            if idx.shape != w.shape or idx.ndim != 2 or idx.shape[0] != count:
                raise ValueError(
                    f"skin of {self.name!r} must be two (V={count}, K) arrays, "
                    f"got {idx.shape} and {w.shape}"
                )
        for key, delta in self.morphs.items():
            if np.shape(delta) != (count, 3):
                raise ValueError(
                    f"morph {key!r} of {self.name!r} must be (V={count}, 3), got {np.shape(delta)}"
                )
        if self.normals is not None and np.shape(self.normals) != (count, 3):
            raise ValueError(f"normals of {self.name!r} must be (V={count}, 3)")

"""A swinging skirt's pushes shared along its cloth with a smooth falloff.

Mid-stride the calf of the back leg sweeps into a dress's flared hem from behind. The
frames push each hem point out of the skin it was anchored to on its own, and share a push
with the cloth only two rings of neighbours round it (``outfit._spread_pushes``): the hem
points the calf met stood 4.4 cm out of their row and the next one 1.7 cm, so the hem
turned 36 degrees at one point (26 at rest), a notch at the back. Here the swinging rows
(below the hips, ``Garment.swing_below``) share each push with all cloth within
``HEM_REACH`` at rest, scaled by a bell that is flat at the pushed point and zero at the
reach, so the hem bends round the calf as one curve.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import csc_matrix
from scipy.spatial import cKDTree

HEM_REACH = 0.15  # m at rest: the cloth one push is shared with (a calf is ~12 cm across)
LEAST = 5e-4  # m: shorter pushes are left alone, as ``outfit.SPREAD_LEAST``


@dataclass(frozen=True, eq=False)
class HemSpread:
    """The swinging rows of an outfit's shells and each one's share of another's push."""

    rows: np.ndarray  # (H,) positions among the shell rows of the swinging cloth
    falloff: csc_matrix  # (H, H) float32 the share of row j's push that row i takes

    @classmethod
    def of(cls, rest: np.ndarray, swinging: np.ndarray, reach: float = HEM_REACH) -> HemSpread:
        """rest: (S, 3) the shell rows at rest; swinging: (S,) bool those that swing."""
        rows = np.flatnonzero(swinging)
        if len(rows) == 0:
            return cls(rows, csc_matrix((0, 0), dtype=np.float32))
        tree = cKDTree(rest[rows].astype(np.float64))
        near = tree.sparse_distance_matrix(tree, reach, output_type="coo_matrix")
        # (1 - (d/R)^2)^2: flat at the pushed point (no kink at the hem's peak) and
        # reaching zero with a flat tangent at the reach (no kink where it ends).
        share = (1.0 - (near.data / reach) ** 2) ** 2
        falloff = csc_matrix((share.astype(np.float32), (near.row, near.col)),
                             shape=(len(rows), len(rows)))  # fmt: skip
        falloff.setdiag(1.0)  # the distance matrix leaves out zero distances
        return cls(rows, csc_matrix(falloff, dtype=np.float32))

    def shared(self, push: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The shell rows' pushes (S, 3) made one smooth field along the swinging cloth:
        (T,) the swinging rows near a push and (T, 3) their push. Its length is the
        longest share of a push near the row (a max, not a sum: pushes side by side do not
        add up), its direction the shares' weighted mean: pushed out of a round calf each
        on its own, neighbouring hem points went out at angles 20 degrees apart, and the
        hem zig-zagged even where the lengths were shared."""
        if len(self.rows) == 0:
            return np.zeros(0, np.intp), np.zeros((0, 3), np.float32)
        own = push[self.rows]
        size = np.einsum("nd,nd->n", own, own)
        moved = np.flatnonzero(size > LEAST**2)
        if len(moved) == 0:
            return np.zeros(0, np.intp), np.zeros((0, 3), np.float32)
        share = self.falloff[:, moved].toarray()  # (H, M): few points are pushed
        length = (share * np.sqrt(size[moved])[None, :]).max(axis=1)
        toward = share @ own[moved]
        across = np.sqrt(np.einsum("nd,nd->n", toward, toward))
        take = np.flatnonzero((length > LEAST) & (across > 1e-9))
        pushed = toward[take] * (length[take] / across[take])[:, None]
        return self.rows[take], pushed.astype(np.float32)

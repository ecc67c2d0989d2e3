"""How a garment hangs on the body: MakeHuman's proxy binding and its evaluation.

Each garment vertex i refers to three body vertices ``a, b, c`` with barycentric weights
``w`` (which may be negative) and an offset ``d``:

    x_i = w_a X[a] + w_b X[b] + w_c X[c] + S d_i,    S = diag(|X[p_k, k] - X[q_k, k]| / L_k)

where the per-axis scale S compares the body's extent along axis k between two reference
vertices ``p_k, q_k`` with the same extent ``L_k`` on the body the garment was authored on
(MakeHuman 1.1 ``proxy.TMatrix``). Everything here is in Avatar's frame (metres, Z-up); the
``.mhclo`` reader converts MakeHuman's decimetre Y-up numbers once.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Binding:
    """A garment's attachment to the body (N garment vertices).

    indices: (N, 3) int32 body vertex indices (a single-vertex reference repeats its index).
    weights: (N, 3) float64 barycentric weights; (1, 0, 0) for single-vertex references.
    offsets: (N, 3) float64 offsets in metres, Avatar axes, before scaling.
    single: (N,) bool, True where the vertex was stored as a single-vertex reference.
    scale_refs: (3, 2) int32 body vertex pair measuring each Avatar axis (x, y, z);
        (-1, -1) for an axis without scaling (S = 1).
    scale_lengths: (3,) float64 the pair's extent along that axis on the authoring body (m).
    """

    indices: np.ndarray
    weights: np.ndarray
    offsets: np.ndarray
    single: np.ndarray
    scale_refs: np.ndarray
    scale_lengths: np.ndarray

    def __len__(self) -> int:
        return int(self.indices.shape[0])

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Binding):
            return NotImplemented
        return all(
            np.array_equal(getattr(self, k), getattr(other, k))
            for k in ("indices", "weights", "offsets", "single", "scale_refs", "scale_lengths")
        )

    __hash__ = None  # type: ignore[assignment]

    def subset(self, index: np.ndarray) -> Binding:
        """The binding of the garment vertices ``index`` only (e.g. after dropping faces)."""
        return Binding(
            self.indices[index],
            self.weights[index],
            self.offsets[index],
            self.single[index],
            self.scale_refs,
            self.scale_lengths,
        )


def make_binding(
    indices: np.ndarray,
    weights: np.ndarray,
    offsets: np.ndarray,
    scale_refs: np.ndarray | None = None,
    scale_lengths: np.ndarray | None = None,
    single: np.ndarray | None = None,
) -> Binding:
    """A Binding from array-likes, with dtypes and shapes normalised (no scaling by default)."""
    indices = np.asarray(indices, dtype=np.int32).reshape(-1, 3)
    n = len(indices)
    refs = np.full((3, 2), -1, np.int32) if scale_refs is None else scale_refs
    lengths = np.ones(3) if scale_lengths is None else scale_lengths
    return Binding(
        indices=indices,
        weights=np.asarray(weights, dtype=np.float64).reshape(n, 3),
        offsets=np.asarray(offsets, dtype=np.float64).reshape(n, 3),
        single=np.zeros(n, bool) if single is None else np.asarray(single, bool).reshape(n),
        scale_refs=np.asarray(refs, dtype=np.int32).reshape(3, 2),
        scale_lengths=np.asarray(lengths, dtype=np.float64).reshape(3),
    )


def axis_scale(binding: Binding, body_vertices: np.ndarray) -> np.ndarray:
    """(..., 3) per-axis offset scale S on a body (..., V, 3); 1 where an axis has no pair."""
    refs = binding.scale_refs
    has = refs[:, 0] >= 0
    safe = np.where(has[:, None], refs, 0)
    axis = np.arange(3)
    extent = np.abs(body_vertices[..., safe[:, 0], axis] - body_vertices[..., safe[:, 1], axis])
    return np.where(has, extent / np.where(has, binding.scale_lengths, 1.0), 1.0)


def fit(binding: Binding, body_vertices: np.ndarray) -> np.ndarray:
    """Garment vertices on a body.

    body_vertices: (..., V, 3) body (all base-mesh vertices, helpers included), metres.
    Returns (..., N, 3) float32 garment vertex positions.
    """
    x = np.asarray(body_vertices, dtype=np.float64)
    w = binding.weights
    ref = x[..., binding.indices, :]  # (..., N, 3 refs, 3 xyz)
    anchor = np.einsum("...nkc,nk->...nc", ref, w)
    scale = axis_scale(binding, x)[..., None, :]
    return (anchor + scale * binding.offsets).astype(np.float32)

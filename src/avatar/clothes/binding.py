"""How a garment hangs on the body: MakeHuman's proxy binding and its evaluation.

Each garment vertex i refers to three body vertices ``a, b, c`` with barycentric weights
``w`` (which may be negative) and an offset ``d``:

    x_i = w_a X[a] + w_b X[b] + w_c X[c] + S d_i,    S = diag(|X[p_k, k] - X[q_k, k]| / L_k)

where the per-axis scale S compares the body's extent along axis k between two reference
vertices ``p_k, q_k`` with the same extent ``L_k`` on the body the garment was authored on
(MakeHuman 1.1 ``proxy.TMatrix``). Everything here is in Avatar's frame (metres, Z-up); the
``.mhclo`` reader converts MakeHuman's decimetre Y-up numbers once.

The record itself (``Binding``, built by ``make_binding``) lives with its file format in
``avatar.io.mhclo``, so that io needs nothing from clothes; it is re-exported here.
"""

from __future__ import annotations

import numpy as np

from avatar.io.mhclo import Binding, make_binding

__all__ = ["Binding", "axis_scale", "fit", "make_binding"]


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

"""Z-buffered point splats: the small numpy pictures (pose and library thumbnails) are
surface points drawn nearest-first into a supersampled buffer and averaged down."""

from __future__ import annotations

import numpy as np


def splat(col: np.ndarray, row: np.ndarray, depth: np.ndarray, rgba: np.ndarray, size: int,
          supersample: int) -> np.ndarray:  # fmt: skip
    """(size, size, 4) float picture of points at pixel ``col``, ``row`` (N,) int of a
    (size x supersample) square buffer (outside it: dropped), the nearest (smallest
    ``depth``) of each pixel kept with its ``rgba`` (N, 4), then averaged over each
    supersample x supersample block: colour weighted by alpha (anti-aliased edges keep the
    colour of what covers them), alpha the covered share."""
    big = size * supersample
    inside = (col >= 0) & (col < big) & (row >= 0) & (row < big)
    pixel = row[inside] * big + col[inside]
    order = np.lexsort((depth[inside], pixel))  # per pixel, nearest first
    keep = order[np.unique(pixel[order], return_index=True)[1]]
    out = np.zeros((big * big, 4))
    out[pixel[keep]] = rgba[inside][keep]
    out[pixel[keep], :3] *= out[pixel[keep], 3:]  # premultiplied, for the averaging
    out = out.reshape(size, supersample, size, supersample, 4).mean(axis=(1, 3))
    alpha = out[..., 3:]
    out[..., :3] = np.where(alpha > 0, out[..., :3] / np.maximum(alpha, 1e-9), 0.0)
    return out

"""A garment's compact correction over a segment of a clip: principal shapes of its per-frame
bind-space deltas and their per-frame weights (``avatar.clothes.bake`` explains the method).

    basis = fit(corrections)             # the fewest principal shapes within ERROR_BOUND
    solve_weights(basis, corrections, t, pushed)   # one frame again, pushed vertices HEAVY
    basis = grow(basis, corrections, frames, most)  # a few sparse shapes for those frames
    morphs, weights = segment_targets(basis, vertices)   # as morph targets, weights in [0, 1]
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

ERROR_BOUND = 5e-4  # m: worst distance of a played-back garment vertex from its exact frame
MAX_BASIS = 16  # correction shapes a garment segment gets (fewer when they meet ERROR_BOUND)
LIMIT = 64  # most shapes a garment gets when ERROR_BOUND needs more than MAX_BASIS
UNMOVED = 1e-5  # m: residual rows shorter than this are round-off, not push-outs
GROW_BOUND = 1e-4  # m: how closely ``grow``'s shapes play the mended frames' push-outs
HEAVY = 100.0  # weight of pushed-out vertices in a frame's least-squares weights


@dataclass
class Corrections:
    """One garment's per-frame bind-space deltas, stored sparsely as they are computed."""

    vertices: int
    frames: int
    rows: dict[int, np.ndarray] = field(default_factory=dict)  # t -> (n,) moved vertices
    deltas: dict[int, np.ndarray] = field(default_factory=dict)  # t -> (n, 3) float32

    def add(self, t: int, delta: np.ndarray) -> None:
        rows = np.flatnonzero(np.any(delta != 0, axis=1))
        self.rows[t], self.deltas[t] = rows, np.asarray(delta[rows], dtype=np.float32)

    def matrix(self) -> tuple[np.ndarray, np.ndarray]:
        """(moved (U,) vertex indices, X (T, U, 3) float32 deltas of those vertices)."""
        moved = np.unique(np.concatenate([np.zeros(0, np.int64), *self.rows.values()]))
        x = np.zeros((self.frames, len(moved), 3), dtype=np.float32)
        for t, rows in self.rows.items():
            x[t, np.searchsorted(moved, rows)] = self.deltas[t]
        return moved, x


@dataclass(frozen=True)
class Basis:
    """A garment's compact correction over one segment: shapes (k, U, 3) over vertices
    ``moved`` (U,), weights (n, k) for the segment's n frames, and the worst per-vertex
    reconstruction error (m)."""

    moved: np.ndarray
    shapes: np.ndarray
    weights: np.ndarray
    error: float

    def moved_delta(self, t: int) -> np.ndarray:
        """(U, 3) float64 bind-space correction of the moved vertices at segment frame t."""
        return np.einsum("k,kvc->vc", self.weights[t].astype(np.float64), self.shapes)

    def delta(self, t: int, vertices: int) -> np.ndarray:
        """(vertices, 3) float64 bind-space correction this basis plays at segment frame t."""
        out = np.zeros((vertices, 3))
        out[self.moved] = self.moved_delta(t)
        return out


def solve_weights(basis: Basis, corrections: Corrections, t: int, pushed: np.ndarray) -> None:
    """Frame t's weights (in place): least squares to its target, vertices ``pushed`` (garment
    indices) weighted ``HEAVY``, so the frame keeps them out with the shapes it has."""
    if not len(basis.shapes):
        return
    target = np.zeros((len(basis.moved), 3))
    at = np.searchsorted(basis.moved, corrections.rows[t])
    inside = at < len(basis.moved)
    inside[inside] = basis.moved[at[inside]] == corrections.rows[t][inside]
    target[at[inside]] = corrections.deltas[t][inside]
    cost = np.ones(len(basis.moved))
    rows = np.searchsorted(basis.moved, pushed)
    found = rows < len(basis.moved)
    found[found] = basis.moved[rows[found]] == pushed[found]
    cost[rows[found]] = HEAVY
    shapes = basis.shapes.reshape(len(basis.shapes), -1).astype(np.float64)
    scaled = shapes * np.repeat(cost, 3)[None]
    lhs, rhs = scaled @ shapes.T, scaled @ target.reshape(-1)
    basis.weights[t] = np.linalg.lstsq(lhs, rhs, rcond=None)[0].astype(np.float32)


def refit(corrections: Corrections, bound: float, heavy: dict[int, np.ndarray]) -> Basis | None:
    """``fit`` to the mended frames, then their weights solved with their pushed vertices
    ``HEAVY``."""
    basis = fit(corrections, bound)
    for t, rows in heavy.items():
        if basis is not None:
            solve_weights(basis, corrections, t, rows)
    return basis


def grow(basis: Basis, corrections: Corrections, frames: list[int], most: int) -> Basis:
    """The basis with a few more shapes that play what ``frames`` miss of their targets
    (the push-outs a check made: sparse, a few vertices each), weighted on those frames
    only: the principal shapes of those residuals, at most ``most``, within
    ``GROW_BOUND``."""
    residual = np.zeros((len(frames), len(basis.moved), 3), dtype=np.float32)
    for r, t in enumerate(frames):
        at = np.searchsorted(basis.moved, corrections.rows[t])
        residual[r, at] = corrections.deltas[t]
        residual[r] -= basis.moved_delta(t)
    # Elsewhere the target is the played frame, up to float32 round-off: zero it, so the
    # shapes stay as sparse as the push-outs (a morph target stores only its non-zero rows).
    residual[np.linalg.norm(residual, axis=2) < UNMOVED] = 0.0
    shapes, weights, _ = fit_basis(residual, GROW_BOUND, most)
    out = np.zeros((len(basis.weights), len(basis.shapes) + len(shapes)), dtype=np.float32)
    out[:, : len(basis.shapes)] = basis.weights
    out[frames, len(basis.shapes) :] = weights
    return Basis(basis.moved, np.concatenate([basis.shapes, shapes]), out, basis.error)


def fit(corrections: Corrections, bound: float = ERROR_BOUND) -> Basis | None:
    """The compact basis of one garment's corrections (``fit_basis``), None without any."""
    if not corrections.rows:
        return None
    moved, x = corrections.matrix()
    shapes, weights, error = fit_basis(x, bound, MAX_BASIS)
    return Basis(moved, shapes, weights, error)


def fit_basis(x: np.ndarray, bound: float = ERROR_BOUND, limit: int = LIMIT) -> tuple[
    np.ndarray, np.ndarray, float
]:  # fmt: skip
    """The fewest principal shapes of per-frame deltas that reproduce every frame within
    ``bound``: x (T, U, 3) -> shapes (k, U, 3) float32 orthonormal (flattened), weights
    (T, k) float32 (projections, so frames without correction get 0), worst error (m).

    k is the smallest count meeting ``bound``, at most ``limit`` (then the error says how
    far off it is).
    """
    frames = len(x)
    flat = x.reshape(frames, -1)
    if not flat.size or not np.any(flat):
        return np.zeros((0,) + x.shape[1:], np.float32), np.zeros((frames, 0), np.float32), 0.0
    directions = _principal_directions(flat, limit)  # (L, N) float64 orthonormal rows
    weights = flat.astype(np.float64) @ directions.T  # (T, L)
    residual = flat.astype(np.float64)
    for k in range(len(directions) + 1):
        error = float(np.sqrt((residual.reshape(frames, -1, 3) ** 2).sum(axis=2).max()))
        if error <= bound or k == len(directions):
            break
        residual -= np.outer(weights[:, k], directions[k])
    shapes = directions[:k].reshape((k,) + x.shape[1:]).astype(np.float32)
    return shapes, weights[:, :k].astype(np.float32), error


def _principal_directions(flat: np.ndarray, limit: int) -> np.ndarray:
    """The top ``limit`` right singular vectors (L, N) of flat (T, N), through the smaller
    of the two Gram matrices (T x T or N x N), in float64."""
    a = flat.astype(np.float64)
    frames, size = a.shape
    if frames <= size:
        values, vectors = np.linalg.eigh(a @ a.T)
        order = np.argsort(values)[::-1][:limit]
        keep = order[values[order] > values[order[0]] * 1e-12]
        out = vectors[:, keep].T @ a
        return out / np.linalg.norm(out, axis=1, keepdims=True)
    values, vectors = np.linalg.eigh(a.T @ a)
    order = np.argsort(values)[::-1][:limit]
    keep = order[values[order] > values[order[0]] * 1e-12]
    return vectors[:, keep].T


def segment_targets(basis: Basis, vertices: int) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """One segment's morphs (name -> (vertices, 3) float32) and their (n, k + 1) weights.

    Weights in [0, 1], which every player keeps (Blender's shape-key sliders and Unity clamp
    to it): w = lo + (hi - lo) u, so x = sum lo_k s_k + sum u_k (hi_k - lo_k) s_k, the first
    term an "offset" target held at 1 over the segment (the rest mesh is unchanged). A shape
    whose weights reach further below 0 than above is flipped first, so that lo is small and
    a shape played on a few frames only (``grow``) stays at 0 on the others."""
    flip = np.where(-basis.weights.min(axis=0) > basis.weights.max(axis=0), -1.0, 1.0)
    moved, shapes, weights = basis.moved, basis.shapes * flip[:, None, None], basis.weights * flip
    lo, hi = np.minimum(weights.min(axis=0), 0.0), np.maximum(weights.max(axis=0), 0.0)
    span = np.where(hi - lo > 0, hi - lo, 1.0)
    out = np.ones((len(weights), len(shapes) + 1), dtype=np.float32)
    out[:, 1:] = np.clip((weights - lo) / span, 0.0, 1.0)
    morphs = {"offset": np.zeros((vertices, 3), dtype=np.float32)}
    morphs["offset"][moved] = np.einsum("k,kvc->vc", lo, shapes)
    for k, shape in enumerate(shapes):
        morphs[f"{k:02d}"] = np.zeros((vertices, 3), dtype=np.float32)
        morphs[f"{k:02d}"][moved] = shape * span[k]
    return morphs, out

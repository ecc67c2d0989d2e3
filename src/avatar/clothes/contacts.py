"""Other body parts near garment points: an arm swinging into a shirt's side, one thigh
into the other trouser leg, a fold closing in the crotch.

A garment point keeps its clearance above the skin it was anchored to at rest, which moves
with it (``collision.PosedBody.anchored``); what that cannot see is skin of another part
coming near. ``remote_contacts`` finds the few points where that may be so, from their
nearest skin vertices, and only those get the exact search.
"""

from __future__ import annotations

import numpy as np

from avatar.geometry import collision

REMOTE_K = 3  # nearest skin vertices whose rest places tell another body part
CLOSING = 0.01  # m that skin may come closer to a point's anchor before it is another part
REMOTE_REACH = 0.06  # m; points further than this from every skin vertex are not checked
FOLD = 0.3  # cosine between anchor and nearest-skin normals below which the skin folded
PLANE_SLACK = 0.002  # m the tangent-plane estimate may fall short before it is checked
CAUGHT = -0.3  # cosine between two successive push directions: caught between two parts
REMOTE = 0.02  # m at rest between a point's anchor and its nearest skin: another body part


def remote_contacts(body: collision.PosedBody, rest_rows: np.ndarray | None, points, need,
                    rest_near, facing, iterations: int = 1):  # fmt: skip
    """Push points out of body parts other than the skin they are anchored to (an arm
    swinging into a shirt's side, one thigh into the other trouser leg). Such a point's
    nearest skin vertex now lies far, at rest, from its nearest one at rest; or one of
    its three nearest came closer to that one than it was at rest (skin pressing in,
    even where its vertex is not the nearest); or it faces another way than its anchor
    (a fold closing, as in the crotch). Only those few get the exact search."""
    # All garments in one query: the largest single cost of a posed frame.
    x, normals, tree = body.vertices, body.normals, body.tree
    # At rest (no rest_rows: the body is at rest) no skin moved, so the nearest one tells all.
    k = 1 if rest_rows is None else REMOTE_K
    dist, near3 = tree.query(points, k=k, reach=REMOTE_REACH)
    dist, near3 = dist.reshape(len(points), k), near3.reshape(len(points), k)
    close = np.isfinite(dist[:, 0])
    near3 = np.where(np.isfinite(dist), near3, near3[:, :1])
    far = np.flatnonzero(~close)
    if len(far):
        near3[far] = tree.query(points[far], k=1)[1][:, None]
    near = near3[:, 0]
    remote: np.ndarray | float = REMOTE
    if rest_rows is not None:
        # In a pose, a point's own skin can lie as far from its anchor's vertex as the point
        # is from both (a loose hem's nearest vertex drifts as the body moves): only skin
        # further than that, at rest, is another part. This halves the exact searches.
        anchor = np.take(x, rest_near, axis=0)
        remote = REMOTE + dist[:, 0] + np.sqrt(_dot_rows(points - anchor, points - anchor))
    other = _other_part(body.rows if rest_rows is None else rest_rows, body.rows, near3,
                        rest_near, remote)  # fmt: skip
    normal = np.take(normals, near, axis=0)
    turned = _dot_rows(normal, facing) < FOLD
    # The nearest vertex's tangent plane is a second, independent opinion: where it says
    # "too close" although the anchor did not, look properly. It also catches points far
    # from every skin vertex because they are deep inside another part (a skirt's hem
    # swept into the belly by a raised thigh), not far outside.
    plane = _dot_rows(points - np.take(x, near, axis=0), normal) < need - PLANE_SLACK
    remote = np.flatnonzero((close & (other | turned)) | plane)
    if len(remote) == 0:
        return points
    points = points.copy()
    before = None
    for _ in range(iterations):
        exact = body.query(points[remote], k=4)
        short = exact.distance < need[remote] - 1e-5
        if not short.any():
            break
        # Points far enough out stay put, so only the short ones are looked at again.
        keep = np.flatnonzero(short)
        remote, exact = remote[keep], exact.take(keep)
        moved = collision.push_out(points[remote], exact, need[remote])
        if before is not None:
            # Pushed out of one part straight into the facing one (an arm against the
            # chest): the middle of the gap between the two is as far from both as it gets.
            prior = before.take(keep)
            caught = np.einsum("nd,nd->n", exact.normal, prior.normal) < CAUGHT
            moved[caught] = 0.5 * (exact.closest[caught] + prior.closest[caught])
        before = exact
        points[remote] = moved
    return points


def _other_part(rest_rows, rows, near3, rest_near, remote) -> np.ndarray:
    """(N,) bool: a point's nearest skin vertex lay further than ``remote`` (m, scalar or
    (N,)), at rest, from its anchor's vertex; or one of its three nearest came closer to
    that vertex than it was at rest.
    rest_rows, rows: (3, V) the skin's coordinate rows at rest and now."""
    rest_gap = _distances(rest_rows, near3, rest_near)
    gap = rest_gap if rows is rest_rows else _distances(rows, near3, rest_near)
    return (rest_gap[:, 0] > remote) | ((rest_gap - gap).max(axis=1) > CLOSING)


def _distances(rows: np.ndarray, near: np.ndarray, anchor: np.ndarray) -> np.ndarray:
    """(N, K) distances between the vertices ``near`` (N, K) and ``anchor`` (N,) of a
    skin given by its coordinate rows (3, V)."""
    square = np.zeros(near.shape, np.float32)
    for row in rows:
        d = np.take(row, near) - np.take(row, anchor)[:, None]
        square += d * d
    return np.sqrt(square)


def _dot_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("nd,nd->n", a, b)

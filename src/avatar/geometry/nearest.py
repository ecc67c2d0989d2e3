"""Nearest body vertices of many points: the k-d tree behind every collision search.

A posed frame builds one tree on the skin and asks it for the nearest vertices of every
garment vertex, which makes this the hottest search of the clothes code. pykdtree (float32,
OpenMP) answers it two to three times faster than scipy's cKDTree at these sizes (13,380
skin vertices, a few hundred to ten thousand queries; see docs/benchmarks.md). Where it is
missing (a Blender whose Python lacks it) scipy's tree answers the same queries.
"""

from __future__ import annotations

import os
import sys
from concurrent.futures import Future, ThreadPoolExecutor

import numpy as np
from scipy.spatial import cKDTree

# pykdtree's OpenMP threads would otherwise spin for a while after every search: with
# other work on the machine (a render, a second worker, other programs) the spinning takes
# the cores from it and searches ran 2-5x slower. Sleeping threads cost microseconds per
# search. Read once, when OpenMP loads; a value the user set is kept.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

try:
    from pykdtree.kdtree import KDTree
except ImportError:  # pragma: no cover - depends on the environment
    KDTree = None  # type: ignore[misc, assignment]

_BUILDER: list = []  # [(pid, executor)]: a forked child makes its own thread


class PointTree:
    """A k-d tree over (V, 3) points, kept in float32 (the collision code's precision)."""

    def __init__(self, points: np.ndarray):
        self.points = np.ascontiguousarray(points, dtype=np.float32)
        if KDTree is None:
            self._tree = cKDTree(self.points, balanced_tree=False, compact_nodes=False)
        else:
            self._tree = KDTree(self.points, leafsize=16)

    @classmethod
    def later(cls, points: np.ndarray) -> Future[PointTree]:
        """A tree built on a background thread (the build runs without the GIL), for a
        caller with other work to do before its first search."""
        points = np.array(points, dtype=np.float32)  # the caller may reuse its array
        if "bpy" in sys.modules:
            # Inside Blender a Python thread still running when the caller goes on to an
            # operator (mode_set, ...) crashed Blender (a segfault in CI), so build it now.
            done: Future[PointTree] = Future()
            done.set_result(cls(points))
            return done
        if not _BUILDER or _BUILDER[0][0] != os.getpid():
            _BUILDER[:] = [(os.getpid(), ThreadPoolExecutor(1, "avatar-kdtree"))]
        return _BUILDER[0][1].submit(cls, points)

    def __len__(self) -> int:
        return len(self.points)

    def query(
        self, points: np.ndarray, k: int = 1, reach: float | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Distances and indices of the k nearest points, nearest first: (N,) arrays for
        k = 1, else (N, k). Beyond ``reach`` (m) a neighbour is missing: distance inf and
        index ``len(self)``, as in scipy."""
        p = np.ascontiguousarray(points, dtype=np.float32).reshape(-1, 3)
        if isinstance(self._tree, cKDTree):
            bound = np.inf if reach is None else reach
            dist, index = self._tree.query(p, k=k, distance_upper_bound=bound, workers=-1)
            return dist.astype(np.float32), index.astype(np.intp)
        dist, index = self._tree.query(p, k=k, distance_upper_bound=reach)
        return dist, index.astype(np.intp)

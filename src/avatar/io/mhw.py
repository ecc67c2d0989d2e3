"""MakeHuman vertex bone weights (``.mhw``, also ``.jsonw``; MakeHuman 1.1 ``animation.py``).

JSON: ``{"name", "version", "license", "weights": {bone: [[vertex, weight], ...]}}``. Weights
are stored unnormalised; MakeHuman normalises them per vertex when it loads them.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from avatar.errors import FormatError
from avatar.io import atomic


@dataclass(frozen=True)
class BoneWeights:
    """Per-bone sparse weights over V vertices.

    bones: B bone names in file order.
    vertex: (n,) int32 vertex index of each entry; bone: (n,) int32 index into ``bones``;
    weight: (n,) float32 weight as stored.
    meta: the file's other top-level fields (name, license, ...).
    """

    bones: tuple[str, ...]
    vertex: np.ndarray
    bone: np.ndarray
    weight: np.ndarray
    meta: dict

    def dense(self, vertex_count: int) -> np.ndarray:
        """(V, B) float32 weights, each row normalised to sum 1 where it has any weight."""
        out = np.zeros((vertex_count, len(self.bones)), np.float32)
        np.add.at(out, (self.vertex, self.bone), self.weight)
        total = out.sum(axis=1, keepdims=True)
        return np.divide(out, total, out=out, where=total > 0)


def loads(text: str, path: str | os.PathLike[str] | None = None) -> BoneWeights:
    """Parse ``.mhw`` JSON; FormatError on bad JSON or a malformed entry."""
    try:
        data = json.loads(text)
        table = data["weights"]
        bones = tuple(table)
        rows = [(v, b, w) for b, name in enumerate(bones) for v, w in table[name]]
        arr = np.asarray(rows, dtype=np.float64).reshape(-1, 3)
    except (ValueError, KeyError, TypeError) as exc:
        raise FormatError(path, 0, f"not a MakeHuman weights file: {exc}") from None
    if len(arr) and (arr[:, 0].min() < 0 or not np.all(np.isfinite(arr))):
        raise FormatError(path, 0, "negative vertex index or non-finite weight")
    meta = {k: v for k, v in data.items() if k != "weights"}
    return BoneWeights(
        bones,
        arr[:, 0].astype(np.int32),
        arr[:, 1].astype(np.int32),
        arr[:, 2].astype(np.float32),
        meta,
    )


def read(path: str | os.PathLike[str]) -> BoneWeights:
    """Read a ``.mhw`` file."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise FormatError(path, 0, f"cannot read: {exc.strerror}") from None
    return loads(text, path)


def dumps(weights: BoneWeights) -> str:
    """JSON text of the weights (the ``meta`` fields first, as MakeHuman writes them)."""
    table: dict[str, list] = {name: [] for name in weights.bones}
    for v, b, w in zip(weights.vertex, weights.bone, weights.weight, strict=True):
        table[weights.bones[b]].append([int(v), float(w)])
    return json.dumps({**weights.meta, "weights": table}, indent=1)


def write(path: str | os.PathLike[str], weights: BoneWeights) -> None:
    """Write a weights file atomically."""
    atomic.write_text(path, dumps(weights))

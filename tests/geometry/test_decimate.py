"""Decimation by vertex clustering: the wanted triangle count, original vertices kept."""

from __future__ import annotations

import numpy as np
import pytest

from avatar.geometry.decimate import decimate
from avatar.mesh import Mesh


def _grid(n: int) -> Mesh:
    """An n x n quad grid (a bumpy sheet) with per-corner UVs."""
    x, y = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1))
    v = np.stack([x.ravel(), y.ravel(), 0.05 * np.sin(6 * x.ravel())], axis=1).astype(np.float32)
    i = np.arange(n * (n + 1)).reshape(n, n + 1)[:, :n].ravel()
    faces = np.stack([i, i + 1, i + n + 2, i + n + 1], axis=1).astype(np.int32)
    return Mesh(v, faces, uvs=v[:, :2].copy(), face_uvs=faces.copy())


@pytest.mark.parametrize("ratio", [0.5, 0.25, 0.1])
def test_decimate_reaches_the_ratio_with_original_vertices(ratio):
    mesh = _grid(40)
    out, source = decimate(mesh, ratio)
    assert abs(len(out.faces) / (2 * 40 * 40) - ratio) < 0.2 * ratio + 0.02
    np.testing.assert_array_equal(out.vertices, mesh.vertices[source])
    assert out.faces.max() < len(out.vertices) and len(np.unique(out.faces)) == len(out.vertices)
    assert np.all((out.faces[:, 0] != out.faces[:, 1]) & (out.faces[:, 1] != out.faces[:, 2]))
    assert out.face_uvs.shape == out.faces.shape and out.face_uvs.max() < len(out.uvs)


def test_decimate_keeps_the_whole_at_ratio_one_and_checks_it():
    mesh = _grid(4)
    out, source = decimate(mesh, 1.0)
    assert len(out.faces) == 32 and len(source) == 25
    with pytest.raises(ValueError, match="ratio"):
        decimate(mesh, 0.0)

"""The hoodie's hood lying on the back (issue 14, seventh pass), measured on its built
piece."""

from __future__ import annotations

import numpy as np


def test_hood_bag_folds_round_its_lower_edge_without_a_crease():
    """The rolled opening ran all the way round the bag's point: between the roll and the
    bag's dome a valley ran along the lower edge, 30 pairs of faces (off the outline)
    meeting at 25-80 degrees, up to 75 (a crease and a lumpy double edge from behind).
    The roll fades out over the lower third: in the lower part, at most 4 such pairs."""
    from avatar.clothes import builtin, library
    from avatar.geometry.shell import boundary_edges

    body = library.authoring_body()
    mesh = builtin._hood(body).mesh
    v = mesh.vertices.astype(np.float64)
    faces = mesh.faces
    outline = np.zeros(len(v), bool)
    outline[boundary_edges(faces)[0].ravel()] = True
    low = v[:, 2] < body.marks.neck[2] - 0.17
    keep = low[faces].all(axis=1) & ~outline[faces].any(axis=1)
    q = v[faces]
    normal = np.cross(q[:, 2] - q[:, 0], q[:, -1] - q[:, 1])
    normal /= np.maximum(np.linalg.norm(normal, axis=1), 1e-12)[:, None]
    edges = np.sort(np.stack([faces, np.roll(faces, -1, axis=1)], -1).reshape(-1, 2), axis=1)
    owner = np.repeat(np.arange(len(faces)), faces.shape[1])
    order = np.lexsort(edges.T[::-1])
    edges, owner = edges[order], owner[order]
    shared = np.all(edges[1:] == edges[:-1], axis=1)
    a, b = owner[:-1][shared], owner[1:][shared]
    both = keep[a] & keep[b]
    assert both.sum() > 100
    fold = np.degrees(np.arccos(np.clip(np.einsum("nd,nd->n", normal[a[both]],
                                                  normal[b[both]]), -1, 1)))  # fmt: skip
    crease = (fold > 25) & (fold < 80)  # the band's turned edge stands at 90
    assert crease.sum() <= 4, np.sort(fold[crease])

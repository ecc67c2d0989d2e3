"""Teeth and tongue: parts of every human, rigged to the jaw, moved by the face units, inside
the head, with their own materials, and exported so ``jawOpen`` opens onto a mouth."""

from __future__ import annotations

import numpy as np
import pytest

import avatar
from avatar.body.shaped import PART_GROUPS
from avatar.human import Human
from avatar.io import gltf
from avatar.looks import skin


@pytest.fixture(scope="module")
def human(model):
    return Human({}, model=model)


def _main_bone(human, part: str) -> list[str]:
    """The bone carrying most weight, per vertex of ``part``."""
    w = human.weights.subset(human.part_vertices(part))
    best = w.indices[np.arange(len(w.indices)), np.argmax(w.weights, axis=1)]
    return [human.skeleton.names[i] for i in best]


def test_teeth_and_tongue_are_parts_with_their_own_materials(human):
    parts = {p.name: p for p in human.parts()}
    assert list(parts)[:4] == ["body", "eyes", "teeth", "tongue"] == list(PART_GROUPS)
    assert len(parts["teeth"].mesh.faces) == 96 and len(parts["tongue"].mesh.faces) == 224
    teeth, tongue = parts["teeth"].material, parts["tongue"].material
    assert (teeth.name, tongue.name) == ("teeth", "tongue")
    assert min(teeth.base_color[:3]) > 0.6  # ivory, not skin or a black hole
    assert tongue.base_color[0] > 2 * tongue.base_color[1]  # pink-red
    assert teeth.roughness < 0.3 and tongue.roughness < 0.5  # wet, glossy
    with pytest.raises(ValueError, match="mouth part"):
        skin.mouth_material("gums")


def test_old_teeth_are_yellower(human):
    young, old = skin.mouth_material("teeth", 0.3), skin.mouth_material("teeth", 1.0)
    assert old.base_color[2] / old.base_color[0] < young.base_color[2] / young.base_color[0]


def test_lower_teeth_ride_the_jaw_upper_the_head(human):
    index = human.part_vertices("teeth")
    lower = np.isin(index, np.unique(human.model.base.faces[
        human.model.base.face_groups["helper-lower-teeth"]]))  # fmt: skip
    bones = np.array(_main_bone(human, "teeth"))
    assert set(bones[lower]) == {"jaw"} and set(bones[~lower]) == {"head"}
    assert all(b.startswith("tongue") or b == "jaw" for b in _main_bone(human, "tongue"))


def _hits(origins: np.ndarray, direction, triangles: np.ndarray) -> np.ndarray:
    """(N,) bool: the ray from each origin along ``direction`` crosses one of ``triangles``
    (T, 3, 3) (Moller-Trumbore, both sides)."""
    d = np.asarray(direction, np.float64)
    a = triangles[:, 0]
    e1, e2 = triangles[:, 1] - a, triangles[:, 2] - a
    p = np.cross(d, e2)
    det = np.einsum("ij,ij->i", e1, p)
    ok = np.abs(det) > 1e-12
    a, e1, e2, p, det = a[ok], e1[ok], e2[ok], p[ok], det[ok]
    s = origins[:, None, :] - a[None]
    u = np.einsum("nij,ij->ni", s, p) / det
    q = np.cross(s, e1[None])
    v = (q @ d) / det
    t = np.einsum("nij,ij->ni", q, e2) / det
    return ((u >= -1e-9) & (v >= -1e-9) & (u + v <= 1 + 1e-9) & (t > 0)).any(axis=1)


def test_mouth_parts_are_hidden_behind_closed_lips(model):
    """Mouth shut, teeth and tongue sit in the mouth: a ray forward from their vertices
    meets the skin (lips, cheeks), so they do not show through the face."""
    base = model.base
    quads = base.faces[base.face_groups["body"]]
    tris = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    for params in ({}, {"age": 0.1, "gender": 0.0}, {"weight": 1.0, "gender": 1.0},
                   {"age": 1.0, "gender": 1.0}):  # fmt: skip
        h = Human(params, model=model)
        v = h.vertices.astype(np.float64)
        mouth = np.concatenate([h.part("teeth").vertices, h.part("tongue").vertices])
        lo, hi = mouth.min(axis=0) - 0.05, mouth.max(axis=0) + 0.05
        near = tris[((v[tris] > lo) & (v[tris] < hi)).all(axis=2).any(axis=1)]
        hidden = _hits(mouth.astype(np.float64), (0, -1, 0), v[near])
        # The lips of MakeHuman's base mesh part by a slit: a ray or two passes through it.
        assert hidden.mean() > 0.97, params
        lips = v[h.part_vertices("body")][:, 1].min()  # the frontmost skin: lips or nose
        assert mouth[:, 1].min() > lips + 0.005, params


def test_jaw_open_lowers_the_lower_teeth_and_tongue_not_the_upper(human):
    morphs = {p.name: p.morphs for p in human.parts(expressions=True)}
    assert set(morphs["teeth"]) == set(morphs["body"]) and "jawOpen" in morphs["teeth"]
    assert not morphs["eyes"]
    index = human.part_vertices("teeth")
    upper = np.isin(index, np.unique(human.model.base.faces[
        human.model.base.face_groups["helper-upper-teeth"]]))  # fmt: skip
    drop = morphs["teeth"]["jawOpen"]
    assert np.abs(drop[upper]).max() == 0.0
    assert drop[~upper, 2].mean() < -0.01  # a centimetre and more down
    assert morphs["tongue"]["jawOpen"][:, 2].mean() < -0.005
    # The lower teeth come out from behind the upper ones: a gap between the rows.
    rest = human.part("teeth").vertices
    assert (rest[~upper] + drop[~upper])[:, 2].max() < rest[upper][:, 2].min()


def test_glb_carries_the_mouth_and_its_jaw_open_shape(human, tmp_path):
    path = avatar.save(human, tmp_path / "mouth.glb", expressions=True)
    back = {p.name: p for p in gltf.read(path).parts}
    for name in ("teeth", "tongue"):
        part = next(p for p in human.parts(expressions=True) if p.name == name)
        np.testing.assert_allclose(back[name].mesh.vertices, part.mesh.vertices, atol=1e-5)
        np.testing.assert_allclose(back[name].morphs["jawOpen"], part.morphs["jawOpen"],
                                   atol=1e-5)  # fmt: skip
        assert back[name].material.name == name


def _first_hits(origins: np.ndarray, direction, triangles: np.ndarray):
    """(N,) index of the nearest triangle each ray from ``origins`` (N, 3) along
    ``direction`` meets first (-1: none), and (N,) its distance (Moller-Trumbore)."""
    d = np.asarray(direction, np.float64) / np.linalg.norm(direction)
    a = triangles[:, 0]
    e1, e2 = triangles[:, 1] - a, triangles[:, 2] - a
    p = np.cross(d, e2)
    det = np.einsum("ij,ij->i", e1, p)
    det = np.where(np.abs(det) > 1e-12, det, np.nan)
    s = origins[:, None, :] - a[None]
    u = np.einsum("nij,ij->ni", s, p) / det
    q = np.cross(s, e1[None])
    v = (q @ d) / det
    t = np.einsum("nij,ij->ni", q, e2) / det
    ok = (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
    t = np.where(ok, t, np.inf)
    first = np.argmin(t, axis=1)
    dist = t[np.arange(len(t)), first]
    return np.where(np.isfinite(dist), first, -1), dist


def _seen_from_front(human, step: float = 0.0005) -> dict[str, float]:
    """mm² of the mouth's parts a camera straight ahead, a little above, sees first:
    "upper" and "lower" teeth, "tongue", "skin" (lips and the mouth's lining)."""
    base = human.model.base
    v = human.vertices.astype(np.float64)
    teeth = human.part("teeth")
    upper_ids = np.unique(base.faces[base.face_groups["helper-upper-teeth"]])
    upper_faces = np.isin(human.part_vertices("teeth")[teeth.faces], upper_ids).all(axis=1)
    tongue = human.part("tongue")
    centre = teeth.vertices.mean(axis=0).astype(np.float64)
    quads = base.faces[base.face_groups["body"]]
    near = quads[(np.linalg.norm(v[quads].mean(axis=1) - centre, axis=1) < 0.06)]
    sets = {"skin": v[near], "upper": teeth.vertices[teeth.faces[upper_faces]],
            "lower": teeth.vertices[teeth.faces[~upper_faces]],
            "tongue": tongue.vertices[tongue.faces]}  # fmt: skip
    tris, label = [], []
    for name, q in sets.items():
        q = q.astype(np.float64)
        tris.append(np.concatenate([q[:, [0, 1, 2]], q[:, [0, 2, 3]]]))
        label += [name] * (2 * len(q))
    tris_all, label = np.concatenate(tris), np.array(label)
    xs = np.arange(-0.025, 0.025, step)
    zs = np.arange(centre[2] - 0.045, centre[2] + 0.025, step)
    gx, gz = np.meshgrid(xs, zs)
    direction = np.array([0.0, 1.0, -0.05])  # the close-up camera: ahead, a little above
    # Rays start 10 cm ahead of the teeth, well in front of the face.
    origins = np.stack([gx.ravel(), np.full(gx.size, centre[1] - 0.1), gz.ravel()], 1)
    hit, _ = _first_hits(origins, direction, tris_all)
    seen = label[hit[hit >= 0]]
    return {name: float((seen == name).sum()) * (step * 1000) ** 2 for name in sets}


@pytest.mark.parametrize("jaw", [0.6, 1.0])
def test_open_mouth_shows_the_upper_teeth_under_the_upper_lip(model, jaw):
    """With the jaw open the upper incisors hang below the upper lip (a real mouth shows
    2-4 mm of them), not hidden behind it over a dark hole; the lower teeth and tongue show
    too. MakeHuman's helper rows meet edge to edge at the lips' line: 0 mm² showed."""
    for params in ({"gender": 0.0, "age": 0.45}, {"gender": 1.0, "age": 0.5},
                   {"gender": 1.0, "age": 1.0, "weight": 0.9}, {"age": 0.12}):  # fmt: skip
        human = Human(params | {"expression/jawOpen": jaw}, model=model)
        seen = _seen_from_front(human)
        width = human.part("teeth").vertices[:, 0].ptp() * 1000  # mm, scales with the child
        # Over the ~30 mm the lips open to, a band of a millimetre and more (0 before).
        assert seen["upper"] > 0.25 * width, (params, seen)
        assert seen["lower"] > 0.5 * width and seen["tongue"] > 0, (params, seen)


def test_closed_mouth_bite_upper_incisors_in_front_of_the_lower(model):
    """Mouth shut, the upper incisors overlap the lower ones in front (overbite, overjet)
    without the rows passing through each other: the lower incisors' biting edge lies
    behind the upper incisors' inner face."""
    human = Human({}, model=model)
    base = model.base
    mesh = human.part("teeth")
    upper = np.isin(human.part_vertices("teeth"),
                    np.unique(base.faces[base.face_groups["helper-upper-teeth"]]))  # fmt: skip
    mid = np.abs(mesh.vertices[:, 0]) < 0.0035
    up, low = mesh.vertices[upper & mid], mesh.vertices[~upper & mid]
    upper_edge, lower_edge = up[np.argmin(up[:, 2])], low[np.argmax(low[:, 2])]
    assert 0.002 < lower_edge[2] - upper_edge[2] < 0.004  # ~3 mm of overlap
    assert upper_edge[1] < lower_edge[1] - 0.001  # in front by a millimetre and more
    inner = up[np.argmax(up[:, 1])]  # the upper incisor's inner (palatal) side
    t = (lower_edge[2] - upper_edge[2]) / (inner[2] - upper_edge[2])
    assert lower_edge[1] > upper_edge[1] + t * (inner[1] - upper_edge[1])  # behind it

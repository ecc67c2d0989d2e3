"""Built-in hair, brows, lashes and tank top: properties that make them look right in renders."""

from __future__ import annotations

import numpy as np
import pytest

from avatar.clothes import builtin, face, hair, library
from avatar.geometry import collision
from avatar.geometry.shell import boundary_edges
from avatar.human import Human
from avatar.looks import textures


@pytest.fixture(scope="module")
def body():
    return library.authoring_body()


@pytest.mark.parametrize("paint", [textures.lash_alpha, textures.brow_alpha, textures.strand_alpha])
def test_strand_alphas_have_see_through_gaps_opaque_cores_and_soft_edges(paint):
    alpha = paint(256)
    assert alpha.dtype == np.uint8 and alpha.shape == (256, 256)
    assert (alpha == 0).mean() > 0.05  # gaps between strands
    assert (alpha >= 200).mean() > 0.02  # strand cores
    assert ((alpha > 20) & (alpha < 200)).any()  # anti-aliased edges, not a stripe pattern
    assert np.array_equal(alpha, paint(256))  # deterministic


def test_lashes_are_many_thin_strands_rooted_on_the_lid_line():
    alpha = textures.lash_alpha(512).astype(np.float32) / 255
    upper = alpha[:256]  # v in [0.5, 1]: root at the bottom row of this half
    assert upper[-3:].mean() > 0.8  # the lash line
    row = upper[128] > 0.5  # half way to the tips: separate strands
    starts = np.count_nonzero(row[1:] & ~row[:-1])
    assert starts > 40
    assert upper[:20].mean() < upper[200:230].mean() / 3  # thinning towards the tips


def test_eyebrow_is_thick_at_the_head_and_thin_at_the_tail():
    alpha = textures.brow_alpha(512) > 128
    head = alpha[:, 48:112].sum(axis=0).mean()
    tail = alpha[:, 432:464].sum(axis=0).mean()
    assert head > 2 * tail > 0
    assert not alpha[:, :5].any() and not alpha[:, -5:].any()  # room around the ends


def test_face_and_hair_materials_cut_out_or_blend():
    for name, mode in (("eyelashes", "BLEND"), ("eyebrows", "BLEND"), ("hair-short", "MASK")):
        m = textures.hair_material(builtin.BY_NAME[name], 128)
        assert m.alpha_mode == mode and m.double_sided
        assert m.base_color_texture.shape == (128, 128, 4)
    roots, tips = textures.strand_shade(128)[[70, 126]].mean(axis=1)
    assert roots < 0.8 * tips  # darker roots


def test_lash_strip_uvs_run_from_the_lid_to_the_tips(body):
    piece = face.eyelashes(body, builtin.EYELASH_GROUPS)
    uv = piece.mesh.uvs
    assert uv[:, 0].min() == 0 and uv[:, 0].max() == 1
    assert uv[:, 1].min() == 0 and uv[:, 1].max() == 1
    eye = body.centre("helper-l-eye")
    upper = face.eyelashes(body, ("helper-l-eyelashes-2",)).mesh
    roots = upper.vertices[upper.uvs[:, 1] == 0.5]
    tips = upper.vertices[upper.uvs[:, 1] == 1.0]
    assert np.linalg.norm(roots - eye, axis=1).mean() < np.linalg.norm(tips - eye, axis=1).mean()


def _turning_degrees(points: np.ndarray, loop: list[int]) -> np.ndarray:
    p = points[loop].astype(np.float64)
    a, b = np.roll(p, -1, 0) - p, p - np.roll(p, 1, 0)
    cos = np.einsum("nd,nd->n", a, b) / np.linalg.norm(a, axis=1) / np.linalg.norm(b, axis=1)
    return np.degrees(np.arccos(np.clip(cos, -1, 1)))


def _loops(faces: np.ndarray) -> list[list[int]]:
    edges, _ = boundary_edges(faces)
    following = dict(zip(edges[:, 0].tolist(), edges[:, 1].tolist(), strict=True))
    loops, seen = [], set()
    for start in following:
        if start in seen:
            continue
        loop = [start]
        while following[loop[-1]] != start and following[loop[-1]] not in seen:
            loop.append(following[loop[-1]])
            seen.add(loop[-1])
        loops.append(loop)
    return loops


def test_tank_top_armholes_are_smooth_curves(body, monkeypatch):
    relaxed = builtin.RELAX

    def armholes(relax):
        monkeypatch.setattr(builtin, "RELAX", relax)
        mesh = builtin.BY_NAME["tanktop"].make(body).mesh
        loops = [p for p in _loops(mesh.faces) if abs(mesh.vertices[p, 0].mean()) > 0.08]
        assert len(loops) == 2  # one armhole each side, apart from neckline and hem
        return np.concatenate([_turning_degrees(mesh.vertices, p) for p in loops])

    assert armholes(0).max() >= 80  # the raw cut is a staircase of face edges
    smooth = armholes(relaxed)
    assert smooth.max() < 50 and smooth.mean() < 20


def test_tank_top_has_straps_over_the_shoulders(body):
    mesh = builtin.BY_NAME["tanktop"].make(body).mesh
    top = mesh.vertices[mesh.vertices[:, 2] > body.marks.neck[2] - 0.02]
    assert (top[:, 0] > 0.05).any() and (top[:, 0] < -0.05).any()
    assert not (np.abs(top[:, 0]) < 0.03).any()  # the neckline is open


def test_short_hair_has_volume_and_a_hairline(body):
    mesh = builtin.BY_NAME["hair-short"].make(body).mesh
    centre, eye_z = hair.head_frame(body)
    height, _ = body.skin_tree.query(mesh.vertices)
    crown = mesh.vertices[:, 2] > eye_z + 0.07
    assert np.percentile(height[crown], 90) > 0.012  # stands off the scalp, not a cap
    cap = hair.base_cap(body).mesh.vertices
    forehead = (hair.around(cap, centre) < 20) & (cap[:, 1] < centre[1])
    assert cap[forehead, 2].min() > eye_z + 0.055  # a bare forehead under the hairline
    assert cap[:, 2].min() < eye_z - 0.04  # down to the nape


def test_long_hair_falls_behind_the_shoulders(body):
    mesh = builtin.BY_NAME["hair-long"].make(body).mesh
    low = mesh.vertices[mesh.vertices[:, 2] < body.marks.neck[2] - 0.1]
    assert len(low) and low[:, 1].min() > body.marks.neck[1] - 0.05


def test_hair_stays_outside_varied_bodies():
    names = [s.name for s in builtin.SPECS if s.category == "hair"]
    worst = 0.0
    for params in ({"gender": 0.0, "age": 0.1}, {"gender": 1.0, "weight": 1.0, "age": 1.0}):
        human = Human(params).dressed(*names)
        faces = human.model.base.faces[human.model.base.face_groups["body"]]
        for part in library.parts(human.outfit):
            _, depth = collision.penetration(human.vertices[:13380], faces, part.mesh.vertices)
            worst = max(worst, float(depth.max()))
    assert worst <= 0.001, f"a hair vertex is {worst * 1000:.2f} mm inside the body"

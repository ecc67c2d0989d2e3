"""Slider drags on a rigged character: what Blender evaluates (the viewport) during a drag is
the exact body and joints, without an edit-mode trip that re-evaluates the whole scene, and
the settle that follows makes the character exactly a fresh ``Human`` again (MakeHuman
assets; skipped without them)."""

from __future__ import annotations

import importlib.util
import json
import os
from pathlib import Path

import numpy as np
import pytest

from avatar.body.shaped import PART_GROUPS

ROOT = Path(__file__).resolve().parents[2]
FIXTURES = Path(os.environ.get("AVATAR_FIXTURES", ROOT.parent / "shared" / "fixtures"))
SHOES = FIXTURES / "makehuman" / "clothes" / "shoes01" / "shoes01.mhclo"
ADDON = "bl_ext.user_default.avatar_addon"
BODY_TOLERANCE = 1e-4  # 0.1 mm: the body and joints shown during a drag
GARMENT_TOLERANCE = 5e-3  # the real-time garment fit before settling (test_extension)




@pytest.fixture
def dressed(installed, assets, empty_scene):
    """A rigged human (hair, brows, lashes) in a T-shirt and jeans, active and settled."""
    import bpy

    assert bpy.ops.avatar.create_human() == {"FINISHED"}
    root = bpy.context.view_layer.objects.active
    assert bpy.ops.avatar.wear(name="tshirt") == {"FINISHED"}
    assert bpy.ops.avatar.wear(name="jeans") == {"FINISHED"}
    assert bpy.ops.avatar.settle() == {"FINISHED"}
    bpy.context.view_layer.update()
    return root


def _fresh(root):
    from avatar.human import Human

    return Human.from_recipe(json.loads(root["avatar_recipe"]))


def _shown(obj) -> np.ndarray:
    """(V, 3) what the viewport draws of a part: its evaluated (depsgraph) vertices."""
    from avatar.blender import mesh

    return mesh.read_vertices(obj, evaluated=True)


def _assert_shown_exactly(root):
    """The evaluated body, eyes, joints and garments against a fresh Human of the recipe."""
    from avatar.blender import armature, live, mesh

    fresh = _fresh(root)
    parts = live.part_objects(root)
    np.testing.assert_allclose(_shown(parts["body"]), fresh.mesh.vertices, atol=BODY_TOLERANCE)
    for part in PART_GROUPS:
        if part != "body":
            want = fresh.part(part).vertices  # as a Human renders it (teeth in their bite)
            np.testing.assert_allclose(_shown(parts[part]), want, atol=BODY_TOLERANCE)
    posed = armature.pose_matrices(root, fresh.skeleton.names)  # what the bones show
    rest = np.asarray(fresh.skeleton.rest)
    np.testing.assert_allclose(posed[:, :3, 3], rest[:, :3, 3], atol=BODY_TOLERANCE)  # joints
    np.testing.assert_allclose(posed[:, :3, :3], rest[:, :3, :3], atol=1e-4)  # orientations
    for garment in fresh.outfit.garments:
        shown = _shown(parts[garment.name])
        # a garment shows its real-time fit as written, undeformed ...
        np.testing.assert_allclose(shown, mesh.read_vertices(parts[garment.name]), atol=1e-6)
        # ... which is within the real-time tolerance of the exact fit
        assert np.abs(shown - garment.mesh.vertices).max() < GARMENT_TOLERANCE, garment.name


def _assert_settled_exactly(root):
    """After settle: a fresh Human's rest, no pose, the Armature modifiers deforming."""
    from avatar.blender import armature, live, mesh

    fresh = _fresh(root)
    assert not live.is_dragging(root) and armature.pose_is_rest(root)
    rest = armature.rest_matrices(root, fresh.skeleton.names)
    np.testing.assert_allclose(rest, fresh.skeleton.rest, atol=BODY_TOLERANCE)
    parts = live.part_objects(root)
    for name, obj in parts.items():
        assert live.DEFORM_OFF_KEY not in obj.keys(), name
        assert all(m.show_viewport for m in obj.modifiers if m.type == "ARMATURE"), name
    np.testing.assert_allclose(mesh.read_vertices(parts["body"]), fresh.mesh.vertices,
                               atol=BODY_TOLERANCE)  # fmt: skip
    np.testing.assert_allclose(_shown(parts["body"]), fresh.mesh.vertices, atol=BODY_TOLERANCE)
    for garment in fresh.outfit.garments:
        np.testing.assert_allclose(mesh.read_vertices(parts[garment.name]),
                                   garment.mesh.vertices, atol=BODY_TOLERANCE)  # fmt: skip
        np.testing.assert_allclose(_shown(parts[garment.name]), garment.mesh.vertices,
                                   atol=BODY_TOLERANCE)  # fmt: skip


def test_a_drag_shows_the_exact_body_and_joints_through_the_pose(dressed):
    import bpy

    from avatar.blender import armature, live

    names = [b.name for b in dressed.data.bones]
    settled_rest = armature.rest_matrices(dressed, names)
    for value in (0.55, 0.56, 0.57, 0.95, 0.2):  # drag steps, then jumps across the middle
        dressed.avatar.weight = value
        bpy.context.view_layer.update()
        assert live.is_dragging(dressed)
        assert dressed.mode == "OBJECT"
        # the rest bones were not touched (no edit mode): the pose shows the new ones
        np.testing.assert_array_equal(armature.rest_matrices(dressed, names), settled_rest)
        _assert_shown_exactly(dressed)
    assert dressed["avatar_settled"] == 0  # exporters and the settle timer know


def test_a_drag_step_re_evaluates_this_character_only(dressed, assets):
    """The edit-mode trip this replaces made Blender re-evaluate every object in the scene."""
    import bpy

    from avatar.blender import character

    other = character.create({"params": {"gender": 1.0}, "clothes": ["tshirt"]},
                             name="Other", location=(2.0, 0.0, 0.0)).root  # fmt: skip
    others = {other.name, *(o.name for o in other.children_recursive)}
    dressed.avatar.weight = 0.55
    bpy.context.view_layer.update()
    updated: list[str] = []

    def collect(scene, depsgraph):
        updated.extend(u.id.name for u in depsgraph.updates if isinstance(u.id, bpy.types.Object))

    bpy.app.handlers.depsgraph_update_post.append(collect)
    try:
        dressed.avatar.weight = 0.56
        bpy.context.view_layer.update()
    finally:
        bpy.app.handlers.depsgraph_update_post.remove(collect)
    assert dressed.name in updated and "body" in {n.split(".")[0] for n in updated}
    assert not others & set(updated), sorted(others & set(updated))


def test_settle_after_a_drag_is_exactly_a_fresh_human(dressed):
    import bpy

    for value in (0.55, 0.56, 0.8):
        dressed.avatar.weight = value
    dressed.avatar.pca_belly = 1.2
    assert bpy.ops.avatar.settle() == {"FINISHED"}
    bpy.context.view_layer.update()
    _assert_settled_exactly(dressed)


def test_a_modifier_the_user_switched_off_stays_off(dressed):
    import bpy

    from avatar.blender import live

    hair = live.part_objects(dressed)["hair-short"]
    hair.modifiers["Armature"].show_viewport = False
    dressed.avatar.weight = 0.6
    assert live.DEFORM_OFF_KEY not in hair.keys()
    bpy.ops.avatar.settle()
    assert hair.modifiers["Armature"].show_viewport is False
    assert all(m.show_viewport for m in live.part_objects(dressed)["body"].modifiers)


def test_a_posed_character_gets_its_rest_bones_written(dressed):
    import bpy

    from avatar.blender import armature, live

    assert bpy.ops.avatar.apply_pose(name="t-pose") == {"FINISHED"}
    posed = armature.pose_matrices(dressed, [b.name for b in dressed.pose.bones])
    dressed.avatar.weight = 0.7
    assert not live.is_dragging(dressed)
    fresh = _fresh(dressed)
    rest = armature.rest_matrices(dressed, fresh.skeleton.names)
    np.testing.assert_allclose(rest, fresh.skeleton.rest, atol=BODY_TOLERANCE)
    assert not armature.pose_is_rest(dressed)  # the T-pose is kept
    assert posed.shape[0] == len(fresh.skeleton.names)


def test_posing_mid_drag_writes_the_true_rest_first(dressed):
    import bpy

    from avatar.blender import armature, live

    dressed.avatar.weight = 0.8
    assert live.is_dragging(dressed)
    assert bpy.ops.avatar.apply_pose(name="t-pose") == {"FINISHED"}
    assert not live.is_dragging(dressed)
    fresh = _fresh(dressed)
    rest = armature.rest_matrices(dressed, fresh.skeleton.names)
    np.testing.assert_allclose(rest, fresh.skeleton.rest, atol=BODY_TOLERANCE)
    body = live.part_objects(dressed)["body"]
    assert all(m.show_viewport for m in body.modifiers)  # the pose deforms the body
    bpy.ops.avatar.settle()
    assert not armature.pose_is_rest(dressed)  # settling does not undo the pose


def test_a_file_is_never_saved_mid_drag(dressed, tmp_path):
    import bpy

    from avatar.blender import live

    dressed.avatar.weight = 0.8
    assert live.is_dragging(dressed)
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "drag.blend"), copy=True)
    assert not live.is_dragging(dressed)
    _assert_settled_exactly(dressed)


def test_an_undo_into_a_drag_settles_it_again(dressed):
    import bpy

    addon_live = importlib.import_module(f"{ADDON}.live")
    dressed.avatar.weight = 0.8
    resume = [h for h in bpy.app.handlers.undo_post if h.__name__ == "_resume_settling"]
    assert len(resume) == 1 and resume[0] in bpy.app.handlers.load_post
    addon_live._PENDING.clear()  # as after an undo: the settle it had pending is gone
    resume[0](bpy.context.scene)  # what Blender calls after restoring an undo step
    assert dressed.name_full in addon_live._PENDING


def test_a_drag_looks_its_garments_up_once(installed, assets, empty_scene, monkeypatch):
    """A user's .mhclo worn: a drag step neither re-resolves nor stats it beyond the
    recipe's own validation (once per garment)."""
    import bpy

    from avatar.blender import character
    from avatar.clothes import library

    if not SHOES.is_file():
        pytest.skip("MakeHuman clothes fixtures not found")
    root = character.create({"params": {}, "clothes": [str(SHOES)]}).root
    root.avatar.weight = 0.55
    calls = []
    real = library.find_garment
    monkeypatch.setattr(library, "find_garment", lambda *a, **k: calls.append(a) or real(*a, **k))
    root.avatar.weight = 0.56
    assert len(calls) <= 1
    bpy.context.view_layer.update()
    _assert_shown_exactly(root)


def test_a_bare_body_drags_exactly(installed, assets, empty_scene):
    import bpy

    from avatar.blender import character, live

    root = character.create({"params": {}, "clothes": []}, rigged=False).root
    for value in (0.55, 0.56, 0.9):
        root.avatar.weight = value
        bpy.context.view_layer.update()
        fresh = _fresh(root)
        body = live.part_objects(root)["body"]
        np.testing.assert_allclose(_shown(body), fresh.mesh.vertices, atol=BODY_TOLERANCE)


def test_affine_inverse_matches_lapack(rng):
    from avatar.blender.armature import affine_inverse

    m = np.tile(np.eye(4), (20, 1, 1))
    m[:, :3, :4] = rng.standard_normal((20, 3, 4))  # shear and scale too
    np.testing.assert_allclose(affine_inverse(m), np.linalg.inv(m), atol=1e-9)
    np.testing.assert_allclose(affine_inverse(m[3]), np.linalg.inv(m[3]), atol=1e-9)


def test_pose_basis_puts_each_bone_at_its_target(rng):
    """Blender's pose rule P_j = P_p (R_p^-1 R_j) B_j, applied down the tree, gives T_j."""
    from bridge_fixtures import bone_matrix, skeleton

    from avatar.blender.armature import pose_basis

    skel = skeleton(rng)
    rest = np.asarray(skel.rest, np.float64)
    heads = rest[:, :3, 3] + rng.normal(0, 0.05, (len(rest), 3))  # moved joints, new rolls
    target = np.stack([bone_matrix(h, h + rng.normal(0, 1, 3), rng.normal(0, 1, 3))
                       for h in heads])  # fmt: skip
    basis = pose_basis(rest, target, skel.parents)
    posed = np.zeros_like(rest)
    for j, p in enumerate(skel.parents):  # parents come first
        offset = rest[j] if p < 0 else np.linalg.inv(rest[p]) @ rest[j]
        posed[j] = (np.eye(4) if p < 0 else posed[p]) @ offset @ basis[j]
    np.testing.assert_allclose(posed, target, atol=1e-9)

"""The Motion panel's operators, run headless on a character made by the installed
extension: clips from a file or a folder, the editable bone mapping and its file, the
quality report, the pose library with thumbnails, rest/T/A-pose, the built-in walk, and
errors that leave the character as it was. Skipped without bpy, the MakeHuman assets or
the BVH fixtures (per test)."""

from __future__ import annotations

import importlib
import importlib.util
import json
import os
import shutil
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
FIXTURES = Path(os.environ.get("AVATAR_FIXTURES", ROOT.parent / "shared" / "fixtures"))
BVH = FIXTURES / "bvh"
WALK = BVH / "cmu_motionbuilder" / "02_01_walk.bvh"
JUMPS = BVH / "cmu_motionbuilder" / "01_01_forward_jumps.bvh"
MAKEHUMAN = BVH / "makehuman_default"
ADDON = "bl_ext.user_default.avatar_addon"

needs_clips = pytest.mark.skipif(not WALK.is_file(), reason="needs the CMU BVH fixtures")




@pytest.fixture
def human(human):
    """The shared new human (conftest), with fresh Motion panel settings."""
    import bpy

    settings = bpy.context.scene.avatar_motion
    for name in ("bvh_path", "map_path", "pose_folder"):
        setattr(settings, name, "")
    settings.custom_map, settings.custom_table, settings.match_names = False, "{}", True
    settings.frame_start = settings.frame_end = 0
    return human


def _settings():
    import bpy

    return bpy.context.scene.avatar_motion


def _root():
    import bpy

    return bpy.context.view_layer.objects.active


def _state(root):
    """What a failed operator must leave alone: objects, vertices, recipe, pose, action."""
    import bpy

    from avatar.blender import live, mesh

    parts = live.part_objects(root)
    action = root.animation_data.action.name if root.animation_data and \
        root.animation_data.action else None  # fmt: skip
    pose = [tuple(b.rotation_quaternion) for b in root.pose.bones]
    objects = sorted(o.name for o in bpy.data.objects)
    return (root.name, root["avatar_recipe"], sorted(parts), objects,
            {n: mesh.read_vertices(o).copy() for n, o in parts.items()}, action, pose)  # fmt: skip


def _assert_same_state(before, after):
    assert before[:4] == after[:4]
    for name in before[2]:
        np.testing.assert_array_equal(before[4][name], after[4][name])
    assert before[5:] == after[5:]


def _bone_curves(root, bone):
    """(frames, 4) the keyed rotation_quaternion of a pose bone, per frame."""
    from avatar.blender import action

    path = f'pose.bones["{bone}"].rotation_quaternion'
    curves = sorted((c for c in action.action_curves(root.animation_data.action)
                     if c.data_path == path), key=lambda c: c.array_index)  # fmt: skip
    assert len(curves) == 4, bone
    return np.stack([[p.co[1] for p in c.keyframe_points] for c in curves], axis=1)


def _module(name):
    return importlib.import_module(f"{ADDON}.{name}")


def _world_head(root, bone):
    import bpy

    bpy.context.view_layer.update()
    pb = root.pose.bones[bone]
    return np.array(root.matrix_world @ pb.head)


def _arm_drop_degrees(root, side):
    """Degrees the upper arm points below horizontal (shoulder to elbow)."""
    d = _world_head(root, f"lowerarm01.{side}") - _world_head(root, f"upperarm01.{side}")
    return float(np.degrees(np.arcsin(-d[2] / np.linalg.norm(d))))


def _clip_folder(tmp_path, *clips):
    folder = tmp_path / "clips"
    folder.mkdir()
    for clip in clips:
        shutil.copy(clip, folder / clip.name)
    return folder


# ------------------------------------------------------------------------ registration


def test_panel_settings_and_operators_register(installed):
    import bpy

    panel = bpy.types.AVATAR_PT_motion
    assert panel.bl_order == 2 and panel.bl_category == "Avatar"
    for op in ("apply_motion", "list_clips", "map_bones", "reset_bone_map", "save_bone_map",
               "load_bone_map", "apply_pose", "rest_pose", "walk", "refresh_poses"):  # fmt: skip
        assert hasattr(bpy.ops.avatar, op), op
    props = bpy.types.Scene.bl_rna.properties["avatar_motion"].fixed_type.bl_rna.properties
    for name in ("bvh_path", "clips", "frame_start", "frame_end", "fps", "in_place", "bones",
                 "walk_speed", "walk_steps", "poses"):  # fmt: skip
        assert name in props, name


# ------------------------------------------------------------------------ clips


def test_the_clip_plays_at_its_own_rate_unless_resample_is_on(installed):
    """The rate field read "FPS 0.00" (0 meaning the clip's own rate), taken for a broken
    clip in the real window: a Resample toggle now says it, and FPS is a real rate."""
    settings = _settings()
    spec = _module("panel_motion").motion_spec
    settings.resample = False
    assert settings.fps == 30.0 and spec(settings, "walk.bvh")["fps"] is None
    settings.resample, settings.fps = True, 24.0
    try:
        assert spec(settings, "walk.bvh")["fps"] == 24.0
    finally:
        settings.resample, settings.fps = False, 30.0



@needs_clips
def test_a_folder_lists_its_clips_and_reports_a_bad_one(human, tmp_path):
    import bpy

    folder = _clip_folder(tmp_path, WALK, JUMPS)
    (folder / "broken.bvh").write_text("HIERARCHY\nROOT Hips\n{\n OFFSET 0 0\n")
    (folder / "empty.bvh").write_text(WALK.read_text().split("MOTION")[0]
                                      + "MOTION\nFrames: 0\nFrame Time: 0.033333\n")  # fmt: skip
    settings = _settings()
    settings.bvh_path = str(folder)
    names = [c.name for c in settings.clips]
    assert names == ["01_01_forward_jumps", "02_01_walk", "broken", "empty"]
    errors = {c.name: c.error for c in settings.clips}
    assert errors["broken"] and "frames" in errors["empty"].lower()
    assert not errors["02_01_walk"] and not errors["01_01_forward_jumps"]
    walk = settings.clips[names.index("02_01_walk")]
    from avatar.io import bvh

    data = bvh.read(WALK)
    assert walk.frames == data.frames > 100 and walk.fps == pytest.approx(data.fps)
    assert not settings.clips[settings.clip_index].error  # a usable clip is chosen
    assert bpy.ops.avatar.list_clips() == {"FINISHED"}
    assert len(settings.clips) == 4

    settings.clip_index = names.index("broken")  # Apply on a bad clip: its error, no change
    before = _state(human)
    with pytest.raises(RuntimeError, match="broken"):
        bpy.ops.avatar.apply_motion()
    _assert_same_state(before, _state(human))


@needs_clips
def test_apply_from_a_folder_plays_the_chosen_clip_and_keeps_the_report(human, tmp_path):
    import bpy

    folder = _clip_folder(tmp_path, JUMPS, WALK)
    name = human.name
    settings = _settings()
    settings.bvh_path = str(folder)
    settings.clip_index = [c.name for c in settings.clips].index("02_01_walk")
    settings.frame_end = 10
    assert bpy.ops.avatar.apply_motion() == {"FINISHED"}
    root = _root()
    assert root.name == name  # rebuilt under its own name
    assert json.loads(root["avatar_motion"])["path"] == str(folder / "02_01_walk.bvh")
    assert len(_bone_curves(root, "upperarm01.L")) == 10
    card = json.loads(root["avatar_motion_card"])
    assert card["frames"] == 10 and card["mapped"] >= 20
    assert 0 <= card["direction_median"] < 15 and card["skating_cm"] >= 0
    rows = _module("motion_report").rows(root)
    labels = [label for label, _, _ in rows]
    for want in ("Error", "Skating", "Floor"):
        assert want in labels, labels
    assert all(isinstance(v, str) and v for _, v, _ in rows)


# ------------------------------------------------------------------------ bone mapping


@needs_clips
def test_the_mapping_is_shown_and_an_edit_changes_which_bones_animate(human):
    import bpy

    settings = _settings()
    settings.bvh_path, settings.frame_end = str(WALK), 8
    assert bpy.ops.avatar.map_bones() == {"FINISHED"}
    rows = {b.name: b for b in settings.bones}
    assert len(rows) == 31  # every CMU bone, mapped or not
    assert (rows["LeftArm"].target, rows["LeftArm"].role) == ("upperarm01.L", "upperarm.L")
    assert rows["LeftUpLeg"].target == "upperleg01.L" and rows["LHipJoint"].target == ""
    assert "upperarm01.L" in {b.name for b in settings.avatar_bones}
    assert not settings.custom_map

    assert bpy.ops.avatar.apply_motion() == {"FINISHED"}
    moving = _bone_curves(_root(), "upperarm01.L")
    assert np.ptp(moving, axis=0).max() > 0.02  # the clip swings the arm

    rows["LeftArm"].target = ""  # unmap the clip's left upper arm
    assert settings.custom_map
    assert "upperarm.L" not in json.loads(settings.custom_table)
    assert {b.name: b.target for b in settings.bones}["LeftArm"] == ""
    assert bpy.ops.avatar.apply_motion() == {"FINISHED"}
    root = _root()
    assert "upperarm.L" not in json.loads(root["avatar_motion"])["bone_map"]
    still = _bone_curves(root, "upperarm01.L")
    assert np.ptp(still, axis=0).max() < 1e-6  # follows its parent: no rotation of its own
    assert np.ptp(_bone_curves(root, "upperleg01.L"), axis=0).max() > 0.02  # legs still walk

    # Re-target: the clip's left arm drives the right upper arm's role instead.
    right = {b.name: b for b in settings.bones}["LeftArm"]
    right.target = "upperarm01.R"
    table = json.loads(settings.custom_table)
    assert table["upperarm.R"] == ["LeftArm"]
    assert {b.name: b.target for b in settings.bones}["RightArm"] == ""  # one bone a role


@needs_clips
def test_the_bone_map_file_round_trips(human, tmp_path):
    import bpy

    from avatar.motion import bonemap

    settings = _settings()
    settings.bvh_path = str(WALK)
    bpy.ops.avatar.map_bones()
    automatic = [(b.name, b.target, b.role) for b in settings.bones]
    {b.name: b for b in settings.bones}["LeftHand"].target = ""
    edited = [(b.name, b.target, b.role) for b in settings.bones]
    table = json.loads(settings.custom_table)
    path = tmp_path / "cmu_edited.json"
    assert bpy.ops.avatar.save_bone_map(filepath=str(path)) == {"FINISHED"}
    saved = json.loads(path.read_text())
    assert saved["bones"] == table and "hand.L" not in saved["bones"]
    assert bonemap.load(path) == table  # the library's own format

    assert bpy.ops.avatar.reset_bone_map() == {"FINISHED"}
    assert not settings.custom_map
    assert [(b.name, b.target, b.role) for b in settings.bones] == automatic
    assert edited != automatic
    assert bpy.ops.avatar.load_bone_map(filepath=str(path)) == {"FINISHED"}
    assert settings.custom_map and json.loads(settings.custom_table) == table
    assert [(b.name, b.target, b.role) for b in settings.bones] == edited


@needs_clips
def test_a_bad_bone_map_file_is_a_report_that_changes_nothing(human, tmp_path):
    import bpy

    settings = _settings()
    settings.bvh_path = str(WALK)
    bpy.ops.avatar.map_bones()
    before_rows = [(b.name, b.target) for b in settings.bones]
    before = _state(human)
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(RuntimeError, match="bad.json"):
        bpy.ops.avatar.load_bone_map(filepath=str(bad))
    wrong = tmp_path / "wrong.json"
    wrong.write_text(json.dumps({"bones": {"elbow.L": ["LeftForeArm"]}}))
    with pytest.raises(RuntimeError, match="elbow.L"):
        bpy.ops.avatar.load_bone_map(filepath=str(wrong))
    with pytest.raises(RuntimeError, match="no such bone map"):
        bpy.ops.avatar.load_bone_map(filepath=str(tmp_path / "none.json"))
    assert not settings.custom_map and [(b.name, b.target) for b in settings.bones] == before_rows
    _assert_same_state(before, _state(human))


# ------------------------------------------------------------------------ errors


@needs_clips
def test_errors_are_one_line_reports_and_leave_the_character(human, tmp_path):
    import bpy

    settings = _settings()
    before = _state(human)
    settings.bvh_path = str(tmp_path / "missing.bvh")
    with pytest.raises(RuntimeError, match="no such BVH file"):
        bpy.ops.avatar.apply_motion()
    empty = tmp_path / "zero.bvh"
    empty.write_text(WALK.read_text().split("MOTION")[0] + "MOTION\nFrames: 0\n"
                     "Frame Time: 0.033333\n")  # fmt: skip
    settings.bvh_path = str(empty)
    with pytest.raises(RuntimeError, match="no motion|no frames"):
        bpy.ops.avatar.apply_motion()
    hollow = tmp_path / "hollow"
    hollow.mkdir()
    settings.bvh_path = str(hollow)
    assert "no .bvh clips" in settings.folder_error
    with pytest.raises(RuntimeError, match="no .bvh clips"):
        bpy.ops.avatar.apply_motion()
    with pytest.raises(RuntimeError, match="no .bvh clips"):
        bpy.ops.avatar.list_clips()
    settings.bvh_path = str(WALK)  # a mapping without hips cannot drive the character
    settings.custom_map, settings.custom_table = True, json.dumps({"head": ["Head"]})
    with pytest.raises(RuntimeError, match="hips"):
        bpy.ops.avatar.apply_motion()
    settings.custom_table = "{broken"
    with pytest.raises(RuntimeError, match="not JSON"):
        bpy.ops.avatar.apply_motion()
    with pytest.raises(RuntimeError, match="pose"):
        bpy.ops.avatar.apply_pose(name="no-such-pose")
    assert human.name in bpy.data.objects
    _assert_same_state(before, _state(human))


# ------------------------------------------------------------------------ poses


def test_t_pose_a_pose_and_rest(human):
    import bpy

    from avatar.blender import live, mesh

    bpy.ops.avatar.wear(name="tshirt")
    root = _root()
    tshirt = live.part_objects(root)["tshirt"]

    def shirt():
        bpy.context.view_layer.update()
        evaluated = tshirt.evaluated_get(bpy.context.evaluated_depsgraph_get())
        return mesh.read_vertices(evaluated).copy()

    def sleeve_span():
        x = shirt()[:, 0]
        return float(x.max() - x.min())

    at_rest = shirt()
    rest_span = sleeve_span()
    rest_drop = _arm_drop_degrees(root, "L")
    assert bpy.ops.avatar.apply_pose(name="t-pose") == {"FINISHED"}
    for side in ("L", "R"):
        assert abs(_arm_drop_degrees(root, side)) < 3.0
    assert sleeve_span() > rest_span + 0.03  # the sleeves follow the arms out
    assert np.linalg.norm(shirt() - at_rest, axis=1).max() > 0.05
    assert bpy.ops.avatar.apply_pose(name="a-pose") == {"FINISHED"}
    for side in ("L", "R"):
        assert _arm_drop_degrees(root, side) == pytest.approx(45.0, abs=3.0)
    assert bpy.ops.avatar.rest_pose() == {"FINISHED"}
    for bone in root.pose.bones:
        np.testing.assert_allclose(bone.rotation_quaternion, (1, 0, 0, 0), atol=1e-7)
        np.testing.assert_allclose(bone.location, (0, 0, 0), atol=1e-7)
    assert _arm_drop_degrees(root, "L") == pytest.approx(rest_drop, abs=1e-3)
    np.testing.assert_allclose(shirt(), at_rest, atol=1e-5)


@needs_clips
def test_a_pose_or_rest_stops_the_motion(human):
    import bpy

    settings = _settings()
    settings.bvh_path, settings.frame_end = str(WALK), 6
    assert bpy.ops.avatar.apply_motion() == {"FINISHED"}
    root = _root()
    assert root.animation_data.action is not None and "avatar_motion" in root.keys()
    assert bpy.ops.avatar.apply_pose(name="t-pose") == {"FINISHED"}
    assert root.animation_data.action is None
    assert "avatar_motion" not in root.keys() and "avatar_motion_card" not in root.keys()
    bpy.context.scene.frame_set(4)  # no action to take the pose away
    assert abs(_arm_drop_degrees(root, "L")) < 3.0
    assert bpy.ops.avatar.apply_motion() == {"FINISHED"}
    assert bpy.ops.avatar.rest_pose() == {"FINISHED"}
    root = _root()
    assert root.animation_data is None or root.animation_data.action is None
    assert not _module("motion_report").rows(root)


@pytest.mark.skipif(not (MAKEHUMAN / "sit01.bvh").is_file(), reason="needs the MakeHuman poses")
def test_the_pose_library_lists_poses_with_thumbnails_and_poses_in_one_click(human, tmp_path):
    import bpy

    from avatar.body import assets
    from avatar.io import png

    folder = tmp_path / "poses"
    folder.mkdir()
    for name in ("sit01", "standing01"):
        shutil.copy(MAKEHUMAN / f"{name}.bvh", folder)
        shutil.copy(MAKEHUMAN / f"{name}.meta", folder)
    thumb = folder / "standing01.thumb"  # MakeHuman's thumbnails are PNG files
    thumb.write_bytes(png.encode(np.full((8, 8, 3), 200, np.uint8)))
    settings = _settings()
    settings.pose_folder = str(folder)
    assert bpy.ops.avatar.refresh_poses() == {"FINISHED"}
    poses = {p.name: p for p in settings.poses}
    assert {"rest", "t-pose", "a-pose", "sit01", "standing01"} <= set(poses)

    cache = _module("motion_cache")
    assert cache.thumbnail_path("standing01", poses["standing01"].path) == str(thumb)
    drawn = Path(cache.thumbnail_path("sit01", poses["sit01"].path))
    assert drawn.is_file() and drawn.parent == assets.cache_root() / "thumbnails"
    assert drawn.read_bytes()[:8] == png.SIGNATURE
    stamp = drawn.stat().st_mtime_ns
    assert cache.thumbnail_path("sit01", poses["sit01"].path) == str(drawn)  # drawn once
    assert drawn.stat().st_mtime_ns == stamp
    # Headless Blender gives previews no icon ids (0) but loads their images.
    for name, path, size in (("sit01", poses["sit01"].path, 96), ("t-pose", "", 96),
                             ("standing01", poses["standing01"].path, 8)):  # fmt: skip
        cache.pose_icon(name, path)
        assert tuple(cache.previews()[f"{name}|{path}"].image_size) == (size, size)

    root = _root()
    hips = _world_head(root, "upperleg01.L")[2]
    assert bpy.ops.avatar.apply_pose(name=poses["sit01"].path) == {"FINISHED"}
    assert _world_head(root, "upperleg01.L")[2] < hips - 0.2  # sitting: hips lower
    assert bpy.ops.avatar.apply_pose(name="sit01") == {"FINISHED"}  # by name, from the folder


# ------------------------------------------------------------------------ walk


def test_the_built_in_walk_has_its_speed_and_steps(human):
    import bpy

    from avatar.blender import live
    from avatar.motion import gait

    bpy.ops.avatar.wear(name="tshirt")  # a dressed character
    settings = _settings()
    settings.walk_speed, settings.walk_steps = 1.0, 4
    bpy.context.scene.render.fps, bpy.context.scene.render.fps_base = 24, 1.0
    assert bpy.ops.avatar.walk() == {"FINISHED"}
    root = _root()
    bpy.context.scene.frame_set(1)
    leg = gait.leg_length(_module("motion_cache").human(root).skeleton)
    seconds = 4 / (2 * 1.0 / (gait.STRIDE_LEGS * leg))
    frames = len(_bone_curves(root, "upperleg01.L"))
    assert frames == round(seconds * 24)
    start = _world_head(root, "root")
    bpy.context.scene.frame_set(frames)
    travelled = np.linalg.norm((_world_head(root, "root") - start)[:2])
    assert travelled == pytest.approx(1.0 * (frames - 1) / 24, rel=0.05)  # 1 m/s
    spec = json.loads(root["avatar_motion"])
    assert spec["walk"] == {"speed": 1.0, "steps": 4}
    tshirt = live.part_objects(root)["tshirt"]  # garments get the baked corrections
    assert tshirt.data.shape_keys is not None
    assert any(k.name.startswith("correction") for k in tshirt.data.shape_keys.key_blocks)
    assert bpy.ops.avatar.walk(speed=1.6, steps=2) == {"FINISHED"}  # or given directly
    assert json.loads(_root()["avatar_motion"])["walk"] == {"speed": 1.6, "steps": 2}


# ------------------------------------------------------------------------ report box width


WORST_CARD = {"source": "makehuman_default_skeleton", "mapped": 163, "scale": 12.3456,
              "frames": 123456, "fps": 119.88, "direction_median": 123.45,
              "direction_p95": 179.99, "worst_bone": "upperarm01.L", "worst_deg": 179.9,
              "skating_cm": 123.456, "contact_frames": 12345, "limit_violations": 12345,
              "floor_penetration_cm": 123.456, "floor_penetrating": 1.0, "hover_cm": 123.45,
              "hover_max_cm": 999.99, "deformed": ["upperarm01.L", "lowerarm01.R", "x"]}


def test_report_rows_fit_the_sidebar_at_its_default_width():
    """Every label, and every value that is a number, of the worst-case card is narrower
    than its column at the sidebar's default width, measured in pixels in Blender's UI font
    (at 10 characters and an icon each the labels showed as "So...", "Di..." in the real
    window, tests/ui)."""
    pytest.importorskip("bpy")
    import blf

    from avatar.motion import report_card

    blf.size(0, 11)  # the UI's label text at scale 1 ("30 frames, 120 fps": 100 px, as seen)
    assert blf.dimensions(0, "30 frames, 120 fps")[0] == pytest.approx(100, abs=3)
    rows = report_card.lines(WORST_CARD)
    assert len(rows) == 10
    for label, value, _ in rows:
        assert blf.dimensions(0, label)[0] <= report_card.LABEL_PX, label
        if label not in report_card.NAMED:
            assert blf.dimensions(0, value)[0] <= report_card.VALUE_PX, value
    short = dict(WORST_CARD, direction_median=1.234, direction_p95=2.5, skating_cm=0.123)
    values = {label: value for label, value, _ in report_card.lines(short)}
    assert values["Error"] == "1.2\u00b0 (p95 2.5\u00b0)" and values["Skating"] == "0.12 cm/frame"


def test_the_panel_splits_rows_where_the_card_was_measured():
    from avatar.motion import report_card

    spec = importlib.util.spec_from_file_location(
        "motion_report", ROOT / "addon" / "avatar_addon" / "motion_report.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module.LABEL_SHARE == report_card.LABEL_SHARE

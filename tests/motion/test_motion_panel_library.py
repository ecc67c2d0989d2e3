"""The library side of the Blender Motion panel: clip folders, the editable bone mapping and
its file, the report card, the walk by speed and steps, pose thumbnails."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import numpy as np
import pytest

from avatar.errors import FormatError, ParameterError
from avatar.motion import bonemap, clips, gait, mapping, report_card

FIXTURES = Path(os.environ.get("AVATAR_FIXTURES", Path(__file__).resolve().parents[3] / "shared"
                               / "fixtures"))  # fmt: skip
WALK = FIXTURES / "bvh" / "cmu_motionbuilder" / "02_01_walk.bvh"
needs_clips = pytest.mark.skipif(not WALK.is_file(), reason="needs the CMU BVH fixtures")


@pytest.fixture(scope="module")
def human(assets):
    from avatar.human import Human

    return Human({})


@needs_clips
def test_a_folder_lists_good_and_bad_clips(tmp_path):
    shutil.copy(WALK, tmp_path / "walk.bvh")
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "bad.BVH").write_text("HIERARCHY\n")
    (tmp_path / "notes.txt").write_text("not a clip")
    found = clips.list_folder(tmp_path)
    assert [c.name for c in found] == ["sub/bad", "walk"]
    assert found[0].error and found[0].frames == 0
    assert not found[1].error and found[1].frames > 100 and found[1].seconds > 1


def test_an_empty_or_missing_folder_is_an_error(tmp_path):
    with pytest.raises(ParameterError, match="no .bvh clips"):
        clips.list_folder(tmp_path)
    with pytest.raises(ParameterError, match="no such folder"):
        clips.list_folder(tmp_path / "none")


@needs_clips
def test_rows_match_the_retarget_and_a_table_changes_them(human):
    from avatar.motion import load_bvh, retarget

    skeleton, clip = load_bvh(WALK)
    rows = mapping.rows(skeleton, clip, human.skeleton)
    assert [r.source for r in rows] == list(skeleton.names)
    _, report = retarget(skeleton, clip, human.skeleton, frames=slice(0, 4), measure=False,
                         fix_feet=False)  # fmt: skip
    assert {(r.source, r.target) for r in rows if r.target} == {m[1:] for m in report.mapped}
    table = mapping.table_of((r.source, r.role) for r in rows)
    del table["upperarm.L"]
    edited = {r.source: r for r in mapping.rows(skeleton, clip, human.skeleton, table)}
    assert edited["LeftArm"].target == "" and edited["RightArm"].target == "upperarm01.R"
    roles = mapping.roles_of(human.skeleton)
    assert roles["upperarm01.L"] == "upperarm.L" and len(roles) >= 21


def test_table_of_rejects_a_role_twice_or_unknown():
    assert mapping.table_of([("A", "hips"), ("B", ""), ("C", "head")]) == {
        "hips": ["A"], "head": ["C"]}  # fmt: skip
    with pytest.raises(ParameterError, match="twice"):
        mapping.table_of([("A", "hips"), ("B", "hips")])
    with pytest.raises(ParameterError, match="elbow"):
        mapping.table_of([("A", "elbow.L")])


def test_a_bone_map_file_round_trips_in_bonemaps_format(tmp_path):
    table = {"head": ["Head"], "hips": ["Hips"], "thigh.L": ["LeftUpLeg"]}
    path = mapping.save(tmp_path / "mine.json", table)
    data = json.loads(path.read_text())
    assert list(data["bones"]) == ["hips", "head", "thigh.L"] and data["name"] == "mine"
    assert mapping.load(path) == table == bonemap.load(path)
    (tmp_path / "bad.json").write_text("{oops")
    with pytest.raises(FormatError, match="bad.json"):
        mapping.load(tmp_path / "bad.json")
    with pytest.raises(ParameterError, match="no such bone map"):
        mapping.load(tmp_path / "none.json")
    with pytest.raises(ParameterError):
        mapping.save(tmp_path / "x.json", {"elbow": ["E"]})
    assert not (tmp_path / "x.json").exists()


@needs_clips
def test_the_report_card_has_the_numbers_the_panel_shows(human):
    from avatar.motion import load_bvh, retarget

    skeleton, clip = load_bvh(WALK)
    _, report = retarget(skeleton, clip, human.skeleton, body=human.body, frames=slice(0, 30))
    card = report_card.card(report)
    json.dumps(card)  # storable on a character
    assert card["frames"] == 30 and card["direction_p95"] >= card["direction_median"] >= 0
    labels = [row[0] for row in report_card.lines(card)]
    assert {"Error", "Skating", "Floor", "Hover"} <= set(labels)
    bad = dict(card, direction_p95=40.0, floor_penetration_cm=3.0)
    alerts = {label for label, _, alert in report_card.lines(bad) if alert}
    assert {"Error", "Floor"} <= alerts


def test_the_walk_goes_at_its_speed_for_its_steps(human):
    walk = gait.walk(human.skeleton, speed=1.2, steps=6, fps=30)
    rate = gait.cadence(human.skeleton, 1.2)
    assert walk.frames == round(6 / (2 * rate) * 30)
    from avatar.rig import kinematics

    world = kinematics.forward(human.skeleton, walk.rotations, walk.translations)
    travel = np.linalg.norm(world[-1, 0, :2, 3] - world[0, 0, :2, 3])
    assert travel == pytest.approx(1.2 * (walk.frames - 1) / 30, rel=0.02)
    for bad in ({"speed": 9.0}, {"steps": 0}, {"fps": 0.0}):
        with pytest.raises(ParameterError):
            gait.walk(human.skeleton, **bad)


def test_a_thumbnail_shows_the_pose(human):
    from avatar.motion import thumbnail

    rest = thumbnail.picture(human.body, human.pose("rest"), 64)
    t = thumbnail.picture(human.body, human.pose("t-pose"), 64)
    assert rest.shape == (64, 64, 4) and rest.dtype == np.uint8
    width = [np.flatnonzero((im[..., 3] > 0).any(axis=0)) for im in (rest, t)]
    assert np.ptp(width[1]) > 1.3 * np.ptp(width[0])  # arms out: a wider figure
    assert (rest[..., 3] > 0).mean() > 0.05 and rest[0, 0, 3] == 0  # a figure, clear corners

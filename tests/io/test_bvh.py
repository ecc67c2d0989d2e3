"""BVH text format and conversion: round trips, the real-world traps, typed errors, fuzzing."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from avatar.errors import FormatError
from avatar.io import bvh
from avatar.rig import quaternion
from avatar.rig.kinematics import forward

FIXTURES = Path(__file__).resolve().parents[2] / ".." / "shared" / "fixtures" / "bvh"
CLIPS = sorted(FIXTURES.glob("*/*.bvh")) if FIXTURES.is_dir() else []
needs_fixtures = pytest.mark.skipif(not CLIPS, reason="../shared/fixtures/bvh is absent")

SMALL = """HIERARCHY
ROOT mixamorig:Hips
{
\tOFFSET 0 90 0
\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
\tJOINT mixamorig:Spine
\t{
\t\tOFFSET 0 10 0
\t\tCHANNELS 3 Xrotation Yrotation Zrotation
\t\tEnd Site
\t\t{
\t\t\tOFFSET 0 50 0
\t\t}
\t}
\tJOINT Left Leg
\t{
\t\tOFFSET 10 -5 0
\t\tCHANNELS 6 Xposition Yposition Zposition Yrotation Zrotation Xrotation
\t\tEnd Site
\t\t{
\t\t\tOFFSET 0 -80 0
\t\t}
\t}
}
MOTION
Frames: 2
Frame Time: .0333333
1 90 2\t10 20 30 5 -5 15 0 0 0 30 0 0
0 91 0 0 0 0 0 0 0 1 2 3 0 0 45
"""


def _euler_matrix(angles_deg, axes: str) -> np.ndarray:
    """Reference: R = R_axes[0] @ R_axes[1] @ R_axes[2] built from explicit matrices."""
    out = np.eye(3)
    for a, axis in zip(np.radians(angles_deg), axes, strict=True):
        c, s = np.cos(a), np.sin(a)
        m = {"X": [[1, 0, 0], [0, c, -s], [0, s, c]], "Y": [[c, 0, s], [0, 1, 0], [-s, 0, c]],
             "Z": [[c, -s, 0], [s, c, 0], [0, 0, 1]]}[axis]  # fmt: skip
        out = out @ np.array(m)
    return out


def test_parses_names_channels_and_mixed_orders():
    data = bvh.loads(SMALL)
    assert data.names == ("mixamorig:Hips", "mixamorig:Spine", "Left Leg")
    assert data.parents.tolist() == [-1, 0, 0]
    assert data.motion.shape == (2, 15)
    assert data.fps == pytest.approx(30.0, rel=1e-5)
    q = bvh.local_rotations(data)
    ref = _euler_matrix([10, 20, 30], "ZXY")
    assert np.allclose(quaternion.to_matrix(q[0, 0]), ref)
    assert np.allclose(quaternion.to_matrix(q[1, 2]), _euler_matrix([0, 0, 45], "YZX"))


def test_position_channels_absolute_on_root_and_auto_on_joints():
    data = bvh.loads(SMALL)
    t = bvh.local_translations(data)
    assert np.allclose(t[0, 0], [1, 90, 2])  # root: absolute
    assert np.allclose(t[1, 2], [11, -3, 3])  # joint values near zero: deltas added to OFFSET
    assert np.allclose(bvh.local_translations(data, "absolute")[1, 2], [1, 2, 3])


def test_text_round_trip_is_lossless():
    data = bvh.loads(SMALL)
    again = bvh.loads(bvh.dumps(data))
    assert again.names == data.names and again.channels == data.channels
    assert np.allclose(again.motion, data.motion) and np.allclose(again.offsets, data.offsets)
    assert np.array_equal(np.isnan(again.end_sites), np.isnan(data.end_sites))


def test_crlf_tabs_and_exponent_frame_time():
    text = SMALL.replace("Frame Time: .0333333", "Frame Time:\t3.33333e-2").replace("\n", "\r\n")
    assert bvh.loads(text).frame_time == pytest.approx(1 / 30, rel=1e-5)


def test_conversion_to_avatar_frame_matches_raw_forward_kinematics():
    data = bvh.loads(SMALL)
    skeleton, anim = bvh.to_animation(data, unit="cm", up="y")
    world = forward(skeleton, anim.rotations, anim.translations)[..., :3, 3]
    raw = bvh.world_positions(data) @ bvh.up_rotation("y").T * 0.01
    assert np.allclose(world, raw, atol=1e-12)
    assert np.allclose(skeleton.heads[0], [0, 0, 0.9])  # Y-up cm -> Z-up m


def test_avatar_animation_round_trips_through_bvh(tmp_path):
    data = bvh.loads(SMALL)
    skeleton, anim = bvh.to_animation(data, unit="cm", up="y")
    path = tmp_path / "out.bvh"
    bvh.save(path, skeleton, anim, unit="mm", up="z", order="YXZ")
    sk2, an2 = bvh.load(path, unit="mm", up="z")
    a = forward(skeleton, anim.rotations, anim.translations)
    b = forward(sk2, an2.rotations, an2.translations)
    assert np.allclose(a[..., :3, 3], b[..., :3, 3], atol=1e-6)


@pytest.mark.parametrize(
    ("mutate", "line", "words"),
    [
        (lambda t: t.replace("Frames: 2", "Frames: 3"), 29, "truncated"),
        (lambda t: t.replace("0 0 0 1 2 3 0 0 45", "0 0 0 1 2 3 0 45"), 29, "values"),
        (lambda t: t.replace("0 91 0", "0 nan 0"), 29, "not finite"),
        (lambda t: t.replace("0 91 0", "0 9x1 0"), 29, "not a number"),
        (lambda t: t.replace("CHANNELS 3", "CHANNELS 7"), 9, "channel count"),
        (lambda t: t.replace("Xrotation Yrotation Z", "Xrotation Yrot Z"), 9, "channel"),
        (lambda t: t.replace("OFFSET 0 10 0", "OFFSET 0 ten 0"), 8, "not a number"),
        (lambda t: t.replace("Frame Time: .0333333", "Frame Time: fast"), 27, "frame time"),
        (lambda t: t.replace("MOTION", "MOTIONS"), 0, "MOTION"),
        (lambda t: t[: t.index("\t\tEnd Site")] + "MOTION\nFrames: 0\nFrame Time: 1\n", 0, "ends"),
    ],
)
def test_malformed_files_raise_format_error_with_line(mutate, line, words):
    with pytest.raises(FormatError) as err:
        bvh.loads(mutate(SMALL), path="clip.bvh")
    assert err.value.path == "clip.bvh"
    assert words.lower() in err.value.message.lower()
    if line:
        assert err.value.line == line


@st.composite
def _skeletons(draw):
    count = draw(st.integers(1, 6))
    parents = [-1]
    for j in range(1, count):  # parent on the path to the previous joint: file (DFS) order
        path = [j - 1]
        while parents[path[-1]] >= 0:
            path.append(parents[path[-1]])
        parents.append(draw(st.sampled_from(path)))
    orders = [draw(st.permutations("XYZ")) for _ in range(count)]
    six = [j == 0 or draw(st.booleans()) for j in range(count)]
    frames = draw(st.integers(0, 4))
    floats = st.floats(-180, 180, allow_nan=False, width=32)
    offsets = np.array(draw(st.lists(floats, min_size=3 * count, max_size=3 * count)))
    width = sum(6 if s else 3 for s in six)
    motion = np.array(draw(st.lists(floats, min_size=width * frames, max_size=width * frames)))
    chans = tuple(
        (("Xposition", "Yposition", "Zposition") if s else ()) + tuple(f"{a}rotation" for a in o)
        for s, o in zip(six, orders, strict=True)
    )
    is_leaf = [j not in parents for j in range(count)]
    ends = np.array([[0.0, 1.0, 0.0] if leaf else [np.nan] * 3 for leaf in is_leaf])
    return bvh.BvhData(tuple(f"j{j}" for j in range(count)), np.array(parents, np.int32),
                       offsets.reshape(count, 3), chans, ends, motion.reshape(frames, width),
                       1 / 24)  # fmt: skip


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_skeletons())
def test_fuzz_dumps_loads_round_trip(data):
    again = bvh.loads(bvh.dumps(data, precision=6))
    assert again.names == data.names and again.channels == data.channels
    assert again.parents.tolist() == data.parents.tolist()
    assert np.allclose(again.motion, data.motion, atol=1e-5)


@settings(max_examples=150, deadline=None)
@given(st.integers(0, len(SMALL) - 1), st.integers(0, 40), st.sampled_from(list("x{\n-9") + [""]))
def test_fuzz_corrupted_text_gives_data_or_format_error(start, length, insert):
    text = SMALL[:start] + insert + SMALL[start + length :]
    try:
        data = bvh.loads(text)
    except FormatError:
        return
    assert data.motion.shape == (data.frames, sum(len(c) for c in data.channels))
    assert np.all(np.isfinite(data.motion))


@needs_fixtures
@pytest.mark.parametrize("clip", CLIPS, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_every_fixture_clip_loads_upright_and_human_sized(clip):
    skeleton, anim = bvh.load(clip)
    world = forward(skeleton, anim.rotations[:: max(1, anim.frames // 20)],
                    anim.translations[:: max(1, anim.frames // 20)])[..., :3, 3]  # fmt: skip
    head = next(j for j, n in enumerate(skeleton.names) if n.lower().endswith("head"))
    feet = [j for j, n in enumerate(skeleton.names) if "foot" in n.lower() or "ankle" in n.lower()]
    up = np.median(world[:, head, 2] - world[:, feet, 2].mean(axis=1))
    assert 0.5 < up < 2.0, (skeleton.extra, up)  # head above feet (crouches too), metres
    data = bvh.read(clip)
    assert bvh.loads(bvh.dumps(data)).motion.shape == data.motion.shape


@pytest.mark.parametrize(
    "motion",
    [
        "MOTION\n\nFrames: 2\nFrame Time: .0333333\n",  # a blank line after MOTION
        "MOTION\r\n\r\nFrames: 2\r\n\r\nFrame Time: .0333333\r\n\r\n",  # blank lines anywhere
        "MOTION  \n \t \nFrames: 2\nFrame Time: .0333333\n",  # whitespace-only lines
    ],
)
def test_blank_lines_in_the_motion_header_are_accepted(motion):
    text = SMALL.replace("MOTION\nFrames: 2\nFrame Time: .0333333\n", motion)
    assert text != SMALL
    data, reference = bvh.loads(text), bvh.loads(SMALL)
    assert data.frames == 2 and data.frame_time == reference.frame_time
    assert np.array_equal(data.motion, reference.motion)


def test_a_bad_row_after_blank_lines_is_reported_on_its_own_line():
    text = SMALL.replace("MOTION\n", "MOTION\n\n\n").replace("0 91 0", "0 9x1 0")
    with pytest.raises(FormatError) as err:
        bvh.loads(text, path="clip.bvh")
    assert err.value.line == 31 and "not a number" in err.value.message


def test_zero_frames_read_as_a_hierarchy_and_refused_as_a_clip(tmp_path):
    text = SMALL[: SMALL.index("Frames")] + "Frames: 0\nFrame Time: .0333333\n"
    data = bvh.loads(text)  # a valid file: the hierarchy without motion
    assert data.frames == 0 and data.motion.shape == (0, 15)
    skeleton, empty = bvh.to_animation(data, unit="cm", up="y")  # a valid empty clip
    assert empty.rotations.shape == (0, 3, 4) and len(skeleton.names) == 3
    path = tmp_path / "empty.bvh"
    path.write_text(text)
    with pytest.raises(FormatError) as err:  # but nothing to load as a clip
        bvh.load(path)
    assert err.value.line == 26 and "Frames: 0" in str(err.value)
    assert str(err.value).startswith(f"{path}:26: ")

"""OBJ, .mhm and .target: round trips, typed errors with file and line, fuzzing."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from avatar.errors import FormatError
from avatar.io import mhm, obj
from avatar.io.target import loads as parse_target
from avatar.mesh import Mesh

QUAD = Mesh(
    vertices=np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1]], np.float32),
    faces=np.array([[0, 1, 2, 3], [0, 1, 4, 4]], np.int32),
    uvs=np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32),
    face_uvs=np.array([[0, 1, 2, 3], [0, 1, 2, 2]], np.int32),
)


def test_obj_round_trip(tmp_path):
    obj.write(tmp_path / "q.obj", QUAD)
    back = obj.read(tmp_path / "q.obj")
    np.testing.assert_allclose(back.vertices, QUAD.vertices, atol=1e-6)
    np.testing.assert_array_equal(back.faces, QUAD.faces)
    np.testing.assert_allclose(back.uvs, QUAD.uvs)


def test_obj_makehuman_axes_round_trip():
    text = obj.dumps(QUAD, axes=obj.MAKEHUMAN)
    back = obj.loads(text, axes=obj.MAKEHUMAN)
    np.testing.assert_allclose(back.vertices, QUAD.vertices, atol=1e-6)


@pytest.mark.parametrize(
    "text,line",
    [("v 0 0 0\nv 1 0\n", 2), ("v 0 0 0\nf 1 2 3\n", 2), ("v 0 0 0\nv a b c\n", 2), ("", 0)],
)
def test_obj_errors_name_the_line(text, line):
    with pytest.raises(FormatError) as info:
        obj.loads(text, "bad.obj")
    assert info.value.line == line and "bad.obj" in str(info.value)


def test_mhm_round_trip_is_lossless(model):
    from avatar.human import Human

    h = Human({"gender": 0.3, "age": 0.712345678, "pca/belly": 1.2, "nose-scale-horiz": -0.4,
               "expression/jawOpen": 0.5}, rig="game_engine", model=model)  # fmt: skip
    text = mhm.dumps(h.to_mhm("me"))
    back = mhm.loads(text)
    assert mhm.dumps(back) == text
    again = Human({**back.modifiers, **back.avatar_params}, back.rig or "default", model)
    assert again.params == h.model.defaults() | h.params
    np.testing.assert_array_equal(again.vertices, h.vertices)


def test_mhm_keeps_unknown_lines():
    text = "version v1.1.1\nname x\nmodifier macrodetails/Gender 1.000000\neyes HighPolyEyes abc\n"
    assert "eyes HighPolyEyes abc" in mhm.dumps(mhm.loads(text))


@pytest.mark.parametrize("line", ["modifier a/b", "modifier a/b x", "modifier a/b nan"])
def test_mhm_bad_modifier_raises(line):
    with pytest.raises(FormatError) as info:
        mhm.loads(f"version v1.1.1\n{line}\n", "c.mhm")
    assert info.value.line == 2


def test_unknown_mhm_modifier_lists_close_matches(model, tmp_path):
    from avatar.errors import ParameterError
    from avatar.human import Human

    (tmp_path / "c.mhm").write_text("modifier macrodetails/Gendr 1.0\n")
    with pytest.raises(ParameterError, match="Gender"):
        Human.from_mhm(str(tmp_path / "c.mhm"), model)


def test_target_parser_converts_axes_and_units():
    index, delta = parse_target("# c\n3 1.0 2.0 3.0\n7 0 0 -0.5\n", "t.target")
    np.testing.assert_array_equal(index, [3, 7])
    np.testing.assert_allclose(delta, [[0.1, -0.3, 0.2], [0, 0.05, 0]], atol=1e-7)


@pytest.mark.parametrize("text,line", [("1 0 0\n", 1), ("1 0 0 0\n2 0 x 0\n", 2),
                                       ("1 0 0 0\n-4 0 0 0\n", 2), ("1 0 nan 0\n", 1)])  # fmt: skip
def test_target_errors_name_the_line(text, line):
    with pytest.raises(FormatError) as info:
        parse_target(text, "t.target")
    assert info.value.line == line


@settings(max_examples=200, deadline=None)
@given(st.text(alphabet="vtfgo0123456789 .-/#\nabcxe", max_size=300))
def test_obj_fuzz_only_raises_format_error(text):
    try:
        obj.loads(text)
    except FormatError:
        pass


@settings(max_examples=200, deadline=None)
@given(st.text(alphabet="modifiernaskltc/|0123456789 .-#\nx", max_size=300))
def test_mhm_fuzz_only_raises_format_error(text):
    try:
        mhm.loads(text)
    except FormatError:
        pass


@settings(max_examples=200, deadline=None)
@given(st.text(alphabet="0123456789 .-e#\nnax", max_size=200))
def test_target_fuzz_only_raises_format_error(text):
    try:
        parse_target(text, "f.target")
    except FormatError:
        pass


def test_rig_json_errors_are_format_errors(tmp_path):
    from avatar.body.assets import _read_json

    (tmp_path / "rig.x.json").write_text('{"a": \n  [1, 2,, ]}')
    with pytest.raises(FormatError) as info:
        _read_json(tmp_path / "rig.x.json")
    assert info.value.line == 2

""".mhclo / .mhmat / .mhw: MakeHuman's syntax, exact round trips, clear errors, fuzzing."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from avatar.errors import FormatError
from avatar.io import mhclo, mhmat, mhw

SMALL = """# a comment kept as licence text: CC0
uuid 1234
basemesh hm08
tag Casual
name tiny
obj_file tiny.obj
x_scale 5399 11998 1.4340
z_scale 962 5320 2.0001
y_scale 791 881 2.4098
z_depth 50
verts 0
17090 17384 17383 0.16911 0.65529 0.17560 0.02236 0.02127 -0.06878
4
material tiny.mhmat
10 11 12 0.5 0.5 0.0
vertexboneweights_file tiny.mhw

delete_verts
1 2 - 5 9
100 - 102
"""


def test_reads_every_reference_kind_and_keyword_after_verts():
    p = mhclo.loads(SMALL)
    b = p.binding
    assert len(b) == 3 and b.single.tolist() == [False, True, False]
    assert b.indices[1].tolist() == [4, 4, 4] and b.weights[1].tolist() == [1, 0, 0]
    # MakeHuman (dx, dy, dz) dm -> Avatar (dx, -dz, dy) m.
    assert np.allclose(b.offsets[0], [0.002236, 0.006878, 0.002127])
    assert np.allclose(b.offsets[2], 0)
    assert p.material == "tiny.mhmat" and p.vertexboneweights_file == "tiny.mhw"
    assert p.delete_verts.tolist() == [1, 2, 3, 4, 5, 9, 100, 101, 102]
    assert p.tags == ("casual",) and p.z_depth == 50
    # x -> Avatar x, MakeHuman z (forward) -> Avatar y, MakeHuman y (up) -> Avatar z.
    assert p.binding.scale_refs.tolist() == [[5399, 11998], [962, 5320], [791, 881]]
    assert np.allclose(p.binding.scale_lengths, [0.1434, 0.20001, 0.24098])


def test_write_read_is_exact():
    p = mhclo.loads(SMALL)
    again = mhclo.loads(mhclo.dumps(p))
    assert again == p
    assert mhclo.dumps(again) == mhclo.dumps(p)


def test_fixture_files_round_trip_exactly(fixtures):
    for path in sorted((fixtures / "makehuman").rglob("*.mhclo")):
        p = mhclo.read(path)
        assert mhclo.loads(mhclo.dumps(p)) == p, path.name


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("1 2 3 0.5 0.5", "1, 6 or 9 numbers"),
        ("1 2 99999 0.3 0.3 0.4 0 0 0", "out of range"),
        ("1 2 x 0.3 0.3 0.4 0 0 0", "integer"),
        ("1 2 3 0.3 nan 0.4 0 0 0", "non-finite"),
    ],
)
def test_bad_reference_line_names_file_and_line(line, message):
    text = SMALL.replace("\n4\n", f"\n{line}\n")
    with pytest.raises(FormatError, match=message) as info:
        mhclo.loads(text, "broken.mhclo")
    assert info.value.path == "broken.mhclo" and info.value.line == 13


def test_other_errors():
    with pytest.raises(FormatError, match="no vertex references"):
        mhclo.loads("name empty\n", "e.mhclo")
    with pytest.raises(FormatError, match="before any"):
        mhclo.loads("1 2 3\n", "e.mhclo")
    with pytest.raises(FormatError, match="range"):
        mhclo.loads("verts 0\n4\ndelete_verts\n5 - 2\n", "e.mhclo")
    with pytest.raises(FormatError, match="cannot read"):
        mhclo.read("/nonexistent/x.mhclo")


refs = st.lists(
    st.one_of(
        st.tuples(st.integers(0, 19157)),
        st.tuples(
            *[st.integers(0, 19157)] * 3,
            *[st.floats(-2, 2, allow_nan=False, width=32)] * 6,
        ),
    ),
    min_size=1,
    max_size=20,
)


@settings(max_examples=60, deadline=None)
@given(refs, st.lists(st.integers(0, 19157), max_size=30), st.integers(0, 100))
def test_fuzz_round_trip(rows, deleted, depth):
    lines = ["name fuzz", f"z_depth {depth}", "x_scale 1 2 0.5", "verts 0"]
    lines += [" ".join(str(x) for x in row) for row in rows]
    if deleted:
        lines += ["delete_verts", " ".join(map(str, deleted))]
    p = mhclo.loads("\n".join(lines))
    assert len(p.binding) == len(rows)
    assert p.delete_verts.tolist() == sorted(set(deleted))
    assert mhclo.loads(mhclo.dumps(p)) == p


@settings(max_examples=100, deadline=None)
@given(st.text(alphabet=st.sampled_from(list("verts0123456789 .-\nxyz_scaledelt#")), max_size=200))
def test_fuzz_garbage_raises_format_error_or_parses(text):
    try:
        mhclo.loads(text, "fuzz.mhclo")
    except FormatError as exc:
        assert exc.path == "fuzz.mhclo"


def test_mhmat_round_trip_and_accessors(tmp_path):
    text = "# c\nname m\ndiffuseColor 1 0.5 0\nshaderConfig normal True\nshaderConfig ao False\n"
    text += "diffuseTexture m.png\nroughness 0.4\ntransparent True\n"
    m = mhmat.loads(text)
    assert mhmat.loads(mhmat.dumps(m)) == m
    assert m.color() == (1.0, 0.5, 0.0) and m.number("roughness") == 0.4 and m.flag("transparent")
    with pytest.raises(FormatError, match="diffuseTexture"):
        mhmat.texture_paths(m, tmp_path, "m.mhmat")
    (tmp_path / "m.png").write_bytes(b"x")
    assert mhmat.texture_paths(m, tmp_path)["diffuseTexture"] == tmp_path / "m.png"
    with pytest.raises(FormatError, match="diffuseColor"):
        mhmat.loads("diffuseColor red\n", "bad.mhmat")


def test_mhw_round_trip_and_normalise():
    text = '{"name": "w", "weights": {"a": [[0, 2.0], [1, 1.0]], "b": [[0, 2.0]]}}'
    w = mhw.loads(text)
    assert mhw.loads(mhw.dumps(w)).weight.tolist() == w.weight.tolist()
    dense = w.dense(3)
    assert dense[0].tolist() == [0.5, 0.5] and dense[1].tolist() == [1, 0] and dense[2].sum() == 0
    with pytest.raises(FormatError):
        mhw.loads("{not json", "bad.mhw")

"""The body model reproduces MakeHuman 1.1 and behaves at the extremes."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from avatar.body import macros
from avatar.errors import ParameterError
from avatar.mesh import face_normals, vertex_normals
from avatar.rig.placement import RigDefinition

STANDARD_RIGS = ["default", "default_no_toes", "game_engine", "game_engine_with_breast", "cmu_mb"]


@pytest.mark.parametrize("rig", STANDARD_RIGS)
def test_default_human_reproduces_stored_joints_within_2mm(model, rig):
    definition = RigDefinition.from_json(rig, model.assets.rig(rig), model.base.groups)
    heads, tails = definition.joint_positions(model.shape())
    error = np.linalg.norm(np.concatenate([heads, tails]) - definition.defaults, axis=1)
    assert error.max() < 0.002, definition.names[int(np.argmax(error)) % len(definition.names)]


def test_macro_level_weights_follow_makehuman():
    lv = macros.level_weights({"age": 0.25, "muscle": 0.75, "gender": 0.2})
    assert lv["female"] == pytest.approx(0.8) and lv["male"] == pytest.approx(0.2)
    assert lv["young"] == pytest.approx((0.25 - 0.1875) * 3.2)
    assert lv["child"] == pytest.approx(1 - lv["young"])
    assert lv["maxmuscle"] == pytest.approx(0.5) and lv["averagemuscle"] == pytest.approx(0.5)
    assert sum(lv[k] for k in macros.RACES) == pytest.approx(1.0)


def test_macro_weights_are_a_partition_per_family(model):
    """Universal targets' weights sum to 1 for any macros (levels are partitions of unity)."""
    rng = np.random.default_rng(0)
    table = model.macro_table
    universal = [k for k, c in enumerate(table.columns) if "universal" in model.target_names[c]]
    for _ in range(20):
        values = {k: rng.uniform() for k in ("gender", "age", "muscle", "weight")}
        assert table.weights(values)[universal].sum() == pytest.approx(1.0)


def test_modifier_names_match_makehuman(model, fixtures):
    mine = {m.name for m in model.modifiers}
    for file in ("modeling_modifiers.json", "measurement_modifiers.json"):
        for group in json.loads((fixtures / "makehuman/modifiers" / file).read_text()):
            for m in group["modifiers"]:
                if "target" in m:
                    side = f"-{m['min']}|{m['max']}" if "min" in m else ""
                    assert f"{group['group']}/{m['target']}{side}" in mine


def test_shape_is_pure_and_default_macros_apply(model):
    a = model.shape({"gender": 0.5})
    b = model.shape()
    np.testing.assert_array_equal(a, b)
    assert a.dtype == np.float32 and a.shape == (19158, 3)


def test_local_modifier_moves_only_its_region(model):
    base = model.shape()
    moved = model.shape({"nose/nose-scale-horiz-decr|incr": 1.0})
    changed = np.linalg.norm(moved - base, axis=1) > 1e-6
    assert 0 < changed.sum() < 2000


def test_short_and_makehuman_names_are_aliases(model):
    a = model.shape({"torso-scale-depth": 0.4, "macrodetails/Gender": 1.0})
    b = model.shape({"torso/torso-scale-depth-decr|incr": 0.4, "gender": 1.0})
    np.testing.assert_array_equal(a, b)


def test_unknown_parameter_lists_close_matches(model):
    with pytest.raises(ParameterError, match="did you mean.*gender"):
        model.shape({"gendr": 1.0})


@pytest.mark.parametrize("value", [float("nan"), float("inf"), "abc"])
def test_bad_values_are_rejected(model, value):
    with pytest.raises(ParameterError):
        model.shape({"age": value})


def test_out_of_range_values_are_clamped(model):
    np.testing.assert_array_equal(model.shape({"age": 7.0}), model.shape({"age": 1.0}))
    np.testing.assert_array_equal(
        model.shape({"nose-scale-horiz": -9}), model.shape({"nose-scale-horiz": -1})
    )


def _folded(model, verts):
    """Faces whose normal opposes the mean normal of their corners (folded over)."""
    body = model.base.faces[model.base.face_groups["body"]]
    v = verts.astype(np.float64)
    corner_mean = vertex_normals(v, body)[body].mean(axis=1)
    return int(np.sum(np.sum(face_normals(v, body) * corner_mean, axis=1) < 0))


def test_extreme_macros_give_finite_meshes_and_few_folds(model):
    """Every corner of the macro cube is finite. MakeHuman 1.1's own targets fold up to ~1%
    of the faces at some corners (old + min weight + min height); Avatar reproduces the data
    exactly, so it allows that and no more."""
    names = ["gender", "age", "muscle", "weight", "height", "proportions"]
    assert _folded(model, model.base.vertices) == 0
    faces = len(model.base.face_groups["body"])
    for corner in itertools.product([0.0, 1.0], repeat=len(names)):
        params = dict(zip(names, corner, strict=True)) | {"cupsize": 1.0, "african": 1.0}
        verts = model.shape(params)
        assert np.isfinite(verts).all()
        assert _folded(model, verts) <= 0.012 * faces, params
    extreme = model.shape({"pca/" + a: 3.0 for a in ("belly", "breast")})
    assert _folded(model, extreme) <= 0.012 * faces


def test_attribute_sliders_are_unit_standard_deviations(model):
    from avatar.body.attributes import ATTRIBUTES, basis

    comps = basis(model)
    for attr in ATTRIBUTES:
        d = model.shape({f"pca/{attr.name}": 1.0}) - model.shape()
        np.testing.assert_allclose(d, comps[attr.name], atol=1e-5)
        assert np.isfinite(d).all() and np.abs(d).max() > 0.005, attr.name


def test_belly_attribute_grows_the_belly(model):
    from avatar.body import measures

    assert (
        measures.measure(model.shape({"pca/belly": 2.0}))["waist"]
        > measures.measure(model.shape())["waist"] + 0.05
    )


def test_attributes_agree_with_the_2020_addon_basis(model, fixtures):
    from avatar.body.attributes import Avatar2020Basis, basis

    theirs = Avatar2020Basis.load(fixtures / "avatar2020/shape")
    mine = basis(model)
    for name in ("breast", "shoulders_fat", "hips_fat"):
        a, b = mine[name][:13380].ravel(), theirs.directions[name].ravel()
        assert a @ b / np.linalg.norm(a) / np.linalg.norm(b) > 0.9, name
    body = theirs.body({"breast": 1.0})
    assert body.shape == (13380, 3) and np.isfinite(body).all()


def test_memoised_macro_sums_match_full_sums(model):
    """Dragging one macro group (contraction), local edits (memo) and jumps give full sums."""
    from avatar.body.model import GROUP_LEVELS, MACRO_GROUP

    levels = set(model.macro_table.level_names) - {"universal"}
    assert levels <= {lv for group in GROUP_LEVELS.values() for lv in group}  # no middle files
    rng = np.random.default_rng(7)
    values = {k: rng.uniform() for k in macros.MACROS}
    for group in [*GROUP_LEVELS, "age", "gender", "age"]:  # also alternate and come back
        for step, v in enumerate([0.0, rng.uniform(), 1.0, rng.uniform()]):
            values |= {m: v for m in macros.MACROS if MACRO_GROUP[m] == group}
            got = model.macro_sum(values)
            np.testing.assert_allclose(got, model.macro_sum.full(values), atol=1e-6)
            got[:] = 0.0  # results are fresh arrays: mutating one must not leak into the next
            if step == 1:  # a local edit reuses the memo and gives the same body twice
                edit = values | {"torso/torso-scale-depth-decr|incr": 0.5}
                np.testing.assert_array_equal(model.shape(edit), model.shape(edit))
        assert model.macro_sum._contraction.group == group  # the drag used a contraction


def test_humans_share_one_model_per_thread():
    """Making many humans does not load the model each time; another thread gets its own
    (a model memoises its last shape)."""
    import threading

    from avatar.body.model import BodyModel
    from avatar.human import Human

    a, b = Human({"weight": 0.2}), Human({"weight": 0.8})
    assert a.model is b.model is BodyModel.shared()
    assert not np.allclose(a.vertices, b.vertices)
    # Bit for bit what a fresh model gives, whatever came before (a slider "dragged").
    for weight in (0.3, 0.31, 0.32, 0.2):
        again = Human({"weight": weight, "gender": 0.4}).vertices
        fresh = Human({"weight": weight, "gender": 0.4}, model=BodyModel.load()).vertices
        assert np.array_equal(again, fresh)
    other = []
    thread = threading.Thread(target=lambda: other.append(BodyModel.shared()))
    thread.start()
    thread.join()
    assert other[0] is not a.model

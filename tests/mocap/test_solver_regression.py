"""The solver reproduces its pinned results (``solver_regression.py`` says what and how).

A faster solver must solve every stored stream to the same pose: each solved bone within
1e-6 rad, the hips' translation and the solved keypoints within 1e-6 m (the file holds
float32: ~1e-7), the same bones solved or held and the same feet planted on every frame.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from tests.mocap import solver_regression as regression


@pytest.fixture(scope="module")
def data():
    return dict(np.load(regression.DATA))


def _angles(q0: np.ndarray, q1: np.ndarray) -> np.ndarray:
    """(...,) radians between unit quaternions (either sign), accurate near zero (an arccos
    of the dot product would be blind below ~1e-7)."""
    d = np.minimum(np.linalg.norm(q1 - q0, axis=-1), np.linalg.norm(q1 + q0, axis=-1))
    return 4.0 * np.arcsin(np.minimum(d / 2.0, 1.0))


@pytest.mark.parametrize("case", list(regression.CASES))
def test_solver_reproduces_pinned_results(data, case):
    assert json.loads(str(data[f"{case}__settings"])) == regression.CASES[case][3]
    got = regression.run(data, case)
    np.testing.assert_array_equal(got["bones"], data[f"{case}__bones"])
    angles = _angles(data[f"{case}__rotations"].astype(np.float64), got["rotations"])
    worst = np.unravel_index(int(np.argmax(angles)), angles.shape)
    assert angles.max() < 1e-6, f"frame {worst[0]}, solved bone {worst[1]}: {angles.max():.2e}"
    assert (got["rest"] == [1.0, 0.0, 0.0, 0.0]).all(), "a bone the solver does not turn moved"
    hips = got["bones"][0]
    np.testing.assert_allclose(got["translations"][:, hips], data[f"{case}__translations"],
                               rtol=0, atol=1e-6)  # fmt: skip
    others = np.delete(got["translations"], hips, axis=1)
    assert (others == 0).all()
    np.testing.assert_allclose(got["points"], data[f"{case}__points_out"], rtol=0, atol=1e-6)
    np.testing.assert_array_equal(got["solved"], data[f"{case}__solved"])
    np.testing.assert_array_equal(got["contacts"], data[f"{case}__contacts"])
    times = data[f"{case}__times"]
    expected = np.where(np.isnan(times), np.arange(len(times)) / 30.0, times)
    np.testing.assert_allclose(got["time"], expected, rtol=0, atol=1e-9)


def test_cases_exercise_what_they_claim(data):
    """The pinned streams reach the branches a speed-up could break: held bones, the whole
    body lost, planted feet, limits biting, every keypoint set, three kinds of rig."""
    info = regression.describe()
    assert {regression.CASES[c][1] for c in info} == {"coco17", "mediapipe33", "h36m17",
                                                      "openpose25"}  # fmt: skip
    assert {regression.CASES[c][0] for c in info} == {"default", "game_engine", "mixamo"}
    assert info["jumps_mediapipe33_dropout"]["held"] > 100
    assert (~data["jumps_mediapipe33_dropout__solved"][10:14]).all()  # nothing seen: all held
    assert info["walk_coco17_default"]["contacts"] > 0
    assert info["jumps_mediapipe33_dropout"]["contacts"] > 0
    # Limits bite: bones end exactly at their limit, single bones and a chain's.
    from avatar.mocap import keypoints, plan

    clamped = set()
    for case, (rig_name, set_name, _, _) in regression.CASES.items():
        rig = keypoints.bind(set_name, regression.skeleton_of(data, rig_name))
        steps = plan.make_plan(rig).steps
        limit = np.array([st.limit for st in steps])
        q = data[f"{case}__rotations"].astype(np.float64)
        at = np.abs(2 * np.arccos(np.minimum(1.0, np.abs(q[..., 0]))) - limit) < 1e-5
        clamped |= {steps[i].role for i in np.nonzero(at)[1]}
    assert {"neck_chain", "shin.L", "forearm.R", "clavicle"} <= clamped, clamped

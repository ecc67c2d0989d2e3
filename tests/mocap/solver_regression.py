"""Pinned solver results: the cases of ``test_solver_regression.py`` and their generator.

``data/solver_regression.npz`` holds, for a handful of cases, everything a solve needs that
lives outside the solver (the rig's skeleton, the keypoint stream: points, confidences and
times, the settings) and what the solver returned for it when the file was written (each
solved bone's rotation, the hips' translation, the solved keypoints, the solved and contact
flags). The test re-solves the stored streams and compares, so it needs neither the body
model nor the fixture clips, and a speed-up of the solver cannot quietly change its output.

The cases reach the solver's branches: noise, the One Euro filter, auto scale and floor,
planted feet, held bones decaying (and ``hold=0``), a whole body missing (the root held), a
missing hip (no hip line), joint limits biting on single bones and on the spine chain, limits
off, irregular and missing timestamps, every shipped keypoint set, three kinds of rig.

Regenerate (only when a change of results is intended, and say why in the commit)::

    .venv/bin/python -m tests.mocap.solver_regression
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

DATA = Path(__file__).parent / "data" / "solver_regression.npz"
FIXTURES = Path(__file__).resolve().parents[3] / "shared" / "fixtures" / "bvh"
FRAMES = 32

# name: (rig, keypoint set, clip under the fixtures' bvh folder (None: synthetic), settings)
CASES: dict[str, tuple[str, str, str | None, dict]] = {
    "walk_coco17_default": ("default", "coco17", "cmu_motionbuilder/02_01_walk.bvh", {}),
    "jumps_mediapipe33_dropout": ("default", "mediapipe33",
                                  "cmu_motionbuilder/01_01_forward_jumps.bvh",
                                  {"floor": "auto", "hold": 0.3}),
    "dance_h36m17_game_engine": ("game_engine", "h36m17", "cmu_reallusion_cc/005_03_dance.bvh",
                                 {"smoothing": None, "plant_feet": False, "scale": 1.0,
                                  "floor": 0.02}),
    "run_openpose25_mixamo_noisy": ("mixamo", "openpose25", "cmu_reallusion_cc/002_03_run_jog.bvh",
                                    {"hold": 0.0}),
    "climb_coco17_free": ("default", "coco17", "cmu_motionbuilder/01_14_climb_jumpdown.bvh",
                          {"limits": False, "smoothing": 0.8}),
    "bend_mediapipe33_limits": ("default", "mediapipe33", None,
                                {"smoothing": None, "scale": 1.0}),
}  # fmt: skip


def settings_of(spec: dict):
    """``SolverSettings`` from a case's JSON-able settings (smoothing: None = off, a number =
    ``OneEuro.strength``)."""
    from avatar.mocap import filters, solver

    spec = dict(spec)
    if "smoothing" in spec:
        s = spec.pop("smoothing")
        spec["smoothing"] = filters.OneEuro.off() if s is None else filters.OneEuro.strength(s)
    return solver.SolverSettings(**spec)


def skeleton_of(data, rig: str):
    """The stored skeleton of ``rig`` (float32 on disk; float64 here, the rest rotations made
    orthonormal again, as every real rig's are, to 1e-16)."""
    from avatar.rig.skeleton import Skeleton

    rest = np.zeros((len(data[f"{rig}__parents"]), 4, 4))
    rest[:, :3, :] = data[f"{rig}__rest"]
    u, _, vt = np.linalg.svd(rest[:, :3, :3])
    rest[:, :3, :3] = u @ vt
    rest[:, 3, 3] = 1.0
    return Skeleton(tuple(str(n) for n in data[f"{rig}__names"]),
                    data[f"{rig}__parents"].astype(np.int32), rest,
                    data[f"{rig}__tails"].astype(np.float64))  # fmt: skip


def stream_of(data, case: str):
    """(points (T, K, 3), confidence (T, K) or None, times (T,) with NaN = None)."""
    conf = data[f"{case}__confidence"].astype(np.float64)
    return (data[f"{case}__points"].astype(np.float64), None if conf.size == 0 else conf,
            data[f"{case}__times"].astype(np.float64))  # fmt: skip


def run(data, case: str) -> dict[str, np.ndarray]:
    """Solve a stored case's stream with the solver as it is now."""
    from avatar.mocap import keypoints, solver

    rig_name, set_name, _, spec = CASES[case]
    rig = keypoints.bind(set_name, skeleton_of(data, rig_name))
    s = solver.PoseSolver(rig, settings_of(spec))
    points, conf, times = stream_of(data, case)
    bones = np.array([st.bone for st in s.plan.steps])
    out: dict[str, list] = {k: [] for k in ("rotations", "rest", "translations", "points",
                                            "solved", "contacts", "time")}  # fmt: skip
    for i in range(len(points)):
        t = None if np.isnan(times[i]) else float(times[i])
        frame = s(points[i], None if conf is None else conf[i], t)
        unsolved = np.ones(len(frame.rotations), bool)
        unsolved[bones] = False
        out["rotations"].append(frame.rotations[bones])
        out["rest"].append(frame.rotations[unsolved])
        out["translations"].append(frame.translations)
        out["points"].append(frame.points)
        out["solved"].append(frame.solved)
        out["contacts"].append(frame.contacts)
        out["time"].append(frame.time)
    result = {k: np.array(v) for k, v in out.items()}
    result["bones"] = bones
    return result


# -- generation (needs the body model and the fixture clips) ---------------------------------


def _stream(case: str, skeleton, rng) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
    from avatar.mocap import keypoints
    from avatar.motion import load_bvh, retarget
    from avatar.motion.timing import resample, select

    rig_name, set_name, clip_path, _ = CASES[case]
    rig = keypoints.bind(set_name, skeleton)
    if clip_path is None:
        points = _bent(rig, rng)
    else:
        source, clip = load_bvh(FIXTURES / clip_path)
        clip = select(resample(clip, 30.0), slice(0, FRAMES))
        clip, _ = retarget(source, clip, skeleton, measure=False)
        points = rig.positions(clip)
    t = len(points)
    times = np.arange(t) / 30.0
    conf = None
    if case == "walk_coco17_default":
        points = points + rng.normal(0, 0.005, points.shape)
    elif case == "jumps_mediapipe33_dropout":
        points = points + rng.normal(0, 0.015, points.shape)
        conf = rng.uniform(0.3, 1.0, points.shape[:2])  # ~28 % below the 0.5 threshold
        conf[10:14] = 0.0  # the whole body lost for four frames: the root is held
        points[20:22, ::5] = np.nan  # and some points NaN
        times = times + rng.uniform(-0.008, 0.008, t)  # an estimator's jittery clock
    elif case == "run_openpose25_mixamo_noisy":
        points = points + rng.normal(0, 0.04, points.shape)  # limits bite
        conf = (rng.random(points.shape[:2]) >= 0.1).astype(float)
    elif case == "climb_coco17_free":
        points[5:25, rig.keypoints.index("left_hip")] = np.nan  # no hip line
        points[15:30, rig.keypoints.index("left_shoulder")] = np.nan
        times[:] = np.nan  # no clock: 30 frames/s after the last
    return points, conf, times


def _bent(rig, rng) -> np.ndarray:
    """(FRAMES, K, 3) the rest keypoints with the upper body bending forward past the spine's
    limit and the knees folding through themselves; two degenerate frames (every point in
    one place, all on a line)."""
    kp = rig.keypoints
    rest = rig.rest
    hips = (rest[kp.index("left_hip")] + rest[kp.index("right_hip")]) / 2
    upper = [i for i, n in enumerate(kp.names) if "hip" not in n and "knee" not in n
             and "ankle" not in n and "heel" not in n and "foot" not in n]  # fmt: skip
    frames = []
    for i in range(FRAMES):
        p = rest.copy()
        a = np.radians(100.0) * i / (FRAMES - 1)  # bend forward (about +X: the head to -Y)
        turn = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
        p[upper] = (p[upper] - hips) @ turn.T + hips
        for side in ("left", "right"):
            knee, ankle = kp.index(f"{side}_knee"), kp.index(f"{side}_ankle")
            b = np.radians(200.0) * i / (FRAMES - 1)  # the shin folding forward and up
            shin = p[ankle] - p[knee]
            fold = np.array([[1, 0, 0], [0, np.cos(b), np.sin(b)], [0, -np.sin(b), np.cos(b)]])
            p[ankle] = p[knee] + fold @ shin
        frames.append(p + rng.normal(0, 0.002, p.shape))
    frames[3][:] = hips  # degenerate: every point in one place (no fit: the root is held)
    frames[4][:] = hips + np.linspace(0.0, 1.0, len(rest))[:, None] * [0.0, 0.0, 1.0]  # a line
    return np.array(frames)


def generate(path: Path = DATA) -> None:
    """Build every case from the body model and the fixtures, solve it, write ``path``."""
    import avatar

    rng = np.random.default_rng(16)
    arrays: dict[str, np.ndarray] = {}
    for rig_name in sorted({c[0] for c in CASES.values()}):
        sk = avatar.Human(rig=rig_name).skeleton
        arrays[f"{rig_name}__names"] = np.array(sk.names)
        arrays[f"{rig_name}__parents"] = np.asarray(sk.parents, np.int16)
        arrays[f"{rig_name}__rest"] = sk.rest[:, :3, :].astype(np.float32)
        arrays[f"{rig_name}__tails"] = sk.tails.astype(np.float32)
    for case, (rig_name, _, _, spec) in CASES.items():
        skeleton = skeleton_of(arrays, rig_name)  # exactly what the test will bind
        points, conf, times = _stream(case, skeleton, rng)
        arrays[f"{case}__points"] = points.astype(np.float32)
        arrays[f"{case}__confidence"] = (np.zeros(0, np.float32) if conf is None
                                         else conf.astype(np.float32))  # fmt: skip
        arrays[f"{case}__times"] = times.astype(np.float64)
        arrays[f"{case}__settings"] = np.array(json.dumps(spec))
        got = run(arrays, case)
        arrays[f"{case}__bones"] = got["bones"].astype(np.int16)
        arrays[f"{case}__rotations"] = got["rotations"].astype(np.float32)  # 1e-7 rad
        arrays[f"{case}__translations"] = got["translations"][:, got["bones"][0]]
        arrays[f"{case}__points_out"] = got["points"].astype(np.float32)
        arrays[f"{case}__solved"] = got["solved"]
        arrays[f"{case}__contacts"] = got["contacts"]
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, **arrays)


def describe(path: Path = DATA) -> dict:
    """Per case: frames, held bone-frames, contacts, settings (what each case exercises)."""
    data = np.load(path)
    return {case: {"frames": len(data[f"{case}__points"]),
                   "held": int((~data[f"{case}__solved"]).sum()),
                   "contacts": int(data[f"{case}__contacts"].sum()),
                   "settings": str(data[f"{case}__settings"])} for case in CASES}  # fmt: skip


if __name__ == "__main__":
    generate()
    for case, info in describe().items():
        print(case, info)  # noqa: T201
    print(DATA, DATA.stat().st_size, "bytes")  # noqa: T201

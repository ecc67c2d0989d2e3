"""What the keypoint solver turns, in which order, from which keypoints: built once per
rig and keypoint set (``make_plan``), then used every frame.

Solved bones, in order: the hips (root), the spine chain (the bones from the hips up to the
chest role, sharing the bend), the clavicles, the neck chain (sharing the bend) and head,
then per side upper arm, forearm, hand, thigh, shin, foot. Every other bone keeps its rest
pose relative to its parent (twist bones, fingers, toes, face).

Each keypoint rides on its nearest solved bone: its carrier (``keypoints.RigKeypoints``) or
the first solved bone above it, the bones in between held at rest.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from importlib import resources

import numpy as np

from avatar.mocap.keypoints import RigKeypoints
from avatar.motion import geometry

LIMBS = ("upperarm", "forearm", "hand", "thigh", "shin", "foot")
# The far joint of a limb bone's bend (twist from the plane of the three joints) and the
# way the joint bends in the body's rest axes: elbows forward (-Y), knees backward (+Y).
POLES = {"upperarm": ("forearm", "hand", (0.0, -1.0, 0.0)),
         "thigh": ("shin", "foot", (0.0, 1.0, 0.0))}  # fmt: skip


@dataclass
class Step:
    """One solved bone.

    bone: rig bone index; kind: "root", "chain", "bone"; role: canonical role or chain name.
    anchor: index (in the plan's order) of the nearest solved bone above, -1 for the root.
    rel: (3, 3) this bone's rest rotation in the anchor's rest frame.
    step: (3,) this bone's rest head in the anchor's bone frame.
    points: keypoint indices carried, offsets (n, 3) in this bone's frame from its head.
    origin: keypoint at this bone's head (-1: none): aims start from the observed joint.
    pole: (far keypoint, bend axis (3,) in this bone's frame) or None.
    limit: the most this bone may turn from rest, radians (inf: no limit).
    """

    bone: int
    kind: str
    role: str
    anchor: int = -1
    rel: np.ndarray = field(default_factory=lambda: np.eye(3))
    step: np.ndarray = field(default_factory=lambda: np.zeros(3))
    points: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    offsets: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    origin: int = -1
    pole: tuple[int, int, np.ndarray] | None = None
    limit: float = np.inf


@dataclass
class Batch:
    """Single bones solved together (their anchors solved before them): the ``Step`` fields
    of n bones stacked, keypoints padded to the most any of them carries (m).

    steps (n,); anchor (n,); rel (n, 3, 3); step (n, 3); points (n, m) keypoint indices
    (0 where padded), real (n, m) bool (False: padding); offsets (n, m, 3); origin (n,)
    (-1: none); pole: has_pole (n,), pole_mid, pole_far (n,) keypoints, pole_axis (n, 3);
    limit (n,) radians, limited (n,) bool (a limit below a half turn).
    """

    steps: np.ndarray
    anchor: np.ndarray
    rel: np.ndarray
    step: np.ndarray
    points: np.ndarray
    real: np.ndarray
    offsets: np.ndarray
    origin: np.ndarray
    has_pole: np.ndarray
    pole_mid: np.ndarray
    pole_far: np.ndarray
    pole_axis: np.ndarray
    limit: np.ndarray
    limited: np.ndarray


def make_batch(steps: list[Step], ids: list[int]) -> Batch:
    """Stack the steps ``ids`` (none anchored on another of them) into one ``Batch``."""
    chosen = [steps[i] for i in ids]
    m = max([len(st.points) for st in chosen] + [1])
    n = len(ids)
    points, real, offsets = np.zeros((n, m), int), np.zeros((n, m), bool), np.zeros((n, m, 3))
    pole_mid, pole_far, pole_axis = np.zeros(n, int), np.zeros(n, int), np.zeros((n, 3))
    for r, st in enumerate(chosen):
        count = len(st.points)
        points[r, :count], real[r, :count], offsets[r, :count] = st.points, True, st.offsets
        if st.pole is not None:
            pole_mid[r], pole_far[r], pole_axis[r] = st.pole[0], st.pole[1], st.pole[2]
    limit = np.array([st.limit for st in chosen], dtype=np.float64)
    return Batch(np.array(ids, int), np.array([st.anchor for st in chosen], int),
                 np.array([st.rel for st in chosen]), np.array([st.step for st in chosen]),
                 points, real, offsets, np.array([st.origin for st in chosen], int),
                 np.array([st.pole is not None for st in chosen]), pole_mid, pole_far,
                 pole_axis, limit, limit < np.pi)  # fmt: skip


@dataclass
class Chain:
    """Bones sharing one turn (spine, neck): indices into the plan's steps, first to last,
    and the keypoints they place (including those of the solved bones hanging on their last
    bone, taken at rest: the clavicles' shoulders, the head's face points) with offsets in
    the first bone's frame."""

    steps: list[int]
    points: np.ndarray
    offsets: np.ndarray  # (n, 3) at rest, in the first bone's frame
    tips: list[int]  # steps hanging on the chain whose points it uses
    # Precomputed for the per-frame solve: each point's owner (index into steps + tips),
    # its offset in the owner's frame; the steps' rest rotations relative to the first
    # bone's; the tips as a Batch (solved between the two spine passes).
    owner: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    owner_offsets: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    rest_rel: np.ndarray = field(default_factory=lambda: np.zeros((0, 3, 3)))
    tip_batch: Batch | None = None
    rel: np.ndarray = field(default_factory=lambda: np.zeros((0, 3, 3)))  # the steps' rel
    step: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))  # the steps' step
    limit: np.ndarray = field(default_factory=lambda: np.zeros(0))  # the steps' limit
    anchor: int = -1  # the first step's anchor
    tip_on: np.ndarray = field(default_factory=lambda: np.zeros(0, int))  # tips' anchors in steps


@dataclass
class Plan:
    rig: RigKeypoints
    steps: list[Step]
    chains: dict[str, Chain]
    order: list[tuple[str, object]]  # ("root", i) / ("chain", name) / ("bone", i)
    # The same work as ``order`` with runs of single bones grouped into dependency levels:
    # ("root", 0) / ("chain", name) / ("bones", Batch).
    schedule: list[tuple[str, object]]
    index: dict[int, int]  # rig bone -> step
    role_steps: dict[str, int]
    hip_points: tuple[int, int]  # keypoints at the left and right hip joints
    shoulder_points: tuple[int, int]
    ankle_points: tuple[int, int]
    leg_length: float  # rig: hip joint to ankle, metres (mean of both legs)


def _limits() -> dict[str, float]:
    text = (resources.files("avatar") / "data" / "mocap" / "limits.json").read_text("utf-8")
    return {k: np.radians(v) for k, v in json.loads(text)["degrees"].items()}


def make_plan(rig: RigKeypoints) -> Plan:
    sk, bmap = rig.skeleton, rig.bmap
    roles = bmap.bones
    limits = _limits()
    order_bones: list[tuple[int, str, str]] = [(roles["hips"], "root", "hips")]
    chest = roles.get("chest", roles.get("spine"))
    spine = geometry.path(sk, roles["hips"], chest)[1:] if chest is not None else []
    order_bones += [(j, "chain", "spine_chain") for j in spine]
    for side in "LR":
        if f"clavicle.{side}" in roles:
            order_bones.append((roles[f"clavicle.{side}"], "bone", "clavicle"))
    neck = []
    if "head" in roles and chest is not None:
        neck = geometry.path(sk, chest, roles["head"])[1:-1]
        order_bones += [(j, "chain", "neck_chain") for j in neck]
        order_bones.append((roles["head"], "bone", "head"))
    for side in "LR":
        for limb in LIMBS:
            if f"{limb}.{side}" in roles:
                order_bones.append((roles[f"{limb}.{side}"], "bone", f"{limb}.{side}"))
    index = {b: i for i, (b, _, _) in enumerate(order_bones)}
    rest = sk.rest[:, :3, :3]
    steps = []
    for b, kind, role in order_bones:
        anchor = _solved_above(sk, b, index)
        st = Step(b, kind, role, anchor, limit=limits.get(role.split(".")[0], np.inf))
        if anchor >= 0:
            a = order_bones[anchor][0]
            st.rel = rest[a].T @ rest[b]
            st.step = rest[a].T @ (sk.heads[b] - sk.heads[a])
        steps.append(st)
    _carry(rig, steps, index)
    _origins_and_poles(rig, steps, roles)
    chains = {}
    for name, members, tip in (("spine_chain", spine, "clavicle"), ("neck_chain", neck, "head")):
        if members:
            chains[name] = _chain(rig, steps, [index[j] for j in members], tip)
    order: list[tuple[str, object]] = [("root", 0)]
    if "spine_chain" in chains:
        order.append(("chain", "spine_chain"))
    done = {0} | set(chains["spine_chain"].steps if "spine_chain" in chains else [])
    for i, st in enumerate(steps):
        if i in done:
            continue
        if st.kind == "chain":
            if ("chain", "neck_chain") not in order:
                order.append(("chain", "neck_chain"))
            continue
        order.append(("bone", i))
    kp = rig.keypoints

    def point(role: str) -> int:
        for i, spec in enumerate(kp.specs):
            if rig.solve[i] and spec.get("at", [None])[0] == f"joint:{role}":
                return i
        return -1

    hip = (point("thigh.L"), point("thigh.R"))
    sho = (point("upperarm.L"), point("upperarm.R"))
    ank = (point("foot.L"), point("foot.R"))
    leg = [float(np.linalg.norm(sk.heads[roles[f"foot.{s}"]] - sk.heads[roles[f"thigh.{s}"]]))
           for s in "LR" if f"foot.{s}" in roles]  # fmt: skip
    return Plan(rig, steps, chains, order, _schedule(steps, order), index,
                {s.role: i for i, s in enumerate(steps)}, hip, sho, ank,
                float(np.mean(leg)) if leg else 0.9)  # fmt: skip


def _schedule(steps: list[Step], order: list[tuple[str, object]]) -> list[tuple[str, object]]:
    """``order`` with each run of single bones split into levels (a bone one level below
    its anchor when the anchor is in the same run), each level one Batch."""
    out: list[tuple[str, object]] = []
    run: list[int] = []

    def flush() -> None:
        level: dict[int, int] = {}
        for i in run:
            level[i] = level[steps[i].anchor] + 1 if steps[i].anchor in level else 0
        for depth in range(max(level.values(), default=-1) + 1):
            out.append(("bones", make_batch(steps, [i for i in run if level[i] == depth])))
        run.clear()

    for kind, item in order:
        if kind == "bone":
            run.append(int(item))  # type: ignore[call-overload]
            continue
        flush()
        out.append((kind, item))
    flush()
    return out


def _solved_above(sk, bone: int, index: dict[int, int]) -> int:
    j = int(sk.parents[bone])
    while j >= 0 and j not in index:
        j = int(sk.parents[j])
    return index.get(j, -1)


def _carry(rig: RigKeypoints, steps: list[Step], index: dict[int, int]) -> None:
    """Each solved keypoint onto its nearest solved bone (inclusive), offset in its frame."""
    sk = rig.skeleton
    rest = sk.rest[:, :3, :3]
    by_step: dict[int, list[int]] = {}
    for k in np.flatnonzero(rig.solve):
        c = int(rig.carriers[k])
        s = index.get(c, _solved_above(sk, c, index))
        if s >= 0:
            by_step.setdefault(s, []).append(int(k))
    for s, ks in by_step.items():
        b = steps[s].bone
        steps[s].points = np.array(ks)
        steps[s].offsets = (rig.rest[ks] - sk.heads[b]) @ rest[b]


def _origins_and_poles(rig: RigKeypoints, steps: list[Step], roles: dict[str, int]) -> None:
    sk = rig.skeleton
    at = {spec["at"][0][6:]: k for k, spec in enumerate(rig.keypoints.specs)
          if rig.solve[k] and spec.get("at", [""])[0].startswith("joint:")}  # fmt: skip
    for st in steps:
        st.origin = at.get(st.role, -1)
        limb, _, side = st.role.partition(".")
        if limb in POLES:
            mid, far, natural = POLES[limb]
            m, f = at.get(f"{mid}.{side}", -1), at.get(f"{far}.{side}", -1)
            if m >= 0 and f >= 0 and f"{mid}.{side}" in roles:
                upper = sk.heads[roles[f"{mid}.{side}"]] - sk.heads[st.bone]
                axis = np.cross(upper, np.asarray(natural))
                axis = axis / np.linalg.norm(axis)
                st.pole = (m, f, sk.rest[st.bone, :3, :3].T @ axis)


def _chain(rig: RigKeypoints, steps: list[Step], members: list[int], tip_role: str) -> Chain:
    """A chain's keypoints: those carried by its bones and by the solved bones hanging on
    them (not on another chain), offsets in the first bone's rest frame."""
    sk = rig.skeleton
    first = steps[members[0]].bone
    rest0 = sk.rest[first, :3, :3]
    tips = [i for i, st in enumerate(steps)
            if st.anchor in members and st.role == tip_role]  # fmt: skip
    owners = members + tips
    ks = [int(k) for i in owners for k in steps[i].points]
    offsets = (rig.rest[ks] - sk.heads[first]) @ rest0 if ks else np.zeros((0, 3))
    owner = np.array([r for r, i in enumerate(owners) for _ in steps[i].points], dtype=int)
    owner_offsets = (np.concatenate([steps[i].offsets for i in owners]) if ks
                     else np.zeros((0, 3)))  # fmt: skip
    rest_rel = np.array([rest0.T @ sk.rest[steps[i].bone, :3, :3] for i in members])
    return Chain(members, np.array(ks, dtype=int), offsets, tips, owner, owner_offsets,
                 rest_rel, make_batch(steps, tips) if tips else None,
                 np.array([steps[i].rel for i in members]),
                 np.array([steps[i].step for i in members]),
                 np.array([steps[i].limit for i in members]), steps[members[0]].anchor,
                 np.array([members.index(steps[i].anchor) for i in tips], dtype=int))

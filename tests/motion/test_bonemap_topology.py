"""Bone roles from topology: joints renamed to meaningless names map as they did by name,
and retarget the same way."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from avatar.errors import ParameterError
from avatar.io import bvh
from avatar.motion import bonemap, geometry
from avatar.motion.retarget import retarget
from avatar.rig import topology
from avatar.rig.kinematics import forward
from avatar.rig.skeleton import Animation, Skeleton

FIXTURES = Path(__file__).resolve().parents[2] / ".." / "shared" / "fixtures" / "bvh"
CLIPS = sorted(FIXTURES.glob("*/*.bvh")) if FIXTURES.is_dir() else []
needs_fixtures = pytest.mark.skipif(not CLIPS, reason="../shared/fixtures/bvh is absent")


def _renamed(skeleton: Skeleton, animation: Animation, keep=()) -> tuple[Skeleton, Animation]:
    names = tuple(n if n in keep else f"j{j}" for j, n in enumerate(skeleton.names))
    return replace(skeleton, names=names), replace(animation, bone_names=names)


def _core(bmap: bonemap.BoneMap) -> dict[str, int]:
    return {r: j for r, j in bmap.bones.items() if r in bonemap.CORE}


def _stick_figure(left_first: bool = True) -> Skeleton:
    """A 21-joint upright human facing -Y (left = +X) with meaningless names."""
    heads, parents = [[0, 0, 1.0]], [-1]

    def chain(parent, points):
        for p in points:
            heads.append(p)
            parents.append(parent)
            parent = len(heads) - 1
        return parent

    sides = (1, -1) if left_first else (-1, 1)
    for s in sides:  # legs: hip, knee, ankle, ball
        chain(0, [[0.1 * s, 0, 0.95], [0.1 * s, 0, 0.5], [0.1 * s, 0, 0.08], [0.1 * s, -0.12, 0]])
    chest = chain(0, [[0, 0, 1.15], [0, 0, 1.4]])
    chain(chest, [[0, 0, 1.5], [0, 0, 1.6]])  # neck, head
    for s in sides:  # clavicle, shoulder, elbow, wrist
        arm = [[0.05 * s, 0, 1.42], [0.2 * s, 0, 1.45], [0.2 * s, 0, 1.15], [0.2 * s, 0, 0.9]]
        chain(chest, arm)
    heads = np.asarray(heads, dtype=float)
    tails = heads + [0, 0, 0.08]
    rest = np.tile(np.eye(4), (len(heads), 1, 1))
    rest[:, :3, 3] = heads
    names = tuple(f"bone{j}" for j in range(len(heads)))
    return Skeleton(names, np.asarray(parents, dtype=np.int32), rest, tails)


@pytest.mark.parametrize("left_first", [True, False])
def test_stick_figure_roles_and_sides(left_first):
    skeleton = _stick_figure(left_first)
    roles = topology.infer(skeleton)
    assert set(bonemap.CORE) <= set(roles)
    heads = skeleton.heads
    assert heads[roles["thigh.L"], 0] > 0 > heads[roles["thigh.R"], 0]
    assert heads[roles["hand.L"], 0] > 0 > heads[roles["hand.R"], 0]
    assert roles["hips"] == 0 and heads[roles["head"], 2] == pytest.approx(1.6)
    assert heads[roles["shin.L"], 2] == pytest.approx(0.5)
    assert heads[roles["forearm.R"], 2] == pytest.approx(1.15)
    assert heads[roles["toe.L"], 1] == pytest.approx(-0.12)
    bmap = bonemap.detect(skeleton)
    assert bmap.convention == "topology" and set(bmap.inferred) >= set(bonemap.CORE)


def test_turned_round_character_swaps_sides():
    """Facing comes from the toes: the same figure turned 180 degrees about Z keeps its
    left leg (now at -X) as the left one."""
    skeleton = _stick_figure()
    turn = np.diag([-1.0, -1.0, 1.0, 1.0])
    turned = replace(skeleton, rest=turn @ skeleton.rest, tails=skeleton.tails * [-1, -1, 1])
    assert topology.infer(turned) == topology.infer(skeleton)


def test_a_chain_has_no_hips():
    """One chain (a tail, a rope) has no two legs: no roles, and detect says so."""
    heads = np.array([[0, 0, z] for z in np.linspace(0, 1, 6)], dtype=float)
    rest = np.tile(np.eye(4), (6, 1, 1))
    rest[:, :3, 3] = heads
    rope = Skeleton(tuple(f"x{j}" for j in range(6)), np.arange(-1, 5, dtype=np.int32), rest,
                    heads + [0, 0, 0.2])  # fmt: skip
    assert topology.infer(rope) == {}
    with pytest.raises(ParameterError):
        bonemap.detect(rope)


def test_avatar_rigs_by_topology_match_names(model):
    from avatar.body.assets import RIG_NAMES
    from avatar.human import Human

    for rig in RIG_NAMES:
        skeleton = Human(rig=rig, model=model).skeleton
        named = bonemap.detect(skeleton).bones
    found = topology.infer(skeleton)
    assert {r: found.get(r) for r in named} == named, rig
    forced = bonemap.detect(skeleton, "topology")  # also by name, e.g. --source-map
    assert forced.convention == "topology" and forced.bones == found


@needs_fixtures
@pytest.mark.parametrize("clip", CLIPS, ids=lambda p: p.name)
def test_renamed_clip_maps_as_by_name(clip):
    skeleton, animation = bvh.load(clip)
    by_name = bonemap.detect(skeleton)
    assert not by_name.inferred
    anon, anim = _renamed(skeleton, animation)
    pos = forward(anon, anim.rotations, anim.translations)[..., :3, 3]
    found = bonemap.detect(anon, heads=pos)
    assert found.convention == "topology"
    assert _core(found) == _core(by_name)
    # Fingers too, where the names say (CMU's stub after the finger base is an extra).
    assert {r: found.bones.get(r) for r in by_name.bones} == by_name.bones


@needs_fixtures
def test_partly_known_names_are_filled_in():
    clip = FIXTURES / "cmu_motionbuilder" / "02_01_walk.bvh"
    skeleton, animation = bvh.load(clip)
    legs = {"LeftUpLeg", "LeftLeg", "RightUpLeg", "RightLeg"}
    anon, _ = _renamed(skeleton, animation, keep=set(skeleton.names) - legs)
    found = bonemap.detect(anon)
    assert found.convention == "cmu_motionbuilder+topology"
    assert {"thigh.L", "shin.L", "thigh.R", "shin.R"} <= set(found.inferred)
    assert not set(found.inferred) & set(bonemap.CORE) - {"thigh.L", "shin.L", "thigh.R", "shin.R"}
    named = bonemap.detect(skeleton).bones
    assert {r: found.bones[r] for r in named} == named


def _core_directions(target: Skeleton, animation: Animation) -> np.ndarray:
    """(T, S, 3) body segments from each body bone to the next (the hand to the middle
    finger)."""
    tmap = bonemap.detect(target)
    segs = np.array([(tmap.bones[r], tmap.bones[n]) for r, n in bonemap.NEXT.items()
                     if r in bonemap.CORE and n in tmap.bones])  # fmt: skip
    heads = forward(target, animation.rotations, animation.translations)[..., :3, 3]
    return heads[:, segs[:, 1]] - heads[:, segs[:, 0]]


@needs_fixtures
@pytest.mark.parametrize(
    "clip",
    [c for c in CLIPS if c.parent.name != "makehuman_default" or c.stem == "fight01"],
    ids=lambda p: p.name,
)
def test_renamed_clip_retargets_the_same(clip):
    from avatar.human import Human

    target = Human().skeleton
    skeleton, animation = bvh.load(clip)
    anon, anim = _renamed(skeleton, animation)
    frames = slice(0, 90)
    ref, _ = retarget(skeleton, animation, target, frames=frames, match_names=False)
    out, report = retarget(anon, anim, target, frames=frames, match_names=False)
    assert report.source_convention == "topology"
    assert any("mapped by topology" in n and "thigh.L=" in n for n in report.notes)
    assert "topology" in report.summary()
    err = geometry.angle(_core_directions(target, ref), _core_directions(target, out))
    assert err.max() < 1.0
    hips = [forward(target, a.rotations, a.translations)[:, 0, :3, 3] for a in (ref, out)]
    assert np.abs(hips[0] - hips[1]).max() < 0.01


@needs_fixtures
@pytest.mark.parametrize("clip", CLIPS, ids=lambda p: p.name)
def test_renamed_file_loads_with_the_same_axes_and_unit(clip):
    """Up axis and unit detection fall back on the hierarchy when names say nothing."""
    data = bvh.read(clip)
    anon = replace(data, names=tuple(f"j{j}" for j in range(len(data.names))))
    up = bvh.detect_up(data)
    assert bvh.detect_up(anon) == up
    assert bvh.detect_unit(anon, up) == bvh.detect_unit(data, up)


@needs_fixtures
def test_anonymous_file_end_to_end(tmp_path):
    """A BVH file whose joints are j0..jN: loaded upright at the right size, mapped by
    topology and retargeted as the named file (< 1 degree), with the report saying so."""
    from avatar.human import Human

    clip = FIXTURES / "cmu_3dsmax" / "131_01_start_walk_stop.bvh"
    data = bvh.read(clip)
    bvh.write(
        tmp_path / "anon.bvh", replace(data, names=tuple(f"j{j}" for j in range(len(data.names))))
    )
    target = Human().skeleton
    frames = slice(0, 120)
    ref, _ = retarget(*bvh.load(clip), target, frames=frames, match_names=False)
    out, report = retarget(*bvh.load(tmp_path / "anon.bvh"), target, frames=frames)
    assert report.source_convention == "topology" and "j1" in report.unused_source
    err = geometry.angle(_core_directions(target, ref), _core_directions(target, out))
    assert err.max() < 1.0


def test_random_trees_never_break_it():
    """Any hierarchy (random trees, random poses) gives roles on real joints or nothing,
    and ``detect`` either maps hips or says it cannot: no other exception."""
    rng = np.random.default_rng(7)
    for _ in range(200):
        count = int(rng.integers(1, 40))
        parents = np.array([-1] + [int(rng.integers(0, j)) for j in range(1, count)], np.int32)
        heads = np.cumsum(rng.normal(size=(count, 3)) * 0.2, axis=0)
        rest = np.tile(np.eye(4), (count, 1, 1))
        rest[:, :3, 3] = heads
        skeleton = Skeleton(tuple(f"x{j}" for j in range(count)), parents, rest,
                            heads + rng.normal(size=(count, 3)) * 0.05)  # fmt: skip
        roles = topology.infer(skeleton, rng.normal(size=(5, count, 3)))
        assert all(0 <= j < count for j in roles.values())
        assert set(roles) <= set(bonemap.NEXT)
        topology.upright_roles(parents, rng.normal(size=(count, 3)), rng.normal(size=(3, count, 3)))
        try:
            assert "hips" in bonemap.detect(skeleton).bones
        except ParameterError:
            pass


def test_conventions_are_read_once_and_handed_out_as_copies():
    """``detect`` reuses the parsed convention files; ``conventions()`` hands out fresh
    copies, so changing one changes neither later calls nor detection."""
    skeleton = _stick_figure()
    before = bonemap.detect(skeleton)
    table = bonemap.conventions()
    table["cmu_motionbuilder"]["hips"] = ["bone0"]
    table.clear()
    assert "cmu_motionbuilder" in bonemap.conventions()
    assert bonemap.conventions()["cmu_motionbuilder"]["hips"] != ["bone0"]
    assert bonemap.detect(skeleton) == before
    assert bonemap._shipped() is bonemap._shipped()  # parsed once per process

"""Shared fixtures of the mocap tests: Avatar rigs and fixture clips retargeted onto them."""

from __future__ import annotations

import functools

import pytest


@functools.cache
def _human(rig: str):
    import avatar

    return avatar.Human(rig=rig)


@pytest.fixture(scope="session")
def rig_skeleton(model):
    """rig name -> the default human's skeleton on that rig."""
    return lambda rig="default": _human(rig).skeleton


@functools.cache
def _clip_on(rig: str, path: str, most: int):
    from avatar.motion import load_bvh, retarget
    from avatar.motion.timing import select

    source, clip = load_bvh(path)
    clip = select(clip, slice(0, most))
    animation, _ = retarget(source, clip, _human(rig).skeleton, measure=False)
    return animation


@pytest.fixture(scope="session")
def clip_on(model):
    """(rig, BVH path, frames) -> the clip's first frames retargeted onto that rig."""
    return lambda rig, path, most=240: _clip_on(rig, str(path), most)


def clips(fixtures):
    """Every fixture BVH clip with motion (more than one frame)."""
    from avatar.io import bvh

    out = []
    for path in sorted((fixtures / "bvh").rglob("*.bvh")):
        if "face-poseunits" in path.name:
            continue  # face shapes only: the body does not move
        if bvh.read(path).motion.shape[0] > 1:
            out.append(path)
    return out

"""``avatar retarget`` plumbing and frame/fps options."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pytest

from avatar.cli import motion as cli
from avatar.errors import ParameterError
from avatar.io import bvh
from avatar.motion import timing

WALK = Path(__file__).resolve().parents[2] / ".." / "shared" / "fixtures" / "bvh"
WALK = WALK / "cmu_motionbuilder" / "02_01_walk.bvh"


def test_parse_frames():
    assert timing.parse_frames("10:20") == slice(10, 20)
    assert timing.parse_frames(":5") == slice(None, 5)
    assert timing.parse_frames(None) is None
    with pytest.raises(ParameterError):
        timing.parse_frames("ten")


@pytest.mark.skipif(not WALK.exists(), reason="../shared/fixtures is absent")
def test_cli_retarget_writes_one_bvh_per_clip(tmp_path):
    parser = argparse.ArgumentParser()
    cli.add_retarget_arguments(parser)
    report = tmp_path / "report.json"
    args = parser.parse_args([str(WALK), "--out", str(tmp_path), "--frames", "0:60",
                              "--fps", "30", "--in-place", "--report", str(report)])  # fmt: skip
    assert cli.run_retarget(args) == 0
    skeleton, anim = bvh.load(tmp_path / WALK.name)
    assert anim.frames == 15 and anim.fps == pytest.approx(30)
    assert len(skeleton.names) == 163 and report.exists()
    hips = skeleton.heads[0]
    assert np.isfinite(hips).all()

"""``avatar retarget`` plumbing and frame/fps options."""

from __future__ import annotations

import argparse
import json
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


@pytest.mark.skipif(not WALK.exists(), reason="../shared/fixtures is absent")
def test_batch_retarget_carries_on_past_bad_clips_and_reports_every_clip(tmp_path, capsys):
    """Good clips are written and reported; each bad one is one line; exit status 1."""
    from avatar import cli as avatar_cli

    clips = tmp_path / "clips"
    clips.mkdir()
    text = WALK.read_text()
    (clips / "a_walk.bvh").write_text(text)
    (clips / "b_garbage.bvh").write_bytes(b"\x00\xffnot a bvh at all\n")
    hierarchy = text[: text.index("MOTION")]
    (clips / "c_empty.bvh").write_text(hierarchy + "MOTION\nFrames: 0\nFrame Time: 0.0083\n")
    (clips / "d_blank_line.bvh").write_text(text.replace("MOTION\n", "MOTION\n\n", 1))
    out, report = tmp_path / "out", tmp_path / "report.json"
    status = avatar_cli.main(["retarget", str(clips), "--out", str(out), "--frames", "0:40",
                              "--report", str(report)])  # fmt: skip
    assert status == 1
    captured = capsys.readouterr()
    errors = [line for line in captured.err.splitlines() if line.startswith("avatar: error")]
    assert "Traceback" not in captured.err
    assert len(errors) == 3  # one line per bad clip and the count
    assert "b_garbage.bvh" in errors[0] and "c_empty.bvh" in errors[1]
    assert "Frames: 0" in errors[1] and "2 of 4 clips failed" in errors[2]
    assert sorted(p.name for p in out.iterdir()) == ["a_walk.bvh", "d_blank_line.bvh"]
    table = json.loads(report.read_text())
    assert sorted(Path(k).name for k in table) == sorted(p.name for p in clips.iterdir())
    rows = {Path(k).name: v for k, v in table.items()}
    assert "error" in rows["b_garbage.bvh"] and "error" in rows["c_empty.bvh"]
    assert rows["a_walk.bvh"]["frames"] == 40 and "direction_p95" in rows["d_blank_line.bvh"]


def test_batch_retarget_of_an_empty_folder_is_an_error_naming_it(tmp_path, capsys):
    from avatar import cli as avatar_cli

    empty = tmp_path / "nothing here"
    empty.mkdir()
    (empty / "notes.txt").write_text("no clips")
    assert avatar_cli.main(["retarget", str(empty), "--out", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err.strip()
    assert err == f"avatar: error: no .bvh clips in folder {str(empty)!r}"
    assert not (tmp_path / "out").exists()


def test_batch_retarget_refuses_an_output_folder_under_a_file(tmp_path, capsys):
    from avatar import cli as avatar_cli

    (tmp_path / "file").write_text("x")
    clip = tmp_path / "clip.bvh"
    clip.write_text("HIERARCHY\n")
    assert avatar_cli.main(["retarget", str(clip), "--out", str(tmp_path / "file" / "o")]) == 1
    assert "is a file" in capsys.readouterr().err

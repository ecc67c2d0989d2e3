"""avatar mocap record/send/serve end to end on loopback (ephemeral ports)."""

from __future__ import annotations

import socket
import threading
import time

import pytest

from avatar.cli import main
from avatar.io import bvh


def _free_port() -> int:
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def test_record_what_send_replays(fixtures, model, tmp_path, capsys):
    clip = fixtures / "bvh/cmu_motionbuilder/02_01_walk.bvh"
    source_skeleton, source = bvh.load(clip)
    short = tmp_path / "short.bvh"
    from avatar.motion.timing import select

    bvh.save(short, source_skeleton, select(source, slice(0, 60)))
    port = _free_port()
    take = tmp_path / "take.bvh"
    status = {}
    recorder = threading.Thread(target=lambda: status.setdefault("rc", main(
        ["mocap", "record", "--vmc", f"127.0.0.1:{port}", "--seconds", "4", "--rig",
         "game_engine", "-o", str(take)])))  # fmt: skip
    recorder.start()
    time.sleep(1.0)
    assert main(["mocap", "send", str(short), "--vmc", f"127.0.0.1:{port}", "--speed", "2"]) == 0
    recorder.join(timeout=30)
    assert status["rc"] == 0
    skeleton, got = bvh.load(take)
    assert got.frames == 60
    assert got.fps == pytest.approx(source.fps, rel=1e-3)  # the sender's rate, not arrival
    assert "pelvis" in skeleton.names  # on the game_engine rig


def test_record_with_no_sender_fails_cleanly(model, tmp_path, capsys):
    take = tmp_path / "take.bvh"
    rc = main(["mocap", "record", "--vmc", f"127.0.0.1:{_free_port()}", "--seconds", "0.3",
               "-o", str(take)])  # fmt: skip
    assert rc == 1 and not take.exists()
    err = capsys.readouterr().err
    assert err.startswith("avatar: error: no VMC frames arrived") and err.count("\n") == 1


def test_bad_addresses_and_files_are_one_line(tmp_path, capsys):
    assert main(["mocap", "send", str(tmp_path / "none.bvh"), "--vmc", "127.0.0.1:9"]) == 1
    assert "no such file" in capsys.readouterr().err
    (tmp_path / "a.bvh").write_text("HIERARCHY\n")
    assert main(["mocap", "send", str(tmp_path / "a.bvh"), "--vmc", "nohost"]) == 1
    assert "HOST:PORT" in capsys.readouterr().err


def test_serve_prints_stats_and_records_keypoints(model, tmp_path, capsys):
    import numpy as np

    import avatar
    from avatar.mocap import keypoint_stream, keypoints

    # the keypoints first: on a loaded machine making a Human took most of the serve window
    human = avatar.Human()
    rig = keypoints.bind("coco17", human.skeleton)
    points = rig.positions(human.pose("t-pose"))[0]
    port = _free_port()
    take = tmp_path / "served.bvh"
    status = {}
    server = threading.Thread(target=lambda: status.setdefault("rc", main(
        ["mocap", "serve", "--keypoints", f"127.0.0.1:{port}", "--set", "coco17",
         "--seconds", "2.5", "-o", str(take)])))  # fmt: skip
    server.start()
    time.sleep(1.0)
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    for i in range(20):
        sock.sendto(keypoint_stream.encode(i, points, np.ones(17), i / 30, axes="avatar"),
                    ("127.0.0.1", port))  # fmt: skip
        time.sleep(0.005)
    sock.sendto(b"garbage", ("127.0.0.1", port))
    sock.close()
    server.join(timeout=30)
    assert status["rc"] == 0
    out = capsys.readouterr().out
    assert "20 frames" in out and "malformed 1" in out
    assert bvh.load(take)[1].frames == 20

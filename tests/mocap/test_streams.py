"""The JSON keypoints stream over UDP and BVH frames over TCP: real sockets, fuzzed input."""

from __future__ import annotations

import json
import socket
import socketserver
import threading
import time

import numpy as np

from avatar.io import bvh
from avatar.mocap import keypoint_stream, keypoints, live
from avatar.mocap.bvhstream import BvhStreamReceiver
from avatar.mocap.stream import Counters


def _wait(fn, seconds=5.0):
    end = time.perf_counter() + seconds
    got = []
    while time.perf_counter() < end:
        got.extend(fn())
        if got:
            time.sleep(0.05)
            got.extend(fn())
            return got
        time.sleep(0.01)
    return got


def test_keypoints_stream_drives_the_rig(fixtures, rig_skeleton, clip_on):
    skeleton = rig_skeleton("default")
    clip = clip_on("default", fixtures / "bvh/cmu_motionbuilder/02_01_walk.bvh", 30)
    rig = keypoints.bind("coco17", skeleton)
    truth = rig.positions(clip)
    source = live.open_keypoints(rig, "127.0.0.1", 0)
    try:
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        for i, p in enumerate(truth):
            sock.sendto(
                keypoint_stream.encode(i, p, None, i / 30, "coco17", "avatar"), source.address
            )
            time.sleep(0.002)
        sock.close()
        poses = _wait(source.take)
        stats = source.stats()
    finally:
        source.close()
    assert len(poses) == len(truth)
    assert stats.frames == len(truth) and stats.dropped_total == 0
    from avatar.rig.kinematics import world_pose

    rot, heads = world_pose(skeleton, poses[-1].rotations, poses[-1].translations)
    solved = rig.posed(rot, heads)
    body = [rig.keypoints.index(n) for n in ("left_wrist", "right_ankle", "left_knee")]
    assert np.linalg.norm(solved[body] - truth[-1][body], axis=-1).max() < 0.03


def test_keypoints_stream_fuzz():
    kset = keypoints.load("coco17")
    counters = Counters()
    parser = keypoint_stream.KeypointParser(kset, counters)
    rng = np.random.default_rng(5)
    good = json.loads(keypoint_stream.encode(5, np.zeros((17, 3))))
    bad = [b"", b"\xff\xfe", b"[1, 2]", b"{", b"{}" , b"nul",
           json.dumps({**good, "points": good["points"][:16]}).encode(),
           json.dumps({**good, "seq": "5"}).encode(),
           json.dumps({**good, "set": "h36m17"}).encode(),
           json.dumps({**good, "axes": "sideways"}).encode(),
           json.dumps({**good, "points": [["a", 1, 2]] * 17}).encode(),
           json.dumps({**good, "points": [[1, 2, 3, 4, 5]] * 17}).encode(),
           json.dumps({**good, "t": float("nan")}).encode(),
           b"[" * 100000 + b"]" * 100000]  # fmt: skip
    bad += [rng.bytes(int(rng.integers(1, 300))) for _ in range(300)]
    for data in bad:
        assert parser.feed(data, 0.0) is None
    nan = json.dumps({**good, "points": [[float("nan"), 0, 0, 1]] + good["points"][1:]})
    frame = parser.feed(nan.encode(), 0.0)  # NaN point: that keypoint is missing
    assert frame is not None and np.isnan(frame.data[0][0]).all()
    assert parser.feed(keypoint_stream.encode(4, np.zeros((17, 3))), 0.0) is None  # older
    assert counters.stats().dropped["out_of_order"] == 1
    assert counters.stats().dropped_total == len(bad) + 1


class _BvhServer(socketserver.StreamRequestHandler):
    text = ""

    def handle(self):
        self.wfile.write(self.text.encode())


def test_bvh_over_tcp_axis_neuron_framing(fixtures):
    path = fixtures / "bvh/cmu_motionbuilder/02_01_walk.bvh"
    data = bvh.read(path)
    text = path.read_text()
    head = text[: text.index("MOTION")] + "MOTION\nFrames: 0\nFrame Time: 0.0083333\n"
    rows = [" ".join(f"{v:.6f}" for v in row) for row in data.motion[:40]]
    lines = [f"0 Avatar00 {r} ||" for r in rows[:20]] + rows[20:]
    lines.insert(5, "not a frame")
    lines.insert(9, "1 2 3")
    lines.insert(12, " ".join(["nan"] * data.motion.shape[1]))
    _BvhServer.text = head + "\n".join(lines) + "\n"
    server = socketserver.TCPServer(("127.0.0.1", 0), _BvhServer)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        with BvhStreamReceiver(*server.server_address) as rx:
            frames = _wait(rx.take)
            skeleton, clip = rx.to_animation([f.data for f in frames])
            stats = rx.stats()
    finally:
        server.shutdown()
        server.server_close()
    assert len(frames) == 40
    np.testing.assert_allclose(np.stack([f.data for f in frames]), data.motion[:40], atol=1e-5)
    assert stats.dropped == {"malformed": 2, "bad_frame": 1}
    ref_skeleton, ref = bvh.load(path)
    np.testing.assert_allclose(clip.rotations, ref.rotations[:40], atol=1e-5)
    assert skeleton.names == ref_skeleton.names

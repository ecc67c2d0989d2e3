"""VMC: frame conversion, Avatar -> UDP -> Avatar, an independent sender, fuzzed packets."""

from __future__ import annotations

import socket
import time

import numpy as np
import pytest

pytest.importorskip("pythonosc")
from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder  # noqa: E402
from pythonosc.osc_message_builder import OscMessageBuilder  # noqa: E402
from pythonosc.udp_client import SimpleUDPClient  # noqa: E402

from avatar.mocap import live, record, unity, vmc  # noqa: E402
from avatar.mocap.stream import Counters  # noqa: E402
from avatar.rig import quaternion as Q  # noqa: E402
from avatar.rig.kinematics import world_pose  # noqa: E402


def _unity_matrix(xyzw):
    """Unity's quaternion -> matrix (the same algebra as any quaternion, in Unity axes)."""
    x, y, z, w = xyzw
    return Q.to_matrix(np.array([w, x, y, z]))


def test_unity_conversions_match_the_axis_change():
    rng = np.random.default_rng(0)
    m = unity.M
    assert np.linalg.det(m) == pytest.approx(-1.0)  # the handedness flips
    for _ in range(50):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        want = m @ _unity_matrix(q) @ m.T  # the same turn seen in Avatar's axes
        got = Q.to_matrix(unity.to_avatar_quaternion(q))
        np.testing.assert_allclose(got, want, atol=1e-12)
        np.testing.assert_allclose(unity.to_unity_quaternion(unity.to_avatar_quaternion(q)), q)
        v = rng.normal(size=3)
        np.testing.assert_allclose(unity.to_avatar_vector(v), m @ v)
        np.testing.assert_allclose(unity.to_unity_vector(unity.to_avatar_vector(v)), v)
    # Unity up (+Y) is Avatar up (+Z); Unity forward (+Z) is the way an Avatar faces (-Y)
    np.testing.assert_allclose(unity.to_avatar_vector([0, 1, 0]), [0, 0, 1])
    np.testing.assert_allclose(unity.to_avatar_vector([0, 0, 1]), [0, -1, 0])


def _receiver():
    return vmc.VmcReceiver("127.0.0.1", 0).start()


def _wait_frames(rx, count, seconds=5.0):
    got = []
    end = time.perf_counter() + seconds
    while len(got) < count and time.perf_counter() < end:
        time.sleep(0.01)
        got.extend(rx.take())
    return got


def _turn_errors(skeleton, a_rot, a_trans, b_rot, b_trans, bones):
    wa, ha = world_pose(skeleton, a_rot, a_trans)
    wb, hb = world_pose(skeleton, b_rot, b_trans)
    d = Q.multiply(Q.conjugate(wa[..., bones, :]), wb[..., bones, :])
    angle = np.degrees(2 * np.arctan2(np.linalg.norm(d[..., 1:], axis=-1), np.abs(d[..., 0])))
    return angle, np.linalg.norm(ha - hb, axis=-1)


@pytest.mark.parametrize("rig_name", ["default", "game_engine", "mixamo"])
def test_a_clip_sent_as_vmc_over_udp_comes_back(fixtures, rig_skeleton, clip_on, rig_name):
    """Avatar sends a clip through a real loopback socket, Avatar receives it: every bone
    VMC carries within 0.5 degrees (float32 on the wire), frames at the sender's rate."""
    skeleton = rig_skeleton(rig_name)
    clip = clip_on(rig_name, fixtures / "bvh/cmu_motionbuilder/02_01_walk.bvh", 60)
    rx = _receiver()
    try:
        host, port = rx.address
        record.send_animation(skeleton, clip, host, port, realtime=True, speed=4.0)
        frames = _wait_frames(rx, clip.frames)
    finally:
        rx.close()
    assert len(frames) == clip.frames
    rig = unity.UnityRig(skeleton)
    got = [rig.from_unity(f.data) for f in frames]
    rot = np.stack([g[0] for g in got])
    trans = np.stack([g[1] for g in got])
    mapped = rig.bone_of[rig.bone_of >= 0]
    angle, dist = _turn_errors(skeleton, clip.rotations, clip.translations, rot, trans, mapped)
    assert angle.max() < 0.5, angle.max()
    # heads move by the bend of the in-between spine bones VMC does not carry (default rig)
    assert dist[:, mapped].max() < 0.015
    fps = record.frame_rate([f.sent for f in frames])
    assert fps == pytest.approx(clip.fps, rel=1e-3)
    assert rx.stats().dropped_total == 0


def test_an_independent_sender_drives_the_rig_as_the_spec_says(rig_skeleton):
    """Messages written by hand from the VMC spec with python-osc's own client, one per
    datagram, ending with /VMC/Ext/OK: the left upper arm turned 90 degrees about Unity's
    +Z (it hangs down), the hips turned 90 degrees about Unity's +Y (the character turns to
    its right), the hips moved 20 cm forward."""
    skeleton = rig_skeleton("default")
    source = live.open_vmc(skeleton, "127.0.0.1", 0)
    try:
        client = SimpleUDPClient(*source.address)
        s = np.sqrt(0.5)
        client.send_message("/VMC/Ext/Root/Pos", ["root", 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0])
        client.send_message("/VMC/Ext/Bone/Pos", ["Hips", 0.0, 0.95, 0.2, 0.0, s, 0.0, s])
        client.send_message("/VMC/Ext/Bone/Pos", ["LeftUpperArm", 0.0, 0.0, 0.0, 0.0, 0.0, s, s])
        client.send_message("/VMC/Ext/T", [1.5])
        client.send_message("/VMC/Ext/OK", [1])
        pose = None
        end = time.perf_counter() + 5
        while pose is None and time.perf_counter() < end:
            time.sleep(0.01)
            pose = source.poll()
    finally:
        source.close()
    assert pose is not None and pose.sent == 1.5
    rot, heads = world_pose(skeleton, pose.rotations, pose.translations)
    hips = skeleton.index("root")
    facing = Q.rotate(Q.multiply(rot[hips], Q.conjugate(skeleton_rest(skeleton)[hips])),
                      np.array([0.0, -1.0, 0.0]))  # fmt: skip
    np.testing.assert_allclose(facing, [-1.0, 0.0, 0.0], atol=1e-6)  # faces its old right
    np.testing.assert_allclose(heads[hips], [0.0, -0.2, 0.95], atol=1e-6)
    elbow = heads[skeleton.index("lowerarm01.L")] - heads[skeleton.index("upperarm01.L")]
    # in the hips' turned frame the arm hangs straight down
    assert elbow[2] / np.linalg.norm(elbow) < -0.99


def skeleton_rest(skeleton):
    return Q.from_matrix(skeleton.rest[:, :3, :3])


def _bundle(*messages):
    b = OscBundleBuilder(IMMEDIATELY)
    for address, args in messages:
        m = OscMessageBuilder(address)
        for a in args:
            m.add_arg(a)
        b.add_content(m.build())
    return b.build().dgram


def _message(address, args):
    m = OscMessageBuilder(address)
    for a in args:
        m.add_arg(a)
    return m.build().dgram


GOOD_BONE = ("/VMC/Ext/Bone/Pos", ["Head", 0.0, 0.1, 0.0, 0.0, 0.0, 0.0, 1.0])


def test_fuzzed_packets_are_dropped_and_counted_never_raised():
    counters = Counters()
    asm = vmc.VmcAssembler(counters)
    rng = np.random.default_rng(3)
    good = _bundle(GOOD_BONE, ("/VMC/Ext/T", [1.0]), ("/VMC/Ext/OK", [1]))
    bad = [
        b"",
        b"\x00" * 7,
        b"#bundle\x00" + b"\xff" * 40,
        good[:-5],  # truncated
        _message("/VMC/Ext/Bone/Pos", [3, 0.0, 0.1, 0.0, 0.0, 0.0, 0.0, 1.0]),  # int name
        _message("/VMC/Ext/Bone/Pos", ["Head", "x", 0.1, 0.0, 0.0, 0.0, 0.0, 1.0]),
        _message("/VMC/Ext/Bone/Pos", ["Head", 0.0]),  # too few
        _message("/VMC/Ext/Bone/Pos", ["Head", float("nan"), 0.1, 0.0, 0.0, 0.0, 0.0, 1.0]),
        _message("/VMC/Ext/Bone/Pos", ["Head", 0.0, 0.1, 0.0, 0.0, 0.0, 0.0, 0.0]),  # zero quat
        _message("/VMC/Ext/Bone/Pos", ["Head", 0.0, 0.1, 0.0, 1e30, 1e30, 0.0, 1.0]),
        _message("/VMC/Ext/Root/Pos", ["root", float("inf"), 0, 0, 0, 0, 0, 1]),
        _message("/VMC/Ext/T", ["late"]),
        _bundle(*[GOOD_BONE] * 600, ("/VMC/Ext/OK", [1])),  # huge count
        _message("/VMC/Ext/Bone/Pos", ["NotABone", 0.0, 0.1, 0.0, 0.0, 0.0, 0.0, 1.0]),
        b"#bundle\x00" + b"\x00" * 8 + (2**31 - 1).to_bytes(4, "big") + b"abc",  # huge size
    ]
    bad += [rng.bytes(int(rng.integers(1, 400))) for _ in range(500)]
    bad += [good[: int(rng.integers(1, len(good)))] for _ in range(100)]
    for data in bad:
        asm.feed(data, 0.0)
    stats = counters.stats()
    assert stats.dropped_total >= 14
    assert {"malformed", "bad_message", "oversize", "unknown_bone"} <= set(stats.dropped)
    later = _bundle(GOOD_BONE, ("/VMC/Ext/T", [2.0]), ("/VMC/Ext/OK", [1]))
    frames = asm.feed(later, 1.0)  # still works after all that
    assert len(frames) == 1 and frames[0].sent == 2.0
    assert np.isfinite(frames[0].data.bones["Head"][1]).all()


def test_out_of_order_frames_are_dropped():
    counters = Counters()
    asm = vmc.VmcAssembler(counters)
    for t, expect in ((1.0, 1), (3.0, 1), (2.0, 0), (3.0, 0), (4.0, 1)):
        frames = asm.feed(_bundle(GOOD_BONE, ("/VMC/Ext/T", [t]), ("/VMC/Ext/OK", [1])), t)
        assert len(frames) == expect, t
    assert counters.stats().dropped == {"out_of_order": 2}


def test_the_receiver_thread_survives_garbage_on_the_wire():
    """Random datagrams through the real socket, then valid frames: the thread is alive and
    takes them (UDP may lose datagrams under load, so the valid one is repeated)."""
    rx = _receiver()
    try:
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        rng = np.random.default_rng(4)
        for i in range(200):
            sock.sendto(rng.bytes(int(rng.integers(1, 1500))), rx.address)
            if i % 20 == 0:
                time.sleep(0.005)
        frames = []
        for t in range(1, 50):
            sock.sendto(_bundle(GOOD_BONE, ("/VMC/Ext/T", [float(t)]), ("/VMC/Ext/OK", [1])),
                        rx.address)  # fmt: skip
            frames = _wait_frames(rx, 1, 0.1)
            if frames:
                break
        sock.close()
        assert rx._thread is not None and rx._thread.is_alive()
    finally:
        rx.close()
    assert len(frames) == 1
    stats = rx.stats()
    assert stats.packets > 100 and stats.dropped.get("malformed", 0) > 50


def test_addresses_are_checked():
    from avatar.errors import ParameterError

    assert vmc.parse_address(":39539", "0.0.0.0") == ("0.0.0.0", 39539)
    assert vmc.parse_address("10.0.0.2:7") == ("10.0.0.2", 7)
    for bad in ("localhost", "host:port", "h:70000"):
        with pytest.raises(ParameterError):
            vmc.parse_address(bad)

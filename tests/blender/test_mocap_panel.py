"""The Mocap panel on the installed extension: a real character driven live from a real
socket by an independent sender (python-osc's own client, VMC messages written by hand
from the spec), the timer step run by hand (headless bpy runs no timers), recording into
an Action, fuzzed packets, a port in use, a deleted character, and the port freed on Stop.
"""

from __future__ import annotations

import math
import socket
import sys
import threading
import time

import numpy as np
import pytest
import test_extension

pytest.importorskip("pythonosc")
from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder  # noqa: E402
from pythonosc.osc_message_builder import OscMessageBuilder  # noqa: E402
from pythonosc.udp_client import SimpleUDPClient  # noqa: E402

MODULE = "bl_ext.user_default.avatar_addon.panel_mocap"
S = math.sqrt(0.5)
IDENTITY = [0.0, 0.0, 0.0, 1.0]  # Unity quaternion order: x, y, z, w
# Unity is left-handed, Y up, the model facing +Z, its left hand towards -X. A turn of +90
# degrees about Unity's +Y takes -X to +Z: the left forearm, out to the side in the T-pose,
# then points forward (the elbow bent 90 degrees in front of the body).
BEND = [0.0, S, 0.0, S]
HIPS_AT = [0.0, 0.95, 0.2]  # Unity: 0.95 m up, 0.2 m forward -> Avatar (0, -0.2, 0.95)



def _panel():
    return sys.modules[MODULE]


def _free_port(kind=socket.SOCK_DGRAM) -> int:
    with socket.socket(socket.AF_INET, kind) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _frame(upper=IDENTITY, lower=IDENTITY, t=None):
    """One VMC frame as the spec lists it: root, bones, (T), OK."""
    out = [
        ("/VMC/Ext/Root/Pos", ["root", 0.0, 0.0, 0.0, *IDENTITY]),
        ("/VMC/Ext/Bone/Pos", ["Hips", *HIPS_AT, *IDENTITY]),
        ("/VMC/Ext/Bone/Pos", ["LeftUpperArm", 0.0, 0.0, 0.0, *upper]),
        ("/VMC/Ext/Bone/Pos", ["LeftLowerArm", 0.0, 0.0, 0.0, *lower]),
    ]
    if t is not None:
        out.append(("/VMC/Ext/T", [float(t)]))
    return [*out, ("/VMC/Ext/OK", [1])]


class Sender(threading.Thread):
    """An independent VMC performer: python-osc's SimpleUDPClient, one message a datagram,
    sending ``self.frame`` every 5 ms until ``stop()``."""

    def __init__(self, port: int, frame):
        super().__init__(daemon=True)
        self.client = SimpleUDPClient("127.0.0.1", port)
        self.frame = frame
        self.sent = 0
        self._halt = threading.Event()

    def run(self):
        while not self._halt.is_set():
            for address, args in self.frame:
                self.client.send_message(address, args)
            self.sent += 1
            time.sleep(0.005)

    def stop(self):
        self._halt.set()
        self.join(2.0)


def _configure(scene, port, source="VMC", record=False, smoothing=0.0):
    settings = scene.avatar_mocap
    settings.source = source
    settings.host = "127.0.0.1"
    settings.port = port
    settings.record = record
    settings.smoothing = smoothing


def _skeleton(root):
    from avatar.blender import live

    return live.geometry(live.recipe_of(root), dress=False).body.skeleton


def _library_pose(skeleton, frame):
    """What the library makes of a hand-written frame (its own conversion, for comparison)."""
    from avatar.mocap.unity import UnityPose, UnityRig

    bones = {a[0]: (np.array(a[1:4]), np.array(a[4:8])) for m, a in frame if m.endswith("Bone/Pos")}
    root = next(a for m, a in frame if m.endswith("Root/Pos"))
    return UnityRig(skeleton).from_unity(
        UnityPose((np.array(root[1:4]), np.array(root[4:8])), bones)
    )


def _pose_bones(arm, names):
    bones = arm.pose.bones
    q = np.empty(len(bones) * 4, np.float32)
    loc = np.empty(len(bones) * 3, np.float32)
    bones.foreach_get("rotation_quaternion", q)
    bones.foreach_get("location", loc)
    index = {b.name: i for i, b in enumerate(bones)}
    order = [index[n] for n in names]
    return q.reshape(-1, 4)[order], loc.reshape(-1, 3)[order]


def _matches(arm, names, want_rot, want_loc, atol=1e-4) -> bool:
    rot, loc = _pose_bones(arm, names)
    dots = np.abs(np.sum(rot * want_rot, axis=1))
    return bool(np.all(dots > 1 - atol) and np.allclose(loc, want_loc, atol=atol))


def _tick_until(check, seconds=5.0):
    panel = _panel()
    end = time.perf_counter() + seconds
    while time.perf_counter() < end:
        assert panel.tick() == pytest.approx(panel.INTERVAL)  # the timer goes on
        if check():
            return True
        time.sleep(0.005)
    return False


def _heads(arm, *names):
    import bpy

    bpy.context.view_layer.update()
    m = np.array(arm.matrix_world)
    return [(m @ np.array([*arm.pose.bones[n].head, 1.0]))[:3] for n in names]


def _body_vertices(root):
    """(V, 3) the body's skin as the scene shows it (deformed by the armature)."""
    import bpy

    from avatar.blender import live

    depsgraph = bpy.context.evaluated_depsgraph_get()
    evaluated = live.part_objects(root)["body"].evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    co = np.empty(len(mesh.vertices) * 3, np.float32)
    mesh.vertices.foreach_get("co", co)
    evaluated.to_mesh_clear()
    return co.reshape(-1, 3)


def _angle(a, b) -> float:
    c = np.dot(a, b) / (np.linalg.norm(a) * np.linalg.norm(b))
    return math.degrees(math.acos(min(max(c, -1.0), 1.0)))


@pytest.fixture
def session_guard(installed):
    """Whatever a test leaves running is stopped (the port and timer freed)."""
    yield
    panel = _panel()
    if panel.running():
        panel.stop()


def test_panel_settings_and_operators_register(installed):
    import bpy

    assert bpy.types.AVATAR_PT_mocap.bl_order == 3
    assert hasattr(bpy.ops.avatar, "mocap_start") and hasattr(bpy.ops.avatar, "mocap_stop")
    settings = bpy.context.scene.avatar_mocap
    assert (settings.source, settings.port) == ("VMC", 39539)
    settings.source = "BVH"  # the port follows the source while it is a default one
    assert settings.port == 7001
    settings.source = "KEYPOINTS"
    assert settings.port == 39540
    settings.port = 40000
    settings.source = "VMC"  # a port of the user's own stays
    assert settings.port == 40000
    settings.port = 39539


def test_an_independent_vmc_sender_drives_the_pose_bones(human, session_guard):
    import bpy

    panel = _panel()
    port = _free_port()
    _configure(bpy.context.scene, port)
    human.location = (0.5, 0.2, 0.0)  # poses are the character's own, wherever it stands
    names = _skeleton(human).names
    assert bpy.ops.avatar.mocap_start() == {"FINISHED"}
    assert panel.running() and bpy.app.timers.is_registered(panel.tick)
    skeleton = _skeleton(human)
    straight = _library_pose(skeleton, _frame())
    bent = _library_pose(skeleton, _frame(lower=BEND))
    sender = Sender(port, _frame())
    sender.start()
    try:
        assert _tick_until(lambda: _matches(human, names, *straight))
        shoulder, elbow, wrist = _heads(human, "upperarm01.L", "lowerarm01.L", "wrist.L")
        skin = _body_vertices(human)
        sender.frame = _frame(lower=BEND)
        assert _tick_until(lambda: _matches(human, names, *bent))
        shoulder2, elbow2, wrist2 = _heads(human, "upperarm01.L", "lowerarm01.L", "wrist.L")
        skin2 = _body_vertices(human)
    finally:
        sender.stop()
    # Blender's own evaluation of the pose, against the spec (not the library):
    # the upper arm did not move, the forearm turned 90 degrees about the vertical and
    # now points forward (-Y, where an Avatar faces); the hips are where the sender put them
    np.testing.assert_allclose([shoulder2, elbow2], [shoulder, elbow], atol=1e-5)
    before, after = wrist - elbow, wrist2 - elbow2
    assert _angle(before, after) == pytest.approx(90.0, abs=0.05)
    axis = np.cross(before, after)
    assert axis[2] / np.linalg.norm(axis) < -0.999  # a turn about -Z: +X (left) -> -Y
    assert after[1] / np.linalg.norm(after) < -0.99
    # in the character's own space (it stands wherever the 3D cursor was)
    np.testing.assert_allclose(human.pose.bones["root"].head, [0.0, -0.2, 0.95], atol=1e-4)
    # the skin follows (the armature deforms it in the evaluated scene): the left hand
    # swings forward, the rest of the body stays
    moved = np.linalg.norm(skin2 - skin, axis=1)
    assert moved.max() > 0.3 and np.median(moved) < 1e-4
    hand = moved > 0.1
    assert np.all(skin2[hand, 0] > 0.1) and np.mean(skin2[hand, 1] - skin[hand, 1]) < -0.1
    stats = panel._LIVE.session.stats()
    assert stats.frames >= 2 and stats.dropped_total == 0
    line = panel.stop()
    assert "dropped" in line and not bpy.app.timers.is_registered(panel.tick)


def test_recording_keys_one_frame_per_received_frame(human, session_guard):
    """Bundles at 50 Hz on the sender's clock, the elbow bending 3 degrees a frame: Stop
    makes an Action with one key per received frame, at the sender's rate, whose values
    are the library's conversion of each frame."""
    import bpy

    from avatar.blender import action as action_bridge

    panel = _panel()
    port = _free_port()
    _configure(bpy.context.scene, port, record=True)
    assert bpy.ops.avatar.mocap_start() == {"FINISHED"}
    skeleton = _skeleton(human)
    count = 30
    frames = []
    for i in range(count):
        half = math.radians(3.0 * i) / 2
        frames.append(_frame(lower=[0.0, math.sin(half), 0.0, math.cos(half)], t=i / 50))

    def send():
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        for frame in frames:
            bundle = OscBundleBuilder(IMMEDIATELY)
            for address, args in frame:
                message = OscMessageBuilder(address)
                for a in args:
                    message.add_arg(a)
                bundle.add_content(message.build())
            sock.sendto(bundle.build().dgram, ("127.0.0.1", port))
            time.sleep(0.004)
        sock.close()

    thread = threading.Thread(target=send, daemon=True)
    thread.start()
    assert _tick_until(lambda: panel._LIVE.session.stats().frames == count)
    thread.join()
    panel.tick()
    assert len(panel._LIVE.session.take) == count
    assert bpy.ops.avatar.mocap_stop() == {"FINISHED"}
    act = human.animation_data.action
    assert act is not None and act.name.startswith(human.name)
    curves = action_bridge.action_curves(act)
    forearm = [c for c in curves if c.data_path == 'pose.bones["lowerarm01.L"].rotation_quaternion']
    assert len(forearm) == 4
    for curve in curves:
        assert len(curve.keyframe_points) == count
    assert bpy.context.scene.render.fps / bpy.context.scene.render.fps_base == pytest.approx(50)
    keyed = np.array([[c.evaluate(1 + i) for c in sorted(forearm, key=lambda c: c.array_index)]
                      for i in range(count)])  # fmt: skip
    j = skeleton.names.index("lowerarm01.L")
    want = np.array([_library_pose(skeleton, f)[0][j] for f in frames])
    np.testing.assert_allclose(np.abs(np.sum(keyed * want, axis=1)), 1.0, atol=1e-5)


def _osc(address, args, types=None):
    m = OscMessageBuilder(address)
    for k, a in enumerate(args):
        m.add_arg(a, types[k] if types else None)
    return m.build().dgram


def _bundle(*datagrams_of_messages):
    b = OscBundleBuilder(IMMEDIATELY)
    for address, args in datagrams_of_messages:
        m = OscMessageBuilder(address)
        for a in args:
            m.add_arg(a)
        b.add_content(m.build())
    return b.build().dgram


def test_fuzzed_packets_are_counted_as_dropped_and_the_operator_keeps_running(human, session_guard):
    import bpy

    panel = _panel()
    port = _free_port()
    _configure(bpy.context.scene, port)
    assert bpy.ops.avatar.mocap_start() == {"FINISHED"}
    rng = np.random.default_rng(11)
    nan = float("nan")
    bad = [
        _osc("/VMC/Ext/Bone/Pos", ["LeftLowerArm", nan, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]),
        _osc("/VMC/Ext/Bone/Pos", ["LeftLowerArm", 0.0, 0.0, 0.0, nan, nan, nan, nan]),
        _osc("/VMC/Ext/Bone/Pos", [7, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]),  # wrong type
        _osc("/VMC/Ext/Bone/Pos", ["LeftLowerArm", "a", "b"]),
        _osc("/VMC/Ext/Root/Pos", ["root", float("inf"), 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]),
        _osc("/VMC/Ext/T", ["yesterday"]),
        _bundle(
            *[("/VMC/Ext/Bone/Pos", ["Head", 0.0, 0.1, 0.0, *IDENTITY])] * 600, ("/VMC/Ext/OK", [1])
        ),  # fmt: skip  # a huge count
        b"#bundle\x00" + b"\x00" * 8 + (2**31 - 1).to_bytes(4, "big") + b"abc",
        *[rng.bytes(int(rng.integers(1, 600))) for _ in range(300)],
    ]
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    for i, data in enumerate(bad):
        sock.sendto(data, ("127.0.0.1", port))
        if i % 25 == 0:
            assert panel.tick() == pytest.approx(panel.INTERVAL)
            time.sleep(0.002)
    assert _tick_until(lambda: panel._LIVE.session.stats().packets >= len(bad))
    stats = panel._LIVE.session.stats()
    assert stats.frames == 0
    assert stats.dropped_total >= len(bad)
    assert {"malformed", "bad_message", "oversize"} <= set(stats.dropped)
    # the panel shows these numbers
    lines = []

    class Layout:  # collects what the panel's statistics box writes
        def label(self, text="", icon="NONE"):
            lines.append(text)

    panel._draw_stats(Layout(), panel._LIVE)
    assert f"Dropped: {stats.dropped_total}" in " ".join(lines)
    assert any(line.startswith("Latency:") for line in lines)
    # still alive: a good frame drives the character
    names = _skeleton(human).names
    bent = _library_pose(_skeleton(human), _frame(lower=BEND))
    sender = Sender(port, _frame(lower=BEND))
    sender.start()
    try:
        assert _tick_until(lambda: _matches(human, names, *bent))
    finally:
        sender.stop()
        sock.close()
    assert bpy.app.timers.is_registered(panel.tick)


def test_a_port_in_use_is_a_one_line_error(human, session_guard):
    import bpy

    panel = _panel()
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as busy:
        busy.bind(("127.0.0.1", 0))
        _configure(bpy.context.scene, busy.getsockname()[1])
        modes = [b.rotation_mode for b in human.pose.bones]
        with pytest.raises(RuntimeError, match="cannot listen on 127.0.0.1:.*in use") as err:
            bpy.ops.avatar.mocap_start()
    assert "\n" not in str(err.value).strip().split("Error: ", 1)[-1].strip()
    assert not panel.running() and not bpy.app.timers.is_registered(panel.tick)
    assert [b.rotation_mode for b in human.pose.bones] == modes


def test_no_bvh_server_is_a_one_line_error(human, session_guard):
    import bpy

    _configure(bpy.context.scene, _free_port(socket.SOCK_STREAM), source="BVH")
    with pytest.raises(RuntimeError, match="cannot connect to 127.0.0.1"):
        bpy.ops.avatar.mocap_start()
    assert not _panel().running()


def test_a_rename_or_an_undone_tag_keeps_the_session_running(human, session_guard):
    import bpy

    panel = _panel()
    _configure(bpy.context.scene, _free_port())
    assert bpy.ops.avatar.mocap_start() == {"FINISHED"}
    human.name = "Renamed"
    assert panel.tick() == pytest.approx(panel.INTERVAL)
    assert panel._LIVE.armature == "Renamed"
    del human[panel.TAG_KEY]  # what an undo to before Start does to the tag
    assert panel.tick() == pytest.approx(panel.INTERVAL)
    assert human.get(panel.TAG_KEY) == panel._LIVE.tag
    assert bpy.ops.avatar.mocap_stop() == {"FINISHED"}
    assert panel.TAG_KEY not in human.keys()


def test_deleting_the_character_stops_the_timer_cleanly(human, session_guard):
    import bpy

    from avatar.blender import character

    panel = _panel()
    port = _free_port()
    _configure(bpy.context.scene, port, record=True)
    assert bpy.ops.avatar.mocap_start() == {"FINISHED"}
    sender = Sender(port, _frame(lower=BEND, t=None))
    sender.start()
    try:
        assert _tick_until(lambda: len(panel._LIVE.session.take) > 0)
        character.remove(human)
        assert panel.tick() is None  # the timer ends itself
    finally:
        sender.stop()
    assert not panel.running() and not bpy.app.timers.is_registered(panel.tick)
    assert "deleted" in panel._MESSAGE[0]
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as again:
        again.bind(("127.0.0.1", port))  # the socket was closed


def test_stop_and_release_free_the_port_and_the_timer(human, session_guard):
    import bpy

    panel = _panel()
    port = _free_port()
    _configure(bpy.context.scene, port)
    held = bpy.data.actions.new("user's action")
    human.animation_data_create()
    human.animation_data.action = held
    assert bpy.ops.avatar.mocap_start() == {"FINISHED"}
    assert human.animation_data.action is None  # detached while live poses drive the bones
    with pytest.raises(RuntimeError, match="already running|poll"):
        bpy.ops.avatar.mocap_start()
    assert bpy.ops.avatar.mocap_stop() == {"FINISHED"}
    assert human.animation_data.action == held  # nothing recorded: the user's action is back
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as again:
        again.bind(("127.0.0.1", port))
    # a take replaces the user's action on the armature; the old one keeps a fake user
    bpy.context.scene.avatar_mocap.record = True
    assert bpy.ops.avatar.mocap_start() == {"FINISHED"}
    sender = Sender(port, _frame(lower=BEND))
    sender.start()
    try:
        assert _tick_until(lambda: len(panel._LIVE.session.take) > 0)
    finally:
        sender.stop()
    assert bpy.ops.avatar.mocap_stop() == {"FINISHED"}
    assert human.animation_data.action != held and held.use_fake_user
    assert "kept with a fake user" in panel._MESSAGE[0]
    bpy.context.scene.avatar_mocap.record = False
    # release() (the add-on's unregister) stops a running session the same way
    assert bpy.ops.avatar.mocap_start() == {"FINISHED"}
    panel.release()
    assert not panel.running() and not bpy.app.timers.is_registered(panel.tick)
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as again:
        again.bind(("127.0.0.1", port))
    # and the port can be listened on again by a new session
    assert bpy.ops.avatar.mocap_start() == {"FINISHED"}
    assert bpy.ops.avatar.mocap_stop() == {"FINISHED"}


def test_bake_garments_rebuilds_the_character_playing_the_take(human, session_guard, tmp_path):
    """Record with Bake Garments on a dressed character: Stop saves the take as BVH and
    applies it as the Motion panel does (the garments get per-frame corrections)."""
    import json

    import bpy

    from avatar.blender import action as action_bridge
    from avatar.blender import live

    panel = _panel()
    assert bpy.ops.avatar.wear(name="tshirt") == {"FINISHED"}
    name = human.name
    port = _free_port()
    _configure(bpy.context.scene, port, record=True)
    bpy.context.scene.avatar_mocap.bake_garments = True
    try:
        assert bpy.ops.avatar.mocap_start() == {"FINISHED"}
        count = 8
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            for i in range(count):
                half = math.radians(10.0 * i) / 2
                frame = _frame(lower=[0.0, math.sin(half), 0.0, math.cos(half)], t=i / 30)
                sock.sendto(_bundle(*frame), ("127.0.0.1", port))
                time.sleep(0.003)
        assert _tick_until(lambda: len(panel._LIVE.session.take) == count)
        assert bpy.ops.avatar.mocap_stop() == {"FINISHED"}
    finally:
        bpy.context.scene.avatar_mocap.bake_garments = False
    assert "garments baked" in panel._MESSAGE[0], panel._MESSAGE[0]
    root = bpy.data.objects[name]
    motion = json.loads(root["avatar_motion"])
    assert motion["path"].endswith(".bvh")
    curves = action_bridge.action_curves(root.animation_data.action)
    assert {len(c.keyframe_points) for c in curves} == {count}
    tshirt = live.part_objects(root)["tshirt"]
    assert tshirt.data.shape_keys is not None  # the per-frame corrections


def _serve_lines(lines, delay=0.003):
    """A one-client TCP server (Axis Neuron's role) sending ``lines``; returns its port."""
    server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    server.bind(("127.0.0.1", 0))
    server.listen(1)

    def serve():
        conn, _ = server.accept()
        with conn:
            for line in lines:
                conn.sendall(line.encode() + b"\n")
                time.sleep(delay)
            time.sleep(1.0)
        server.close()

    threading.Thread(target=serve, daemon=True).start()
    return server.getsockname()[1]


def test_a_bvh_stream_without_header_drives_the_character_with_the_skeleton_file(
    human, session_guard
):
    """Frame lines only (the server sends no HIERARCHY), the skeleton from the panel's file:
    every frame arrives and is recorded; a skeleton file that is not there is one line."""
    import bpy

    walk = test_extension.WALK
    if not walk.is_file():
        pytest.skip("fixture BVH clip not found")
    panel = _panel()
    settings = bpy.context.scene.avatar_mocap
    settings.bvh_header = str(walk.with_name("no such file.bvh"))
    _configure(bpy.context.scene, _serve_lines([]), source="BVH", record=True)
    with pytest.raises(RuntimeError, match="cannot read the stream's skeleton"):
        bpy.ops.avatar.mocap_start()
    lines = walk.read_text().split("MOTION", 1)[1].strip().splitlines()[2:22]
    settings.bvh_header = str(walk)
    _configure(bpy.context.scene, _serve_lines(lines), source="BVH", record=True)
    try:
        assert bpy.ops.avatar.mocap_start() == {"FINISHED"}
        assert _tick_until(lambda: len(panel._LIVE.session.take) == len(lines))
        assert panel._LIVE.session.stats().dropped_total == 0
        assert bpy.ops.avatar.mocap_stop() == {"FINISHED"}
    finally:
        settings.bvh_header = ""
    assert f"{len(lines)} frames" in panel._MESSAGE[0]


def test_a_keypoints_stream_drives_the_character(human, session_guard):
    import bpy

    from avatar.mocap import keypoint_stream, keypoints
    from avatar.rig.skeleton import Animation

    panel = _panel()
    port = _free_port()
    _configure(bpy.context.scene, port, source="KEYPOINTS")
    bpy.context.scene.avatar_mocap.keypoint_set = "coco17"
    skeleton = _skeleton(human)
    rig = keypoints.bind("coco17", skeleton)
    # the left forearm bent 90 degrees forward at the elbow, as keypoints
    rot = np.tile([1.0, 0.0, 0.0, 0.0], (1, len(skeleton.names), 1))
    j = skeleton.index("lowerarm01.L")
    rot[0, j] = [S, S, 0.0, 0.0]
    points = rig.positions(Animation(rot, np.zeros((1, len(skeleton.names), 3)), 30.0,
                                     skeleton.names))[0]  # fmt: skip
    assert bpy.ops.avatar.mocap_start() == {"FINISHED"}
    names = skeleton.names
    rest = _pose_bones(human, names)[0].copy()
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        for i in range(10):
            sock.sendto(keypoint_stream.encode(i, points, None, i / 30, "coco17", "avatar"),
                        ("127.0.0.1", port))  # fmt: skip
            time.sleep(0.003)
    assert _tick_until(lambda: panel._LIVE.session.stats().frames >= 1)
    panel.tick()
    got = _pose_bones(human, names)[0]
    assert np.abs(np.sum(got[j] * rest[j])) < 0.99  # the forearm turned
    # ... to where the keypoints put it: elbow -> wrist along the streamed one
    elbow, wrist = _heads(human, "lowerarm01.L", "wrist.L")
    k = rig.keypoints.index
    assert _angle(wrist - elbow, points[k("left_wrist")] - points[k("left_elbow")]) < 5.0
    assert panel._LIVE.session.stats().dropped_total == 0
    assert bpy.ops.avatar.mocap_stop() == {"FINISHED"}

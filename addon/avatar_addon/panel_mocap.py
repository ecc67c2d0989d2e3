"""Mocap panel: drive the active character live from VMC, BVH over TCP or keypoints.

Start opens the source (``avatar.mocap.session.LiveSession``: a socket on a thread, never
blocking) and registers ``tick`` with ``bpy.app.timers`` (60 Hz): each tick takes the
newest pose and writes it into the armature's pose bones in two array writes
(``avatar.blender.mocap_drive.PoseWriter``). With Record on, every frame the sender
completed is kept and Stop keys them into a new Action, one key per frame at the sender's
rate; with Bake Garments it then saves the take as BVH and rebuilds the character playing
it, as the Motion panel's Apply does (garments with per-frame corrections). Stop (or
``release()`` when the add-on is disabled) closes the socket, removes the timer and
writes the take. If the character disappears the timer stops itself.

Headless scripts, where timers do not run, call ``tick()`` themselves.
"""

import logging
import time
import uuid

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, StringProperty

from .operators import INSTALL_HINT, root_of

log = logging.getLogger(__name__)

INTERVAL = 1.0 / 60.0  # s between ticks: one display frame
REDRAW_EVERY = 0.25  # s between redraws of the statistics
TAG_KEY = "avatar_mocap_live"  # on the driven root while a session runs (found after a rename)
DEFAULT_PORTS = {"VMC": 39539, "BVH": 7001, "KEYPOINTS": 39540}  # = session.DEFAULT_PORTS
KEYPOINT_SETS = ("mediapipe33", "coco17", "h36m17", "openpose25")  # keypoints.shipped()
SMOOTHING_HELP = (
    "One Euro filter strength: 0 off; 0.5 the filter's defaults (1.5 Hz cutoff at rest, "
    "5 Hz per m/s: about 106 ms lag on a still joint, 24 ms at 1 m/s); 1 the strongest "
    "(0.3 Hz at rest). Rotation streams are filtered per bone, keypoints before solving"
)


def _source_changed(self, context):
    if self.port in DEFAULT_PORTS.values():  # the user's own port stays
        self.port = DEFAULT_PORTS[self.source]


class AvatarMocapSettings(bpy.types.PropertyGroup):
    source: EnumProperty(
        name="Source",
        items=[
            ("VMC", "VMC", "VMC protocol (OSC over UDP): VSeeFace, XR Animator, Warudo, ..."),
            ("BVH", "BVH over TCP", "Connect to a BVH-over-TCP server (Axis Neuron style)"),
            ("KEYPOINTS", "Keypoints", "The JSON keypoints stream over UDP (docs/mocap.md)"),
        ],
        default="VMC",
        update=_source_changed,
    )
    host: StringProperty(
        name="Host",
        default="",
        description="VMC and keypoints: the address to listen on (empty: every interface); "
        "BVH: the server to connect to (empty: 127.0.0.1)",
    )
    port: IntProperty(name="Port", default=39539, min=0, max=65535,
                      description="UDP port to listen on (VMC 39539, keypoints 39540) or the "
                      "BVH server's TCP port (Axis Neuron: 7001)")  # fmt: skip
    keypoint_set: EnumProperty(name="Keypoints", default="mediapipe33",
                               items=[(k, k, f"{k} keypoints") for k in KEYPOINT_SETS])  # fmt: skip
    bvh_header: StringProperty(name="Skeleton", subtype="FILE_PATH", default="",
                               description="A BVH file with the stream's skeleton, for "
                               "servers that send no header")  # fmt: skip
    smoothing: FloatProperty(name="Smoothing", min=0.0, max=1.0, default=0.3,
                             subtype="FACTOR", description=SMOOTHING_HELP)  # fmt: skip
    record: BoolProperty(name="Record", default=False,
                         description="Keep every received frame; Stop keys them into a new "
                         "Action (one key per frame, at the sender's rate)")  # fmt: skip
    bake_garments: BoolProperty(
        name="Bake Garments",
        default=False,
        description="On Stop, save the take as BVH (mocap_takes/ beside the .blend file, or "
        "the system's temporary folder) and apply it as the Motion panel does: the character "
        "is rebuilt playing it, its garments with per-frame corrections (the exact resolve: "
        "about 45 ms a frame, so Stop waits)",
    )


class _Live:
    """The running session: library objects (``session``: avatar.mocap.session.LiveSession,
    ``writer``: avatar.blender.mocap_drive.PoseWriter) and the names of what it drives.
    (A plain class: Blender's extension loader leaves dataclasses without their module.)"""

    def __init__(self, session, writer, armature, scene, tag, held_action):
        self.session = session
        self.writer = writer
        self.armature = armature
        self.scene = scene
        self.tag = tag
        self.held_action = held_action
        self.redrawn = 0.0


_LIVE: "_Live | None" = None
_MESSAGE = [""]  # the last session's closing line, shown in the panel


def running() -> bool:
    return _LIVE is not None


def _settings_of(scene):
    from avatar.mocap.session import LiveSettings

    s = scene.avatar_mocap
    header = None
    if s.source == "BVH" and s.bvh_header.strip():
        header = _read_header(bpy.path.abspath(s.bvh_header))
    return LiveSettings(s.source.lower(), s.host.strip(), int(s.port), float(s.smoothing),
                        s.keypoint_set, header)  # fmt: skip


def _read_header(path):
    from avatar.errors import ParameterError

    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            return f.read()
    except OSError as exc:
        raise ParameterError(f"{path}: cannot read the stream's skeleton: {exc.strerror}") from None


def start(scene, root) -> str:
    """Open the scene's source and drive ``root``'s armature from it; returns a report line.
    Raises AvatarError (port in use, no server, ...) with nothing changed."""
    global _LIVE
    from avatar.blender import live as live_bridge
    from avatar.blender import mocap_drive
    from avatar.errors import AvatarError
    from avatar.mocap.session import LiveSession

    if _LIVE is not None:
        raise AvatarError("a mocap session is already running: stop it first")
    if root is None or root.type != "ARMATURE":
        raise AvatarError("select a rigged Avatar character first")
    skeleton = live_bridge.geometry(live_bridge.recipe_of(root), dress=False).body.skeleton
    session = LiveSession(skeleton, _settings_of(scene))  # raises before anything changes
    try:
        writer = mocap_drive.PoseWriter(root, skeleton.names)
    except Exception:
        session.close()
        raise
    tag = uuid.uuid4().hex
    root[TAG_KEY] = tag
    _LIVE = _Live(session, writer, root.name, scene.name, tag, mocap_drive.hold_action(root))
    _MESSAGE[0] = ""
    if not bpy.app.timers.is_registered(tick):
        # persistent: a file load keeps the timer, which then finds the character gone
        # and closes the socket instead of leaving it open with no timer
        bpy.app.timers.register(tick, first_interval=0.0, persistent=True)
    host, port = session.address
    return f"Mocap: {root.name} driven from {scene.avatar_mocap.source} on {host}:{port}"


def _armature(live):
    """The driven armature: by name and tag; else by tag (it was renamed); else by name
    alone (an undo went back past Start and took the tag: put it back); else None."""
    named = bpy.data.objects.get(live.armature)
    if named is not None and named.get(TAG_KEY) == live.tag:
        return named
    obj = next((o for o in bpy.data.objects if o.get(TAG_KEY) == live.tag), None)
    if obj is not None:
        live.armature = obj.name
        return obj
    if named is not None and named.type == "ARMATURE" and TAG_KEY not in named.keys():
        named[TAG_KEY] = live.tag
        return named
    return None


def tick():
    """One timer step: the newest pose onto the armature. Returns the next interval, or
    None (the timer ends) once the session is gone or its character was deleted."""
    live = _LIVE
    if live is None:
        return None
    try:
        arm = _armature(live)
        if arm is None or not live.writer.fits(arm):
            stop("Mocap stopped: the character was deleted")
            return None
        scene = bpy.data.scenes.get(live.scene)
        recording = bool(scene is not None and scene.avatar_mocap.record)
        pose = live.session.step(recording)
        if pose is not None:
            live.writer.write(arm, pose.rotations, pose.translations)
        now = time.monotonic()
        if now - live.redrawn > REDRAW_EVERY:
            live.redrawn = now
            _redraw()
    except Exception as exc:  # noqa: BLE001 - a timer must never raise into Blender
        log.exception("Avatar mocap: tick failed")
        stop(f"Mocap stopped: {exc}")
        return None
    return INTERVAL


def stop(message: str | None = None, bake: bool = True) -> str:
    """End the session: socket closed, timer removed, the take (if any) keyed into a new
    Action on the armature (and, with ``bake`` and the scene's Bake Garments, applied as a
    motion with garment corrections). Returns the closing line (also shown in the panel)."""
    global _LIVE
    live, _LIVE = _LIVE, None
    if bpy.app.timers.is_registered(tick):
        bpy.app.timers.unregister(tick)
    if live is None:
        return message or "Mocap: not running"
    from avatar.blender import mocap_drive

    take = live.session.close()
    arm = _armature(live)
    line = message or "Mocap stopped"
    if arm is not None:
        del arm[TAG_KEY]
        if take is not None:
            scene = bpy.data.scenes.get(live.scene)
            act = mocap_drive.write_take(arm, take, f"{arm.name} take", scene=scene)
            line += f"; {take.frames} frames at {take.fps:g} fps keyed into '{act.name}'"
            if mocap_drive.keep_action(live.held_action):
                line += f" ('{live.held_action}' kept with a fake user)"
            if bake and scene is not None and scene.avatar_mocap.bake_garments:
                line += _bake(arm, live.session.skeleton, take)
        else:
            mocap_drive.restore_action(arm, live.held_action)
    elif take is not None:
        line += f"; the {take.frames}-frame take was lost with the character"
    stats = live.session.stats()
    line += f" ({stats.frames} frames received, {stats.dropped_total} dropped)"
    _MESSAGE[0] = line
    log.info("%s", line)
    _redraw()
    return line


def _bake(arm, skeleton, take) -> str:
    """Save ``take`` as BVH and rebuild the character playing it (the Motion panel's Apply:
    garments get per-frame corrections); returns the report's tail."""
    from avatar.blender import character
    from avatar.errors import AvatarError
    from avatar.io import bvh

    from . import live as live_props

    if not character.recipe_of(arm).get("clothes"):
        return "; nothing worn, no garments to bake"
    path = _take_path(arm.name)
    try:
        bvh.save(path, skeleton, take)
        motion = {"path": path, "frames": None, "fps": None, "in_place": False}
        built, _ = character.apply_motion(arm, motion)
    except (AvatarError, OSError) as exc:
        return f"; garments not baked: {exc}"
    live_props.sync_from_recipe(built.root)
    return f"; garments baked (take saved as {path})"


def _take_path(name: str) -> str:
    """A new BVH path for a take: mocap_takes/ beside the .blend file, else in the
    system's temporary folder (an unsaved file has no folder of its own)."""
    import os
    import tempfile

    folder = bpy.path.abspath("//mocap_takes") if bpy.data.filepath else None
    folder = folder or os.path.join(tempfile.gettempdir(), "avatar_mocap_takes")
    os.makedirs(folder, exist_ok=True)
    stamp = time.strftime("%Y%m%d-%H%M%S")
    base = bpy.path.clean_name(name)
    path = os.path.join(folder, f"{base}-{stamp}.bvh")
    count = 1
    while os.path.exists(path):
        count += 1
        path = os.path.join(folder, f"{base}-{stamp}-{count}.bvh")
    return path


def _redraw():
    wm = bpy.context.window_manager
    for window in wm.windows if wm is not None else ():
        for area in window.screen.areas:
            if area.type == "VIEW_3D":
                area.tag_redraw()


def release():
    """On unregister: stop the session (the take is still keyed; garments not baked)."""
    if _LIVE is not None:
        try:
            stop("Mocap stopped: the add-on was disabled", bake=False)
        except Exception:  # noqa: BLE001 - unregistering must go on
            log.exception("Avatar mocap: stopping on unregister failed")
    if bpy.app.timers.is_registered(tick):
        bpy.app.timers.unregister(tick)


class AVATAR_OT_mocap_start(bpy.types.Operator):
    """Drive the active character live from the chosen source"""

    bl_idname = "avatar.mocap_start"
    bl_label = "Start"

    @classmethod
    def poll(cls, context):
        root = root_of(context.object)
        return _LIVE is None and root is not None and root.type == "ARMATURE"

    def execute(self, context):
        try:
            from avatar.errors import AvatarError
        except ImportError:
            self.report({"ERROR"}, INSTALL_HINT)
            return {"CANCELLED"}
        try:
            line = start(context.scene, root_of(context.object))
        except AvatarError as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        except ModuleNotFoundError as exc:  # python-osc (the ``vmc`` extra) not installed
            self.report({"ERROR"}, f"live capture needs the {exc.name!r} package (python-osc)")
            return {"CANCELLED"}
        self.report({"INFO"}, line)
        return {"FINISHED"}


class AVATAR_OT_mocap_stop(bpy.types.Operator):
    """Stop live capture: close the socket and key the recorded take into an Action"""

    bl_idname = "avatar.mocap_stop"
    bl_label = "Stop"

    @classmethod
    def poll(cls, context):
        return _LIVE is not None

    def execute(self, context):
        self.report({"INFO"}, stop())
        return {"FINISHED"}


class AVATAR_PT_mocap(bpy.types.Panel):
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Avatar"
    bl_label = "Mocap"
    bl_idname = "AVATAR_PT_mocap"
    bl_order = 3

    def draw(self, context):
        settings = context.scene.avatar_mocap
        layout = self.layout
        column = layout.column()
        column.enabled = _LIVE is None  # a session keeps the settings it started with
        column.prop(settings, "source")
        row = column.row(align=True)
        row.prop(settings, "host")
        row.prop(settings, "port")
        if settings.source == "KEYPOINTS":
            column.prop(settings, "keypoint_set")
        if settings.source == "BVH":
            column.prop(settings, "bvh_header")
        column.prop(settings, "smoothing", slider=True)
        row = layout.row(align=True)
        row.prop(settings, "record", icon="REC")
        row.prop(settings, "bake_garments", icon="MOD_CLOTH")
        row = layout.row(align=True)
        row.scale_y = 1.3
        if _LIVE is None:
            row.operator("avatar.mocap_start", icon="PLAY")
            if _MESSAGE[0]:
                layout.label(text=_MESSAGE[0], icon="INFO")
            return
        row.operator("avatar.mocap_stop", icon="PAUSE")
        _draw_stats(layout.box(), _LIVE)


def _draw_stats(box, live):
    stats = live.session.stats()
    host, port = live.session.address
    box.label(text=f"{live.armature} <- {host}:{port}", icon="CON_ARMATURE")
    box.label(text=f"{stats.rate:.0f} frames/s, {stats.packets} packets")
    reasons = ", ".join(f"{k} {v}" for k, v in sorted(stats.dropped.items()))
    box.label(text=f"Dropped: {stats.dropped_total}" + (f" ({reasons})" if reasons else ""))
    box.label(text=f"Latency: {stats.latency_ms:.1f} ms")
    if len(live.session.take):
        box.label(text=f"Recorded: {len(live.session.take)} frames", icon="REC")


CLASSES = (AvatarMocapSettings, AVATAR_OT_mocap_start, AVATAR_OT_mocap_stop, AVATAR_PT_mocap)
POINTERS = {(bpy.types.Scene, "avatar_mocap"): AvatarMocapSettings}

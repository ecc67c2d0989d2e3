"""Keypoint sets (MediaPipe-33, COCO-17, Human3.6M-17, OpenPose BODY_25) and where each
keypoint sits on an Avatar rig.

A set is a JSON file in ``avatar/data/mocap/`` (or a user file of the same shape)::

    {"name": "coco17", "axes": "avatar", "reference_height": 1.66,
     "keypoints": [{"name": "nose", "on": "head", "offset": [0, -0.116, 0.003]},
                   {"name": "left_shoulder", "at": ["joint:upperarm.L"]}, ...]}

Each keypoint is a point of the rig, named by canonical roles (``avatar.motion.bonemap``):

- ``"at": ["joint:ROLE", ...]``: the head of the role's bone (first candidate the rig has);
  ``"end:ROLE"``: its tail; ``"mid:A|B|..."``: the mean of those heads;
- ``"on": ROLE`` with ``"offset"``: a point carried by that bone, ``offset`` metres from
  its head in the rest pose's axes (+X the character's left, -Y forward, +Z up) for a body
  ``reference_height`` tall (scaled to the rig's height); ``"fallback"`` is used when no
  ``at`` candidate exists on a rig;
- ``"solve": false`` keeps a point out of the solver (it is only reported).

Every keypoint is carried rigidly by one bone (``RigKeypoints.carriers``): the bone a joint
hangs from, or the bone an end or ``on`` point belongs to; its position in any pose is
``head + R_world @ offset``. The solver, the round-trip tests and the noise benchmark all
use these same positions.

``axes`` names the frame a producer of the set writes (see ``AXES``): points are turned
into Avatar's frame (metres, Z up, the character facing -Y, +X its left) once, by
``to_avatar``.
"""

from __future__ import annotations

import functools
import json
import os
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from avatar.errors import FormatError, ParameterError, unknown_name
from avatar.motion import bonemap
from avatar.rig import quaternion
from avatar.rig.kinematics import world_pose
from avatar.rig.skeleton import Animation, Skeleton

AXES: dict[str, np.ndarray] = {
    # Avatar's own frame: Z up, the subject faces -Y, +X is the subject's left.
    "avatar": np.eye(3),
    # A camera's frame, the subject facing it: x right in the image (the subject's left),
    # y down, z away from the camera (MediaPipe world landmarks, most 3D lifters).
    "camera": np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]]),
    # Y up, the subject facing +Z, +X the subject's left (glTF, three.js).
    "y-up": np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]),
}
"""Frame name -> (3, 3) rotation taking that frame's vectors to Avatar's (``M @ p``)."""


def to_avatar(points: np.ndarray, axes: str) -> np.ndarray:
    """(..., 3) points in frame ``axes`` (a name in ``AXES``) -> Avatar's frame."""
    if axes not in AXES:
        raise unknown_name("keypoint axes", axes, AXES)
    return np.asarray(points, dtype=np.float64) @ AXES[axes].T


@dataclass(frozen=True)
class KeypointSet:
    """A keypoint set as its file describes it (rig independent).

    names: K keypoint names, in the producer's index order.
    specs: K dicts (``at``/``on``/``offset``/``fallback``/``solve``), as in the file.
    axes: the frame producers write (a key of ``AXES``).
    reference_height: metres; ``offset`` values are for a body this tall.
    """

    name: str
    description: str
    names: tuple[str, ...]
    specs: tuple[dict, ...]
    axes: str
    reference_height: float

    def index(self, name: str) -> int:
        try:
            return self.names.index(name)
        except ValueError:
            raise unknown_name(f"{self.name} keypoint", name, self.names) from None


def shipped() -> tuple[str, ...]:
    """Names of the keypoint sets that ship with Avatar."""
    return tuple(sorted(_shipped_files()))


@functools.cache
def _shipped_files() -> dict[str, str]:
    folder = resources.files("avatar") / "data" / "mocap"
    out = {}
    for entry in folder.iterdir():
        if entry.name.endswith(".json") and not entry.name.startswith(("unity", "limits")):
            out[entry.name[:-5]] = entry.read_text(encoding="utf-8")
    return out


def load(name: str | os.PathLike[str]) -> KeypointSet:
    """A shipped set by name (``shipped()``) or a user's JSON file of the same shape."""
    files = _shipped_files()
    key = str(name)
    if key in files:
        return parse(files[key], f"{key}.json")
    if Path(key).suffix == ".json" and Path(key).is_file():
        return parse(Path(key).read_text(encoding="utf-8"), key)
    raise unknown_name("keypoint set", key, files)


def parse(text: str, path: str) -> KeypointSet:
    """A keypoint set file's text, checked (FormatError on anything malformed)."""
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise FormatError(path, exc.lineno, exc.msg) from None
    points = data.get("keypoints") if isinstance(data, dict) else None
    if not isinstance(points, list) or not points:
        raise FormatError(path, 0, 'a keypoint set needs {"keypoints": [...]}')
    names, specs = [], []
    for i, spec in enumerate(points):
        if not isinstance(spec, dict) or not isinstance(spec.get("name"), str):
            raise FormatError(path, 0, f"keypoint {i}: needs a name")
        _check_spec(spec, path, spec["name"])
        names.append(spec["name"])
        specs.append(spec)
    axes = data.get("axes", "avatar")
    if axes not in AXES:
        raise FormatError(path, 0, str(unknown_name("axes", axes, AXES)))
    return KeypointSet(str(data.get("name", Path(path).stem)), str(data.get("description", "")),
                       tuple(names), tuple(specs), axes,
                       float(data.get("reference_height", 1.66)))  # fmt: skip


def _check_spec(spec: dict, path: str, name: str) -> None:
    anchors = spec.get("at", [])
    if isinstance(anchors, str) or not all(isinstance(a, str) for a in anchors):
        raise FormatError(path, 0, f"{name}: 'at' must be a list of anchors")
    for a in anchors:
        kind, _, roles = a.partition(":")
        if kind not in ("joint", "end", "mid"):
            raise FormatError(path, 0, f"{name}: anchor {a!r} is not joint:, end: or mid:")
        for role in roles.split("|"):
            if role not in bonemap.NEXT:
                raise FormatError(path, 0, f"{name}: {unknown_name('role', role, bonemap.NEXT)}")
    for inner in [spec] + ([spec["fallback"]] if "fallback" in spec else []):
        if "on" in inner and inner["on"] not in bonemap.NEXT:
            raise FormatError(path, 0, f"{name}: {unknown_name('role', inner['on'], bonemap.NEXT)}")
        offset = inner.get("offset", [0, 0, 0])
        if not (isinstance(offset, list) and len(offset) == 3):
            raise FormatError(path, 0, f"{name}: offset must be [x, y, z]")
    if not anchors and "on" not in spec:
        raise FormatError(path, 0, f"{name}: needs 'at' or 'on'")


@dataclass(frozen=True)
class RigKeypoints:
    """A keypoint set placed on one rig.

    carriers: (K,) int, the bone carrying each keypoint (-1: the rig lacks it); for a
        ``mid`` point, the deepest bone above all its joints.
    offsets: (K, 3) float64, each keypoint in its carrier's bone frame, from its head.
    solve: (K,) bool, keypoints the solver uses.
    rest: (K, 3) float64, the keypoints in the rest pose (metres).
    terms: (keypoint (N,), bone (N,), offset (N, 3), weight (N,)): exact positions are
        sums of weighted carried points (a ``mid`` point averages its joints, each carried
        by the bone it hangs from); one term per other keypoint.
    """

    keypoints: KeypointSet
    skeleton: Skeleton
    bmap: bonemap.BoneMap
    carriers: np.ndarray
    offsets: np.ndarray
    solve: np.ndarray
    rest: np.ndarray
    terms: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]

    def positions(self, animation: Animation) -> np.ndarray:
        """(T, K, 3) keypoint positions over an animation on this rig (NaN where absent)."""
        rot, heads = world_pose(self.skeleton, animation.rotations, animation.translations)
        return self.posed(rot, heads)

    def posed(self, world_rotations: np.ndarray, heads: np.ndarray) -> np.ndarray:
        """(..., K, 3) from world bone rotations (..., J, 4) and heads (..., J, 3)."""
        kp, bone, offset, weight = self.terms
        each = heads[..., bone, :] + quaternion.rotate(world_rotations[..., bone, :], offset)
        out = np.zeros(heads.shape[:-2] + (len(self.carriers), 3))
        np.add.at(out, (..., kp, slice(None)), each * weight[:, None])  # type: ignore[arg-type]
        out[..., self.carriers < 0, :] = np.nan
        return out


def bind(keypoints: KeypointSet | str, skeleton: Skeleton,
         bmap: bonemap.BoneMap | None = None) -> RigKeypoints:  # fmt: skip
    """Place a keypoint set on a rig (``bmap``: its bone map, detected when None).

    Raises ParameterError when the rig lacks the hips, shoulders or hips joints a solve needs.
    """
    kset = load(keypoints) if isinstance(keypoints, str) else keypoints
    bmap = bonemap.detect(skeleton) if bmap is None else bmap
    missing = [r for r in ("hips", "thigh.L", "thigh.R", "upperarm.L", "upperarm.R")
               if r not in bmap.bones]  # fmt: skip
    if missing:
        raise ParameterError(f"this rig lacks {', '.join(missing)}: no keypoints can drive it")
    scale = float(np.ptp(skeleton.heads[:, 2]) + 0.1) / kset.reference_height
    rest_rot = skeleton.rest[:, :3, :3]
    k = len(kset.names)
    carriers = np.full(k, -1)
    points = np.full((k, 3), np.nan)
    terms: list[tuple[int, int, np.ndarray, float]] = []
    for i, spec in enumerate(kset.specs):
        found = _place(spec, skeleton, bmap, scale)
        if found is None and "fallback" in spec:
            found = _place(spec["fallback"], skeleton, bmap, scale)
        if found is not None:
            carriers[i], points[i], parts = found
            terms += [(i, b, p, 1.0 / len(parts)) for b, p in parts]
    offsets = np.zeros((k, 3))
    ok = carriers >= 0
    c = carriers[ok]
    offsets[ok] = np.einsum("kba,kb->ka", rest_rot[c], points[ok] - skeleton.heads[c])
    solve = ok & np.array([bool(s.get("solve", True)) for s in kset.specs])
    tk = np.array([t[0] for t in terms], dtype=int)
    tb = np.array([t[1] for t in terms], dtype=int)
    tp = np.array([t[2] for t in terms]).reshape(-1, 3)
    to = np.einsum("kba,kb->ka", rest_rot[tb], tp - skeleton.heads[tb])
    tw = np.array([t[3] for t in terms])
    return RigKeypoints(kset, skeleton, bmap, carriers, offsets, solve, points, (tk, tb, to, tw))


def _place(spec: dict, skeleton: Skeleton, bmap: bonemap.BoneMap, scale: float):
    """(carrier bone, rest position, [(bone, rest point)] terms) of one keypoint spec on a
    rig, or None when the rig lacks its roles."""
    offset = np.asarray(spec.get("offset", [0.0, 0.0, 0.0]), dtype=np.float64) * scale
    if "on" in spec:
        j = bmap.bones.get(spec["on"])
        if j is None:
            return None
        point = skeleton.heads[j] + offset
        return j, point, [(j, point)]
    for anchor in spec.get("at", []):
        kind, _, names = anchor.partition(":")
        roles = names.split("|")
        if not all(r in bmap.bones for r in roles):
            continue
        bones = [bmap.bones[r] for r in roles]
        if kind == "end":
            point = skeleton.tails[bones[0]] + offset
            return bones[0], point, [(bones[0], point)]
        # a joint rides on the bone it hangs from
        parts = [(_hung_from(skeleton, b), skeleton.heads[b] + offset) for b in bones]
        point = np.mean([p for _, p in parts], axis=0)
        carrier = parts[0][0] if kind == "joint" else _common_carrier(skeleton, bones)
        return carrier, point, parts
    return None


def _hung_from(skeleton: Skeleton, bone: int) -> int:
    parent = int(skeleton.parents[bone])
    return parent if parent >= 0 else bone


def _common_carrier(skeleton: Skeleton, bones: list[int]) -> int:
    """The deepest bone above all of ``bones``' joints (what carries their mean)."""
    chains = []
    for b in bones:
        chain, j = [], int(skeleton.parents[b])
        while j >= 0:
            chain.append(j)
            j = int(skeleton.parents[j])
        chains.append(chain or [b])
    common = set(chains[0]).intersection(*chains[1:])
    return next(j for j in chains[0] if j in common) if common else bones[0]

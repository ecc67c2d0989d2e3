"""The pose library: built-in poses for any rig, and pose files from user folders.

    poselib.list_poses()                         # PoseEntry records, built-ins first
    pose = poselib.load("t-pose", skeleton)      # (1, J) Animation on that skeleton
    pose = poselib.load("sit01", skeleton, folders=["~/makehuman/v1py3/data/poses"])
    t_rest, motion = poselib.switch_rest(skeleton, motion, "t-pose")

Built-ins need no data and work on any humanoid rig (bone roles by ``bonemap.detect``):
``rest``; ``t-pose``, arms straight out sideways, horizontal; ``a-pose``, arms straight
and 45 degrees down; both with legs straight (hip to ankle as in the rest, without
forward bend). They are computed from the rig's rest geometry, not read from files.

Pose files: single-frame BVH (MakeHuman's CC0 poses, any convention; the first frame is
retargeted onto the rig) and MPFB pose JSON (``{"bone_rotations": {bone: [x, y, z]}}``,
Euler XYZ radians in bone-local space). Folders come from the ``folders`` arguments and
``$AVATAR_POSES_PATH`` (os.pathsep-separated), scanned recursively; a ``.meta`` file
beside a BVH (MakeHuman's ``name``/``tag``/``description`` lines) describes it.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Iterable
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from avatar.errors import FormatError, ParameterError, unknown_name
from avatar.io import bvh
from avatar.motion import bonemap, geometry
from avatar.motion.retarget import retarget
from avatar.rig import quaternion
from avatar.rig.poses import from_euler_map, rebase, rest_pose
from avatar.rig.skeleton import Animation, Skeleton

ENV_PATH = "AVATAR_POSES_PATH"
BUILT_IN = {
    "rest": "the rig's rest pose (MakeHuman rigs rest in an A-pose)",
    "a-pose": "arms straight, 45 degrees down; legs straight",
    "t-pose": "arms straight out sideways, horizontal; legs straight",
}
ARM_DROP = {"t-pose": 0.0, "a-pose": 45.0}  # degrees below horizontal
_UP = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class PoseEntry:
    """One pose of the library: name, where it comes from, a description."""

    name: str
    source: str  # "built-in", "bvh" or "mpfb"
    path: Path | None
    description: str = ""


def user_folders(folders: Iterable[str | os.PathLike[str]] = ()) -> list[Path]:
    """The pose folders to scan: ``folders`` then those in ``$AVATAR_POSES_PATH``."""
    env = [p for p in os.environ.get(ENV_PATH, "").split(os.pathsep) if p]
    return [Path(p).expanduser() for p in [*folders, *env]]


def list_poses(folders: Iterable[str | os.PathLike[str]] = ()) -> list[PoseEntry]:
    """Built-in poses, then every pose file in the user folders. A file whose name is
    taken (MPFB's per-rig ``default_fk/t-pose.json``, ``cmu_mb_fk/t-pose.json``) is listed
    as ``folder/name``; when that is taken too, the first one wins."""
    entries = [PoseEntry(n, "built-in", None, d) for n, d in BUILT_IN.items()]
    seen = set(BUILT_IN)
    for folder in user_folders(folders):
        for path in sorted(folder.rglob("*")) if folder.is_dir() else []:
            entry = _entry(path)
            if entry is None:
                continue
            if entry.name.lower() in seen:
                entry = replace(entry, name=f"{path.parent.name}/{entry.name}")
            if entry.name.lower() not in seen:
                seen.add(entry.name.lower())
                entries.append(entry)
    return entries


def _entry(path: Path) -> PoseEntry | None:
    suffix = path.suffix.lower()
    if suffix == ".bvh":
        return PoseEntry(path.stem, "bvh", path, _meta_description(path.with_suffix(".meta")))
    if suffix == ".json" and _is_mpfb_pose(path):
        return PoseEntry(path.stem, "mpfb", path, f"MPFB pose ({path.parent.name})")
    return None


def _meta_description(path: Path) -> str:
    """``name - description`` from a MakeHuman ``.meta`` file ("" when absent)."""
    if not path.is_file():
        return ""
    fields: dict[str, str] = {}
    for line in path.read_text(encoding="utf-8", errors="replace").splitlines():
        key, _, value = line.strip().partition(" ")
        fields.setdefault(key, value.strip())
    return " - ".join(v for v in (fields.get("name"), fields.get("description")) if v)


def _is_mpfb_pose(path: Path) -> bool:
    try:
        head = path.read_text(encoding="utf-8", errors="replace")[:4096]
    except OSError:
        return False
    return '"bone_rotations"' in head


def load(
    name_or_path: str | os.PathLike[str],
    skeleton: Skeleton,
    folders: Iterable[str | os.PathLike[str]] = (),
    reference: Callable[[], Skeleton] | None = None,
) -> Animation:
    """A pose on ``skeleton`` as a one-frame Animation (1, J).

    name_or_path: a built-in name, a pose name from the library, or a ``.bvh``/``.json``
        file. BVH poses are retargeted (first frame, hips kept over the rig's); MPFB JSON
        poses apply by bone name, or through ``reference()`` (the MakeHuman rig their
        bones name) and the retargeter when ``skeleton`` lacks those bones.
    Raises ParameterError for an unknown name (listing close ones), FormatError for a
    broken file.
    """
    key = str(name_or_path)
    if key.lower() in BUILT_IN:
        return built_in(skeleton, key.lower())
    path = Path(key).expanduser()
    if not path.is_file():
        entries = {e.name.lower(): e for e in list_poses(folders) if e.path is not None}
        entry = entries.get(key.lower())
        if entry is None or entry.path is None:
            raise unknown_name("pose", key, [e.name for e in list_poses(folders)])
        path = entry.path
    if path.suffix.lower() == ".bvh":
        return _from_bvh(path, skeleton)
    if path.suffix.lower() == ".json":
        return _from_mpfb(path, skeleton, reference)
    raise ParameterError(f"{path}: a pose file is .bvh or MPFB .json")


def _from_bvh(path: Path, skeleton: Skeleton) -> Animation:
    source, clip = bvh.load(path)
    pose, _ = retarget(source, clip, skeleton, frames=slice(0, 1), in_place=True,
                       fix_feet=False, measure=False)  # fmt: skip
    return pose


def _from_mpfb(path: Path, skeleton: Skeleton, reference: Callable[[], Skeleton] | None):
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise FormatError(str(path), exc.lineno, exc.msg) from None
    rotations = data.get("bone_rotations") if isinstance(data, dict) else None
    if not isinstance(rotations, dict):
        raise FormatError(str(path), 0, 'an MPFB pose needs {"bone_rotations": {...}}')
    known = sum(b in skeleton.names for b in rotations)
    if known >= len(rotations) / 2 or reference is None:
        if not known:
            raise ParameterError(f"{path}: none of its bones are in this rig")
        return from_euler_map(skeleton, rotations, data.get("bone_translations"))

    source = reference()
    pose = from_euler_map(source, rotations, data.get("bone_translations"))
    out, _ = retarget(source, pose, skeleton, in_place=True, fix_feet=False, measure=False)
    return out


def built_in(skeleton: Skeleton, name: str) -> Animation:
    """``rest``, ``t-pose`` or ``a-pose`` for any humanoid rig (see the module docstring)."""
    if name == "rest":
        return rest_pose(skeleton)
    if name not in ARM_DROP:
        raise unknown_name("built-in pose", name, BUILT_IN)
    return arms_out(skeleton, ARM_DROP[name])


def arms_out(skeleton: Skeleton, drop_degrees: float, bmap: bonemap.BoneMap | None = None,
             legs_down: bool = False):  # fmt: skip
    """(1, J) pose: both arms straight (upper arm, forearm and hand in one line), held out
    sideways ``drop_degrees`` below horizontal in the body's frontal plane; legs straight
    (hip to ankle in the rest's frontal plane; ``legs_down``: vertical and parallel, the
    spine and chest upright, as Unity's humanoid T-pose has them). Sideways is the rest
    pose's hip-to-hip line; other bones keep their rest relation."""
    bmap = bmap or bonemap.detect(skeleton)
    heads = skeleton.heads
    roles = bmap.bones
    if "thigh.L" in roles and "thigh.R" in roles:
        left = heads[roles["thigh.L"]] - heads[roles["thigh.R"]]
    else:
        left = np.array([1.0, 0.0, 0.0])  # Avatar's characters: left is +X
    left = geometry.unit(left - (left @ _UP) * _UP)
    forward = np.cross(_UP, left)
    a = np.radians(drop_degrees)
    want: dict[str, np.ndarray] = {}
    for side, sign in (("L", 1.0), ("R", -1.0)):
        arm = sign * np.cos(a) * left - np.sin(a) * _UP
        want.update({f"{r}.{side}": arm for r in ("upperarm", "forearm", "hand")})
        ends = [roles.get(f"{r}.{side}") for r in ("thigh", "foot")]
        if None not in ends:
            leg = heads[ends[1]] - heads[ends[0]]
            leg = -_UP if legs_down else geometry.unit(leg - (leg @ forward) * forward)
            want.update({f"thigh.{side}": leg, f"shin.{side}": leg})
    if legs_down:
        want.update({"spine": _UP, "chest": _UP})
    return aim(skeleton, bmap, want)


def aim(skeleton: Skeleton, bmap: bonemap.BoneMap, want: dict[str, np.ndarray]) -> Animation:
    """(1, J) pose turning each role's segment (its head to the next role's head, or its
    own tail) onto a world direction, parents first, by the shortest arc about its head;
    everything below a turned bone turns with it."""
    rot = skeleton.rest[:, :3, :3].copy()
    pos = skeleton.heads.copy()
    tails = skeleton.tails.copy()
    below = _subtrees(skeleton.parents)
    for role in sorted((r for r in want if r in bmap.bones), key=lambda r: bmap.bones[r]):
        j = bmap.bones[role]
        nxt = bmap.bones.get(bonemap.NEXT.get(role) or "")
        end = pos[nxt] if nxt is not None and np.linalg.norm(pos[nxt] - pos[j]) > 1e-3 else tails[j]
        turn = geometry.swing(end - pos[j], want[role])
        sub = below[j]
        rot[sub] = turn @ rot[sub]
        pos[sub] = pos[j] + (pos[sub] - pos[j]) @ turn.T
        tails[sub] = pos[j] + (tails[sub] - pos[j]) @ turn.T
    parents = skeleton.parents
    local_rest = skeleton.local_rest()[:, :3, :3]
    base = np.where((parents >= 0)[:, None, None], rot[np.maximum(parents, 0)] @ local_rest,
                    local_rest)  # fmt: skip
    q = quaternion.from_matrix(np.swapaxes(base, -1, -2) @ rot)
    j = len(skeleton.names)
    return Animation(q[None], np.zeros((1, j, 3)), 24.0, skeleton.names)


def _subtrees(parents: np.ndarray) -> list[np.ndarray]:
    """Per bone, (n,) indices of itself and all its descendants."""
    inside = np.eye(len(parents), dtype=bool)
    for j in range(len(parents) - 1, -1, -1):  # children after parents: fold upwards
        if parents[j] >= 0:
            inside[parents[j]] |= inside[j]
    return [np.flatnonzero(row) for row in inside]


def switch_rest(
    skeleton: Skeleton, animation: Animation, to: str = "t-pose"
) -> tuple[Skeleton, Animation]:
    """The same motion over a T-pose (or A-pose, or any library pose) rest.

    Returns the skeleton resting in pose ``to`` and the motion re-expressed on it (world
    motion unchanged; see ``rig.poses.rebase``, whose ``inverse`` switches back exactly).
    """
    return rebase(skeleton, animation, load(to, skeleton))

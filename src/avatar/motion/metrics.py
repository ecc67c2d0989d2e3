"""Retarget quality: an error per mapped bone (world direction for canonical bones, the
turn relative to the parent for same-named ones), foot skating, floor penetration,
joint-limit (hyperextension) violations and, on a body, the skin's stretch per bone."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from avatar.motion import deformation, geometry
from avatar.motion.bonemap import BoneMap
from avatar.motion.contacts import FootContacts
from avatar.motion.pairs import Pair, segment_world
from avatar.rig import quaternion
from avatar.rig.kinematics import rest_quaternions
from avatar.rig.skeleton import Skeleton

_HYPEREXTENSION_DEG = 10.0
_BACK = np.array([0.0, 1.0, 0.0])  # knees bend toward +Y, elbows toward -Y (rest frame)


@dataclass(frozen=True)
class Quality:
    """Numbers a user can judge a retarget by.

    direction_*: error (degrees) over all frames and every mapped bone: for a canonical
        bone the angle between its segment on the target and on the source, in the world;
        for a same-named bone (``=name``) the angle between its turn relative to its
        parent (from its rest) on the target and on the source.
    per_bone: role (``=name`` for same-named bones) -> median error (degrees).
    skating_cm: mean horizontal slide of the pinned foot joint per contact frame (cm).
    penetration_cm: deepest foot joint below its standing height (cm, 0 when none).
    limit_violations: frames where a knee or elbow bends backwards by over 10 degrees.
    stretch: target bone -> mean stretch of the skin weighted to it (a fraction; see
        ``deformation``), measured when the retarget had the body; {} otherwise.
    face_stretch: the face's mean edge stretch in its worst frame (a fraction).
    eye_drift_mm: the farthest an eyeball leaves the place the head carries it to (mm).
    deformed: bones whose skin stretches over their limit (``deformation.limit``).
    """

    direction_median: float
    direction_p95: float
    direction_max: float
    per_bone: dict[str, float]
    skating_cm: float
    contact_frames: int
    penetration_cm: float
    limit_violations: int
    stretch: dict[str, float] = field(default_factory=dict)
    face_stretch: float = 0.0
    eye_drift_mm: float = 0.0
    deformed: tuple[str, ...] = ()

    def summary(self) -> str:
        worst = max(self.per_bone, key=self.per_bone.__getitem__, default="-")
        text = (
            f"direction error median {self.direction_median:.2f} deg, p95 "
            f"{self.direction_p95:.2f} deg (worst {worst} "
            f"{self.per_bone.get(worst, 0.0):.1f} deg); foot skating {self.skating_cm:.2f} "
            f"cm/contact frame over {self.contact_frames} frames; floor penetration "
            f"{self.penetration_cm:.2f} cm; joint-limit violations {self.limit_violations}"
        )
        if self.stretch:
            bad = ", ".join(f"{b} {self.stretch[b] * 100:.0f}%" for b in self.deformed[:6])
            text += (
                f"\nskin stretch: face {self.face_stretch * 100:.1f}%, eyes "
                f"{self.eye_drift_mm:.1f} mm from their sockets; "
                + (f"DEFORMED: {bad}" if bad else "no bone over its limit")
            )
        return text

    def with_stretch(self, measured: deformation.Stretch) -> Quality:
        """This quality with the skin's stretch under the motion (``deformation.measure``)."""
        return replace(
            self,
            stretch=dict(measured.per_bone),
            face_stretch=float(measured.face.max(initial=0.0)),
            eye_drift_mm=float(measured.eyes.max(initial=0.0) * 1000.0),
            deformed=measured.deformed(),
        )

    def as_dict(self) -> dict:
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


def local_errors(pairs: list[Pair], src, target: Skeleton, world) -> dict[str, np.ndarray]:
    """``=name`` -> (T,) angle (degrees) between a same-named bone's turn relative to its
    parent on the target and on the source. The turn of bone j is its world rotation's
    change from rest, d = (W_p R_p^-1)^-1 (W_j R_j^-1), in world axes, so a bone the source
    leaves at rest relative to its parent must stay so (a face bone turned against the
    head tears the face while every segment direction is right).

    src: frame-first source (``rot`` (T, Js, 4)); world: (T, J, 4) target world rotations.
    """
    rest_s = rest_quaternions(src.skeleton)[0]
    rest_t = rest_quaternions(target)[0]

    def turn(rot, rest, j: int, parent: int) -> np.ndarray:
        d = quaternion.multiply(rot[:, j], quaternion.conjugate(rest[j]))
        if parent < 0:
            return d
        dp = quaternion.multiply(rot[:, parent], quaternion.conjugate(rest[parent]))
        return quaternion.multiply(quaternion.conjugate(dp), d)

    out = {}
    for p in pairs:
        if not p.role.startswith("="):
            continue
        ds = turn(src.rot, rest_s, p.source, int(src.skeleton.parents[p.source]))
        dt = turn(world, rest_t, p.target, int(target.parents[p.target]))
        w = np.abs(np.sum(ds.astype(np.float64) * dt, axis=-1))  # cos(half the angle)
        out[p.role] = np.degrees(2 * np.arccos(np.clip(w, 0.0, 1.0)))
    return out


def direction_errors(pairs: list[Pair], src, target: Skeleton, world, pos) -> dict[str, np.ndarray]:
    """role -> (T,) angle (degrees) between source and target segment directions, for the
    canonical pairs (same-named ones: ``local_errors``)."""
    out = {}
    by_role = {p.role: p for p in pairs}
    for p in pairs:
        if p.role.startswith("="):
            continue
        s = segment_world(src.skeleton, src.rot, src.pos, p.source, p.source_end)
        t = segment_world(target, world, pos, p.target, p.target_end)
        if p.role == "hips" and "thigh.L" in by_role and "thigh.R" in by_role:
            # The pelvis is judged by its hip-to-hip line: its "segment" to the spine
            # differs between skeletons by build, not by pose.
            left, right = by_role["thigh.L"], by_role["thigh.R"]
            s = src.pos[:, left.source] - src.pos[:, right.source]
            t = pos[:, left.target] - pos[:, right.target]
        out[p.role] = geometry.angle(s, t)
    return out


def skating(pos: np.ndarray, tmap: BoneMap, feet: FootContacts) -> tuple[float, int]:
    """(mean horizontal slide per contact frame in cm, number of contact frames)."""
    slides, count = [], 0
    for side, pinned in feet.pinned.items():
        for role in ("foot", "toe"):
            j = tmap.bones.get(f"{role}.{side}")
            if j is None:
                continue
            on = pinned == role
            both = on[1:] & on[:-1]
            step = np.linalg.norm(np.diff(pos[:, j, :2], axis=0), axis=-1)
            slides.append(step[both])
            count += int(on.sum())
    if not count:
        return 0.0, 0
    return float(np.concatenate(slides).sum() / count * 100.0), count


def penetration(pos: np.ndarray, tmap: BoneMap, target: Skeleton) -> float:
    """Deepest foot joint below its rest (standing) height, cm."""
    depth = 0.0
    for role in ("foot.L", "toe.L", "foot.R", "toe.R"):
        j = tmap.bones.get(role)
        if j is not None:
            depth = max(depth, float((target.heads[j, 2] - pos[:, j, 2]).max()))
    return max(depth, 0.0) * 100.0


def hyperextension(world: np.ndarray, pos: np.ndarray, tmap: BoneMap, target: Skeleton) -> int:
    """Frames in which a knee or elbow bends against its hinge by over 10 degrees."""
    bad = np.zeros(len(pos), dtype=bool)
    for upper, lower, end, bend in (("thigh", "shin", "foot", _BACK),
                                    ("upperarm", "forearm", "hand", -_BACK)):  # fmt: skip
        for side in ("L", "R"):
            idx = [tmap.bones.get(f"{r}.{side}") for r in (upper, lower, end)]
            if None in idx:
                continue
            rest = target.rest[idx[0], :3, :3]
            hinge = rest.T @ geometry.unit(
                np.cross(target.heads[idx[1]] - target.heads[idx[0]], bend)
            )
            a, b = pos[:, idx[1]] - pos[:, idx[0]], pos[:, idx[2]] - pos[:, idx[1]]
            sign = np.sum(np.cross(a, b) * quaternion.rotate(world[:, idx[0]], hinge), axis=-1)
            bad |= (sign < 0) & (geometry.angle(a, b) > _HYPEREXTENSION_DEG)
    return int(bad.sum())


def measure(pairs, src, target: Skeleton, world, pos, tmap: BoneMap, feet, fps) -> Quality:
    """All metrics of one retarget (see ``Quality``)."""
    errors = direction_errors(pairs, src, target, world, pos)
    errors |= local_errors(pairs, src, target, world)
    flat = np.concatenate(list(errors.values())) if errors else np.zeros(1)
    slide, count = skating(pos, tmap, feet) if feet is not None else (0.0, 0)
    return Quality(
        direction_median=float(np.median(flat)),
        direction_p95=float(np.percentile(flat, 95)),
        direction_max=float(flat.max()),
        per_bone={k: float(np.median(v)) for k, v in errors.items()},
        skating_cm=slide,
        contact_frames=count,
        penetration_cm=penetration(pos, tmap, target),
        limit_violations=hyperextension(world, pos, tmap, target),
    )

"""Keypoints -> pose on an Avatar rig, frame by frame (numpy, no optimiser).

Per frame (``PoseSolver.__call__``), in the order of ``plan.make_plan``:

1. keypoints below the confidence threshold (or NaN) are dropped, the rest One-Euro
   filtered (``filters``);
2. root: a weighted rigid fit of the hips bone's points (hip joints, pelvis) and the
   shoulders (taken at rest relative to the hips), then turned so the hip line matches
   exactly and placed at the observed pelvis (scaled by the rig's leg length over the
   subject's, optionally lifted onto a floor);
3. spine chain: one turn fitted to the shoulders (and any chest points), shared along its
   bones (bone k of n gets the fraction (k+1)/n), refined twice for the shared bend;
   clavicles aim at the shoulders;
4. neck chain fitted to the face points the same way; the head by a rigid fit about its
   joint;
5. limbs: each bone's swing turns it onto its observed segment (from the observed joint
   at its head, so the rig keeps its own bone lengths), upper arms and thighs take their
   twist from the plane of the limb's three joints, hands and feet fit their points;
6. joint limits (``data/mocap/limits.json``) clamp each bone's turn from rest;
7. a bone whose keypoints are all missing keeps its last good rotation, decaying to rest
   with time constant ``hold``;
8. feet planted while a contact is detected (ankle near the floor and slow), by two-bone
   leg IK, released smoothly (``feet``).

``solve`` runs a whole clip; ``PoseSolver`` is the streaming form. Single bones are solved a
dependency level at a time (``plan.Batch``: both arms and legs in one set of array
operations), chains in closed form per iteration, so a frame costs a fixed few hundred numpy
calls whatever the rig (``bench/mocap.py`` times it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from avatar.errors import ParameterError
from avatar.mocap import rotations as rot
from avatar.mocap.feet import FootPlanter
from avatar.mocap.filters import OneEuro, PointFilter
from avatar.mocap.keypoints import RigKeypoints
from avatar.mocap.plan import Batch, Plan, make_plan
from avatar.rig.skeleton import Animation


@dataclass(frozen=True)
class SolverSettings:
    """threshold: confidence below which a keypoint counts as missing (0..1).
    hold: seconds; a bone without keypoints relaxes to rest with this time constant.
    smoothing: One Euro parameters (``OneEuro.off()`` for none).
    limits: clamp bones to ``data/mocap/limits.json``.
    scale: root motion scale, or "auto" (rig leg length / the subject's, measured over
        the first confident frames).
    floor: None (heights as given), "auto" (the lowest ankle seen stands at the rig's rest
        ankle height) or the floor's height in the input (metres).
    plant_feet: pin feet while a contact is detected.
    """

    threshold: float = 0.5
    hold: float = 0.5
    smoothing: OneEuro = field(default_factory=OneEuro)
    limits: bool = True
    scale: float | str = "auto"
    floor: float | str | None = None
    plant_feet: bool = True


@dataclass(frozen=True)
class SolvedFrame:
    """One solved pose on the rig.

    rotations: (J, 4) pose-bone quaternions (w, x, y, z), as ``Animation.rotations[t]``.
    translations: (J, 3) pose-bone locations (the hips only).
    points: (K, 3) the keypoints on the solved rig (metres, Avatar's frame).
    time: seconds (the input's clock); solved: (S,) bool per solved bone, False where it
    was held; contacts: (2,) bool, left and right foot planted.
    """

    rotations: np.ndarray
    translations: np.ndarray
    points: np.ndarray
    time: float
    solved: np.ndarray
    contacts: np.ndarray


class PoseSolver:
    """Streaming solver for one rig and keypoint set: ``solver(points, confidence, t)``."""

    def __init__(self, rig: RigKeypoints, settings: SolverSettings | None = None):
        self.settings = settings or SolverSettings()
        self.plan: Plan = make_plan(rig)
        self.rig = rig
        sk = rig.skeleton
        self._rest = sk.rest[:, :3, :3]
        self._hips = self.plan.steps[0].bone
        sho = [k for k in self.plan.shoulder_points if k >= 0]
        self._root_points = np.concatenate([self.plan.steps[0].points, np.array(sho, int)])
        self._root_offsets = np.concatenate([
            self.plan.steps[0].offsets,
            (rig.rest[sho] - sk.heads[self._hips]) @ self._rest[self._hips]])  # fmt: skip
        self._feet = FootPlanter(self.plan)
        self._bones = np.array([st.bone for st in self.plan.steps])
        carried = [(k, i, st.offsets[r]) for i, st in enumerate(self.plan.steps)
                   for r, k in enumerate(st.points)]  # fmt: skip
        self._point_ids = np.array([c[0] for c in carried], dtype=int)
        self._point_owner = np.array([c[1] for c in carried], dtype=int)
        self._point_offsets = np.array([c[2] for c in carried]).reshape(-1, 3)
        self.reset()

    def reset(self) -> None:
        """Forget the stream (filter state, held rotations, scale, floor, contacts)."""
        count = len(self.plan.steps)
        self._last = np.tile(np.eye(3), (count, 1, 1))
        self._root = self.rig.skeleton.heads[self._hips].copy()
        self._filter = PointFilter(len(self.rig.keypoints.names), self.settings.smoothing)
        self._legs: list[float] = []
        self._scale = None if self.settings.scale == "auto" else float(self.settings.scale)
        self._floor = math.inf
        self._time: float | None = None
        self._feet.reset()

    # -- one frame ---------------------------------------------------------------------

    def __call__(self, points: np.ndarray, confidence: np.ndarray | None = None,
                 t: float | None = None) -> SolvedFrame:  # fmt: skip
        """Solve one frame: points (K, 3) metres in Avatar's frame (NaN: missing),
        confidence (K,) in 0..1 or None, t seconds (None: 30 frames/s after the last)."""
        k = len(self.rig.keypoints.names)
        p = np.asarray(points, dtype=np.float64)
        if p.shape != (k, 3):
            raise ParameterError(f"expected ({k}, 3) keypoints for {self.rig.keypoints.name}, "
                                 f"got {p.shape}")  # fmt: skip
        t = (0.0 if self._time is None else self._time + 1 / 30) if t is None else float(t)
        dt = 1 / 30 if self._time is None else max(t - self._time, 1e-6)
        self._time = t
        bad = ~np.isfinite(p).all(axis=1)
        if confidence is not None:
            c = np.asarray(confidence, dtype=np.float64).reshape(k)
            bad |= ~(c >= self.settings.threshold)
            w = np.where(bad, 0.0, np.nan_to_num(c))
        else:
            w = np.where(bad, 0.0, 1.0)
        p = np.where(bad[:, None], np.nan, p)
        p = self._filter(p, t)
        ok = ~bad & np.isfinite(p).all(axis=1)
        return self._solve(p, ok, w, t, dt)

    def _solve(self, p, ok, w, t, dt) -> SolvedFrame:
        n = len(self.plan.steps)
        world = np.empty((n, 3, 3))
        heads = np.empty((n, 3))
        local = np.empty((n, 3, 3))
        solved = np.zeros(n, dtype=bool)
        decay = math.exp(-dt / self.settings.hold) if self.settings.hold > 0 else 0.0
        frame = _Frame(p, ok, w, world, heads, local, solved, decay)
        self._solve_root(frame)
        for kind, item in self.plan.schedule[1:]:
            if kind == "chain":
                self._solve_chain(frame, str(item))
                tips = self.plan.chains[str(item)].tip_batch
                if item == "spine_chain" and tips is not None:
                    self._solve_bones(frame, tips)  # again, with the clavicles just solved
                    self._solve_chain(frame, "spine_chain")
            else:
                self._solve_bones(frame, item)  # type: ignore[arg-type]
        contacts = np.zeros(2, dtype=bool)
        if self.settings.plant_feet:
            contacts = self._feet(frame, dt, self._inherit)
        return self._output(frame, t, contacts)

    def _inherit(self, f: _Frame, i: int) -> tuple[np.ndarray, np.ndarray]:
        """(world rotation with this bone at rest relative to its anchor, head)."""
        st = self.plan.steps[i]
        wa = f.world[st.anchor]
        return wa @ st.rel, f.heads[st.anchor] + wa @ st.step

    def _finish(self, f: _Frame, i: int, base: np.ndarray, world: np.ndarray | None) -> None:
        """Record bone i's pose: ``world`` solved (None: held), limits applied."""
        st = self.plan.steps[i]
        if world is None:
            self._last[i] = rot.power(self._last[i], f.decay) if f.decay else np.eye(3)
            local = self._last[i]
        else:
            local = base.T @ world
            if self.settings.limits and st.limit < math.pi:
                local = rot.clamp(local, st.limit)
            self._last[i] = local
            f.solved[i] = True
        f.local[i] = local
        f.world[i] = base @ local

    def _finish_many(self, f: _Frame, batch: Batch, base: np.ndarray, world: np.ndarray,
                     solved: np.ndarray) -> None:  # fmt: skip
        """``_finish`` for a batch: rows where ``solved`` take ``world`` (n, 3, 3), the
        others are held."""
        ids = batch.steps
        local = base.transpose(0, 2, 1) @ world
        if not solved.all():
            held = ids[~solved]
            last = rot.power_many(self._last[held], f.decay) if f.decay else np.eye(3)
            self._last[held] = last
            local[~solved] = self._last[held]
        if self.settings.limits:
            over = solved & batch.limited
            if over.any():
                over &= rot.angle_many(local) > batch.limit
                for r in np.flatnonzero(over):  # rare: the scalar clamp
                    local[r] = rot.clamp(local[r], float(batch.limit[r]))
        self._last[ids[solved]] = local[solved]
        f.solved[ids] |= solved
        f.local[ids] = local
        f.world[ids] = base @ local

    # -- root ----------------------------------------------------------------------------

    def _scale_now(self, p: np.ndarray, ok: np.ndarray) -> float:
        if self._scale is not None:
            return self._scale
        legs = []
        for side in (0, 1):
            hip, ankle = self.plan.hip_points[side], self.plan.ankle_points[side]
            knee = self._knee(side)
            if min(hip, ankle, knee) >= 0 and ok[[hip, knee, ankle]].all():
                legs.append(np.linalg.norm(p[knee] - p[hip]) + np.linalg.norm(p[ankle] - p[knee]))
        if legs:
            self._legs.append(float(np.mean(legs)))
        if len(self._legs) >= 30:  # settle on the median of the first confident frames
            self._scale = self.plan.leg_length / float(np.median(self._legs))
            return self._scale
        return self.plan.leg_length / float(np.median(self._legs)) if self._legs else 1.0

    def _knee(self, side: int) -> int:
        st = self.plan.role_steps.get("shin." + "LR"[side])
        return -1 if st is None else self.plan.steps[st].origin

    def _solve_root(self, f: _Frame) -> None:
        keep = f.ok[self._root_points]
        idx, a = self._root_points[keep], self._root_offsets[keep]
        rest = self._rest[self._hips]
        if len(idx) < 3:
            self._finish(f, 0, rest, None)
            f.heads[0] = self._root
            return
        s = self._scale_now(f.p, f.ok)
        b, wt = f.p[idx] * s, f.w[idx]
        ca, cb = (wt @ a) / wt.sum(), (wt @ b) / wt.sum()
        r = rot.kabsch(a - ca, b - cb, wt)
        if r is None:
            self._finish(f, 0, rest, None)
            f.heads[0] = self._root
            return
        hl, hr = self.plan.hip_points
        pos = {int(k): i for i, k in enumerate(idx)}
        if hl in pos and hr in pos:  # the hip line exactly, the tilt from the fit
            il, ir = pos[hl], pos[hr]
            r = rot.between(r @ (a[il] - a[ir]), b[il] - b[ir]) @ r
            t = (b[il] + b[ir]) / 2 - r @ ((a[il] + a[ir]) / 2)
        else:
            t = cb - r @ ca
        lift = np.array([0.0, 0.0, self._lift(f, s)])
        self._finish(f, 0, rest, r)
        f.heads[0] = self._root = t + lift
        if s != 1.0 or lift[2] != 0.0:
            # Every later step compares keypoints with bone heads: put them in the rig's
            # space, as the root was (scaled to the rig, on its floor).
            f.p = f.p * s + lift

    def _lift(self, f: _Frame, s: float) -> float:
        floor = self.settings.floor
        if floor is None:
            return 0.0
        if floor != "auto":
            return -float(floor) * s
        ankles = [k for k in self.plan.ankle_points if k >= 0 and f.ok[k]]
        if ankles:
            self._floor = min(self._floor, float(f.p[ankles, 2].min()) * s)
        if not math.isfinite(self._floor):
            return 0.0
        sk = self.rig.skeleton
        feet = [sk.heads[st.bone, 2] for st in self.plan.steps if st.role.startswith("foot.")]
        return (float(np.mean(feet)) if feet else 0.08) - self._floor

    # -- chains (spine, neck) --------------------------------------------------------------

    def _solve_chain(self, f: _Frame, name: str) -> None:
        chain = self.plan.chains[name]
        given: dict[int, np.ndarray | None] = {}
        if name == "neck_chain":  # the head's own rigid fit places and turns it
            given = {i: self._rigid(f, i) for i in chain.tips}
        base0, head0 = self._inherit(f, chain.steps[0])
        keep = f.ok[chain.points] if len(chain.points) else np.zeros(0, bool)
        b = f.p[chain.points[keep]] - head0
        wt = f.w[chain.points[keep]]
        a = chain.offsets[keep] @ base0.T
        turn = None
        if len(b) >= 2:
            turn = rot.kabsch(a, b, wt)
        if turn is None and len(b) >= 1:
            turn = rot.between(wt @ a, wt @ b)
        if turn is None:
            for i in chain.steps:
                base, f.heads[i] = self._inherit(f, i)
                self._finish(f, i, base, None)
            return
        at_rest = base0 @ chain.rest_rel  # (n, 3, 3) the chain's bones at rest
        fractions = np.arange(1, len(chain.steps) + 1) / len(chain.steps)
        for attempt in range(3):  # the shared bend moves the points: fit the residual turn
            axis, angle = rot.log(turn)
            world = rot.turns_about(axis, angle * fractions) @ at_rest
            if attempt == 2:
                break  # a fix found now would not be applied
            got = self._chain_points(f, chain, world, given)[keep] - head0
            fix = rot.kabsch(got, b, wt) if len(b) >= 2 else rot.between(wt @ got, wt @ b)
            if fix is None or rot.angle_of(fix) < 1e-5:
                break
            turn = fix @ turn
        self._place_chain(f, chain, world)

    def _place_chain(self, f: _Frame, chain, world: np.ndarray) -> None:
        """Pose a chain's bones at world rotations (n, 3, 3), each relative to the one
        before; bone by bone (``_finish``) only where a joint limit bites."""
        ids, anchor = chain.steps, chain.anchor
        above = np.concatenate([f.world[anchor][None], world[:-1]])
        base = above @ chain.rel
        local = base.transpose(0, 2, 1) @ world
        if self.settings.limits and (rot.angle_many(local) > chain.limit).any():
            for k, i in enumerate(chain.steps):
                base_k, f.heads[i] = self._inherit(f, i)
                self._finish(f, i, base_k, world[k])
            return
        f.heads[ids] = f.heads[anchor] + np.cumsum((above @ chain.step[:, :, None])[:, :, 0], 0)
        self._last[ids] = local
        f.solved[ids] = True
        f.local[ids] = local
        f.world[ids] = base @ local

    def _rigid(self, f: _Frame, i: int) -> np.ndarray | None:
        """World rotation of bone i from a rigid fit (rotation and translation) of its own
        keypoints, or None when they do not fix one."""
        st = self.plan.steps[i]
        keep = f.ok[st.points]
        if keep.sum() < 3:
            return None
        a, b, wt = st.offsets[keep], f.p[st.points[keep]], f.w[st.points[keep]]
        return rot.kabsch(a - (wt @ a) / wt.sum(), b - (wt @ b) / wt.sum(), wt)

    def _chain_points(self, f: _Frame, chain, world: np.ndarray, given: dict) -> np.ndarray:
        """(n, 3) the chain's keypoints with its bones at world rotations (c, 3, 3); the
        bones hanging on it (``chain.tips``) in their latest pose relative to it, or at
        the world rotation ``given`` maps them to (None: the latest)."""
        above = np.concatenate([f.world[chain.anchor][None], world[:-1]])
        heads = f.heads[chain.anchor] + np.cumsum((above @ chain.step[:, :, None])[:, :, 0], 0)
        if chain.tips:
            tips, on = chain.tip_batch, chain.tip_on
            wa = world[on]
            tip_world = wa @ tips.rel @ self._last[tips.steps]
            for r, i in enumerate(chain.tips):
                if given.get(i) is not None:
                    tip_world[r] = given[i]
            tip_heads = heads[on] + (wa @ tips.step[:, :, None])[:, :, 0]
            world = np.concatenate([world, tip_world])
            heads = np.concatenate([heads, tip_heads])
        own = chain.owner
        return heads[own] + (world[own] @ chain.owner_offsets[:, :, None])[:, :, 0]

    # -- single bones, a level at a time ---------------------------------------------------

    def _solve_bones(self, f: _Frame, batch: Batch) -> None:
        """Swing (and twist) each bone of a batch onto its keypoints, all at once: a rigid
        turn where two or more points fix one, else the shortest arc onto their weighted
        direction, twisted into the limb's plane for upper arms and thighs."""
        wa = f.world[batch.anchor]
        base = wa @ batch.rel
        f.heads[batch.steps] = head = f.heads[batch.anchor] + (wa @ batch.step[:, :, None])[:, :, 0]
        keep = f.ok[batch.points] & batch.real
        count = keep.sum(1)
        has_origin = batch.origin >= 0
        has_origin[has_origin] = f.ok[batch.origin[has_origin]]
        origin = np.where(has_origin[:, None], f.p[batch.origin], head)
        b = np.where(keep[:, :, None], f.p[batch.points] - origin[:, None, :], 0.0)
        a = batch.offsets @ base.transpose(0, 2, 1)
        wt = np.where(keep, f.w[batch.points], 0.0)
        world = base.copy()
        arc = count >= 1
        many = count >= 2
        if many.any():
            turn, fixed = rot.kabsch_many(a[many], b[many], wt[many])
            rows = np.flatnonzero(many)
            world[rows[fixed]] = turn[fixed] @ base[rows[fixed]]
            arc[rows[fixed]] = False
        if arc.any():
            along = (wt[arc, :, None] * b[arc]).sum(1)
            turned = rot.between_many((wt[arc, :, None] * a[arc]).sum(1), along) @ base[arc]
            twist = batch.has_pole[arc]
            if twist.any():
                rows = np.flatnonzero(arc)[twist]
                turned[twist] = self._twist(f, batch, rows, turned[twist], along[twist])
            world[arc] = turned
        self._finish_many(f, batch, base, world, count >= 1)

    def _twist(self, f: _Frame, batch: Batch, rows: np.ndarray, world: np.ndarray,
               along: np.ndarray) -> np.ndarray:  # fmt: skip
        """Turn limbs' upper bones (``rows`` of the batch, world (r, 3, 3), aimed along
        (r, 3)) about their own axes so each bend axis lies along the normal of the
        observed plane of the limb's three joints (weighted by how bent the limb is: a
        straight limb keeps the swing's twist)."""
        origin, mid, far = batch.origin[rows], batch.pole_mid[rows], batch.pole_far[rows]
        seen = (origin >= 0) & f.ok[origin] & f.ok[mid] & f.ok[far]
        upper, lower = f.p[mid] - f.p[origin], f.p[far] - f.p[mid]
        normal = rot.cross_many(upper, lower)
        with np.errstate(invalid="ignore"):
            bend = np.sqrt((normal * normal).sum(1)) / (
                np.sqrt((upper * upper).sum(1) * (lower * lower).sum(1)) + 1e-12)
        weight = np.clip((bend - 0.05) / 0.15, 0.0, 1.0)  # sin of the bend: 3..11 degrees
        weight = np.where(seen, weight, 0.0)
        length = np.sqrt((along * along).sum(1))[:, None]
        d = np.where(length > 1e-12, along / np.where(length > 1e-12, length, 1.0), along)
        have = (world @ batch.pole_axis[rows][:, :, None])[:, :, 0]
        have = have - d * (have * d).sum(1)[:, None]
        want = normal - d * (normal * d).sum(1)[:, None]
        live = (weight > 0) & ((have * have).sum(1) >= 1e-12) & ((want * want).sum(1) >= 1e-12)
        if not live.any():
            return world
        angle = np.arctan2((rot.cross_many(have, want) * d).sum(1), (have * want).sum(1))
        angle = np.where(live, weight * angle, 0.0)
        return rot.axis_angle_many(np.nan_to_num(d), np.nan_to_num(angle)) @ world

    # -- output ----------------------------------------------------------------------------

    def _output(self, f: _Frame, t: float, contacts: np.ndarray) -> SolvedFrame:
        sk = self.rig.skeleton
        count = len(sk.names)
        rotations = np.zeros((count, 4))
        rotations[:, 0] = 1.0
        rotations[self._bones] = rot.quaternions(f.local)
        translations = np.zeros((count, 3))
        translations[self._hips] = self._rest[self._hips].T @ (f.heads[0] - sk.heads[self._hips])
        points = np.full((len(self.rig.keypoints.names), 3), np.nan)
        own, off = self._point_owner, self._point_offsets
        points[self._point_ids] = f.heads[own] + (f.world[own] @ off[:, :, None])[:, :, 0]
        return SolvedFrame(rotations, translations, points, t, f.solved.copy(), contacts)


@dataclass
class _Frame:
    """One frame's working state: keypoints (K, 3), ok (K,), weights (K,), and per solved
    bone world rotations (S, 3, 3), heads (S, 3), local rotations (S, 3, 3), solved (S,)."""

    p: np.ndarray
    ok: np.ndarray
    w: np.ndarray
    world: np.ndarray
    heads: np.ndarray
    local: np.ndarray
    solved: np.ndarray
    decay: float


def solve(rig: RigKeypoints, points: np.ndarray, confidence: np.ndarray | None = None,
          fps: float = 30.0, settings: SolverSettings | None = None) -> Animation:  # fmt: skip
    """A clip of keypoints (T, K, 3) (confidence (T, K) or None) -> ``Animation`` on the rig
    at ``fps``, every frame solved in order by one ``PoseSolver``."""
    solver = PoseSolver(rig, settings)
    points = np.asarray(points, dtype=np.float64)
    frames = [solver(points[i], None if confidence is None else confidence[i], i / fps)
              for i in range(len(points))]  # fmt: skip
    names = rig.skeleton.names
    count = len(names)
    rotations = np.stack([fr.rotations for fr in frames]) if frames else np.zeros((0, count, 4))
    moves = np.stack([fr.translations for fr in frames]) if frames else np.zeros((0, count, 3))
    return Animation(rotations, moves, float(fps), names)

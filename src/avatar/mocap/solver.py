"""Keypoints -> pose on an Avatar rig, frame by frame (closed form, no optimiser).

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

``solve`` runs a whole clip; ``PoseSolver`` is the streaming form.

Cost. A frame turns about two dozen bones, one 3x3 product or two each, in dependency
order: at that size numpy's fixed cost per call (~1 us) is most of the work, so everything
rig-only is prepared once per solver (``_Bone``, ``_Chain``) and a frame walks the bones with
plain float arithmetic (``rotations``: 9-tuple matrices), going to numpy only for the input
filter, the SVD of each rigid fit and the final matrix -> quaternion conversion. Single bones
are solved in their anchor's rest frame (the fitted turn conjugated: one product fewer);
chain refinements move only the fitted keypoints (Rodrigues on vectors, no posed frames).
The spine is solved twice (before and after the clavicles hanging on it): the second pass
reuses the first's initial fit, and the first places only the bone the clavicles hang on.
COCO-17 0.55-0.85 ms a frame, MediaPipe-33 0.70-1.2 ms, on a shared 2-core machine at load
12-16 (0.22-0.25 x forward kinematics of the rig; 1.3x the revision before these changes,
~5x the numpy-per-level solver before that), with the same results
(``tests/mocap/test_solver_regression.py``: within 1e-6 rad); ``bench/mocap.py`` times it
against forward kinematics of the rig and the previous revision. What is left is mostly
Python's per-operation cost and ~11-15 LAPACK SVDs of 3x3 rigid fits (5-10 us each).
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from avatar.errors import ParameterError
from avatar.mocap import rotations as rot
from avatar.mocap.feet import FootPlanter
from avatar.mocap.filters import OneEuro, PointFilter
from avatar.mocap.keypoints import RigKeypoints
from avatar.mocap.plan import Plan, make_plan
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
        ankle height), "ground" (the lowest ankle of every frame does: for hips-centred
        input such as MediaPipe's world landmarks, which carry no height above the floor, so
        a crouch lowers the hips instead of lifting the feet; a jump stays on the floor) or
        the floor's height in the input (metres).
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


@dataclass(frozen=True, slots=True)
class _Bone:
    """What a solved bone needs every frame, from the plan, as plain floats and ints.

    anchor: step index of the nearest solved bone above (-1 for the root); rel (9,) its rest
    rotation in the anchor's rest frame and step (3,) its rest head in the anchor's frame;
    points: keypoints carried, offsets in this bone's frame; origin: the keypoint at its
    head (-1: none); pole: (mid keypoint, far keypoint, bend axis in this bone's frame) for
    upper arms and thighs; limit: radians (``limited`` when below a half turn), cos_limit
    its cosine (a turn bites where (trace - 1) / 2 is below it: no arccos per bone).
    """

    anchor: int
    rel: rot.M
    step: rot.V
    points: tuple[int, ...]
    offsets: tuple[rot.V, ...]
    origin: int
    pole: tuple[int, int, rot.V] | None
    limit: float
    limited: bool
    cos_limit: float


@dataclass(frozen=True, slots=True)
class _Chain:
    """A chain (``plan.Chain``) prepared for the per-frame solve.

    steps: its bones (step indices, first to last), anchor: the first one's anchor;
    rest_rel: each bone's rest rotation in the first bone's rest frame; hops: for bone k >= 1
    the vector from bone k-1's head to bone k's, in the first bone's rest frame (hops[0]
    unused); limits: radians.
    points: the chain's keypoints and offsets (in the first bone's rest frame, everything at
    rest, for the initial fit); per point the chain bone ``carrier`` that turns it, ``tip``
    (index into tips for a point riding on a solved bone hanging on the chain: clavicles,
    head; -1: on a chain bone) and ``lever``: for a chain bone's point its offset from the
    carrier's head in the first bone's rest frame, for a tip's point its offset in the tip's
    own frame (turned by the tip's latest pose at each pass).
    tips: (step, index in steps of the bone it hangs on, the tip's head from that bone's
    head in the first bone's rest frame, its rest rotation in the first bone's rest frame);
    tip_on: the second entries. rel: each bone's rest rotation in the previous bone's rest
    frame (the first's: in its anchor's).
    """

    name: str
    steps: tuple[int, ...]
    anchor: int
    rest_rel: tuple[rot.M, ...]
    hops: tuple[rot.V, ...]
    limits: tuple[float, ...]
    points: tuple[int, ...]
    offsets: tuple[rot.V, ...]
    carrier: tuple[int, ...]
    tip: tuple[int, ...]
    lever: tuple[rot.V, ...]
    tips: tuple[tuple[int, int, rot.V, rot.M], ...]
    tip_ids: tuple[int, ...]
    tip_on: tuple[int, ...]
    rel: tuple[rot.M, ...]


def _m(a: np.ndarray) -> rot.M:
    return tuple(float(v) for v in np.asarray(a, dtype=np.float64).reshape(9))  # type: ignore[return-value]


def _v(a: np.ndarray) -> rot.V:
    return tuple(float(v) for v in np.asarray(a, dtype=np.float64).reshape(3))  # type: ignore[return-value]


class PoseSolver:
    """Streaming solver for one rig and keypoint set: ``solver(points, confidence, t)``.

    Everything that depends only on the rig and the keypoint set (the plan, rest frames,
    lengths, index lists) is prepared here once; a frame then walks the bones with plain
    float arithmetic (``rotations``), going to numpy for the input filter, the SVDs of rigid
    fits and the final conversion to quaternions.
    """

    def __init__(self, rig: RigKeypoints, settings: SolverSettings | None = None):
        self.settings = settings or SolverSettings()
        floor = self.settings.floor
        if not (floor is None or floor in ("auto", "ground")
                or (isinstance(floor, int | float) and math.isfinite(floor))):  # fmt: skip
            raise ParameterError(f"floor must be None, 'auto', 'ground' or a height in metres, "
                                 f"got {floor!r}")  # fmt: skip
        self.plan: Plan = make_plan(rig)
        self.rig = rig
        sk = rig.skeleton
        steps = self.plan.steps
        self._count = len(steps)
        self._hips = steps[0].bone
        self._bone = [self._prepare_bone(st) for st in steps]
        self._hips_rest = _m(sk.rest[self._hips, :3, :3])
        self._hips_head = _v(sk.heads[self._hips])
        sho = [k for k in self.plan.shoulder_points if k >= 0]
        root_offsets = np.concatenate([steps[0].offsets,
                                       (rig.rest[sho] - sk.heads[self._hips])
                                       @ sk.rest[self._hips, :3, :3]])  # fmt: skip
        self._root_points = [int(k) for k in steps[0].points] + sho
        self._root_offsets = [_v(o) for o in root_offsets]
        self._knees = [self._knee(side) for side in (0, 1)]
        feet = [sk.heads[st.bone, 2] for st in steps if st.role.startswith("foot.")]
        self._rest_ankle = float(np.mean(feet)) if feet else 0.08
        self._chains = {name: self._prepare_chain(c, name) for name, c in self.plan.chains.items()}
        self._schedule = self._prepare_schedule()
        self._feet = FootPlanter(self.plan)
        # Output: quaternions of the solved bones into (J, 4), keypoints from their carriers.
        self._bones = np.array([st.bone for st in steps])
        self._identity = np.tile([1.0, 0.0, 0.0, 0.0], (len(sk.names), 1))
        carried = [(k, i, st.offsets[r]) for i, st in enumerate(steps)
                   for r, k in enumerate(st.points)]  # fmt: skip
        self._point_ids = np.array([c[0] for c in carried], dtype=int)
        self._point_owner = np.array([c[1] for c in carried], dtype=int)
        self._point_offsets = np.array([c[2] for c in carried]).reshape(-1, 3, 1)
        self._ones = [1.0] * len(rig.keypoints.names)  # weights when no confidence is given
        self.reset()

    def _prepare_bone(self, st) -> _Bone:
        pole = None if st.pole is None else (int(st.pole[0]), int(st.pole[1]), _v(st.pole[2]))
        return _Bone(int(st.anchor), _m(st.rel), _v(st.step), tuple(int(k) for k in st.points),
                     tuple(_v(o) for o in st.offsets), int(st.origin), pole, float(st.limit),
                     bool(st.limit < math.pi), math.cos(min(float(st.limit), math.pi)))  # fmt: skip

    def _prepare_chain(self, chain, name: str) -> _Chain:
        steps = self.plan.steps
        ids = list(chain.steps)
        rest_rel = [np.asarray(r) for r in chain.rest_rel]
        hops = [np.zeros(3)] + [rest_rel[k - 1] @ chain.step[k] for k in range(1, len(ids))]
        tips = []
        for r, i in enumerate(chain.tips):
            on = int(chain.tip_on[r])
            tips.append((i, on, _v(rest_rel[on] @ steps[i].step), _m(rest_rel[on] @ steps[i].rel)))
        carrier, tip, lever = [], [], []
        for own, off in zip(chain.owner, chain.owner_offsets, strict=True):
            if own < len(ids):
                carrier.append(int(own))
                tip.append(-1)
                lever.append(_v(rest_rel[own] @ off))
            else:
                carrier.append(tips[own - len(ids)][1])
                tip.append(int(own) - len(ids))
                lever.append(_v(off))  # in the tip's own frame: turned by its pose each pass
        return _Chain(name, tuple(ids), int(chain.anchor), tuple(_m(r) for r in rest_rel),
                      tuple(_v(h) for h in hops), tuple(float(x) for x in chain.limit),
                      tuple(int(k) for k in chain.points), tuple(_v(o) for o in chain.offsets),
                      tuple(carrier), tuple(tip), tuple(lever), tuple(tips),
                      tuple(int(i) for i in chain.tips), tuple(t[1] for t in tips),
                      tuple(self._bone[i].rel for i in ids))  # fmt: skip

    def _prepare_schedule(self) -> list[tuple[str, object]]:
        """The plan's schedule with batches as step lists and chains prepared; the spine's
        tips (clavicles) solved between two passes of the spine, as the plan orders."""
        out: list[tuple[str, object]] = []
        for kind, item in self.plan.schedule[1:]:
            if kind == "chain":
                chain = self._chains[str(item)]
                tips = self.plan.chains[str(item)].tip_batch
                if item == "spine_chain" and tips is not None:
                    out.append(("first", chain))
                    out.append(("bones", [int(i) for i in tips.steps]))
                    out.append(("again", chain))
                else:
                    out.append(("once", chain))
            else:
                out.append(("bones", [int(i) for i in item.steps]))  # type: ignore[attr-defined]
        return out

    def reset(self) -> None:
        """Forget the stream (filter state, held rotations, scale, floor, contacts)."""
        self._last: list[rot.M] = [rot.EYE] * self._count
        self._root: rot.V = self._hips_head
        self._filter = PointFilter(len(self.rig.keypoints.names), self.settings.smoothing)
        self._legs: list[float] = []
        self._scale = None if self.settings.scale == "auto" else float(self.settings.scale)
        self._floor = math.inf
        self._ground = 0.0  # floor="ground": the last frame's lift (kept while ankles are unseen)
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
        if confidence is None and np.isfinite(p).all():  # the usual frame: nothing missing
            p = self._filter(p, t)
            ok = np.isfinite(p).all(axis=1).tolist()
            return self._solve(p.tolist(), ok, self._ones, t, dt)
        finite = np.isfinite(p).all(axis=1)
        if confidence is not None:
            c = np.asarray(confidence, dtype=np.float64).reshape(k)
            bad = ~(finite & (c >= self.settings.threshold))
            w = np.where(bad, 0.0, np.nan_to_num(c))
        else:
            bad = ~finite
            w = np.where(bad, 0.0, 1.0)
        if bad.any():
            p = np.where(bad[:, None], np.nan, p)
        p = self._filter(p, t)
        ok = ~bad & np.isfinite(p).all(axis=1)
        return self._solve(p.tolist(), ok.tolist(), w.tolist(), t, dt)

    def _solve(self, p: list, ok: list, w: list, t: float, dt: float) -> SolvedFrame:
        n = self._count
        decay = math.exp(-dt / self.settings.hold) if self.settings.hold > 0 else 0.0
        f = _Frame(p, ok, w, [rot.EYE] * n, [rot.ZERO] * n, [rot.EYE] * n, [False] * n, decay,
                   {})  # fmt: skip
        self._solve_root(f)
        for kind, item in self._schedule:
            if kind == "bones":
                for i in item:  # type: ignore[attr-defined]
                    self._solve_bone(f, i)
            else:
                self._solve_chain(f, item, kind)  # type: ignore[arg-type]
        contacts = np.zeros(2, dtype=bool)
        if self.settings.plant_feet:
            contacts = self._feet(f, dt, self._inherit)
        return self._output(f, t, contacts)

    def _inherit(self, f: _Frame, i: int) -> tuple[rot.M, rot.V]:
        """(world rotation with bone i at rest relative to its anchor, its head)."""
        b = self._bone[i]
        wa = f.world[b.anchor]
        return rot.mul(wa, b.rel), rot.add(f.heads[b.anchor], rot.apply(wa, b.step))

    def _finish(self, f: _Frame, i: int, base: rot.M, local: rot.M | None) -> None:
        """Record bone i's pose: ``local`` (relative to ``base``) solved, None: held (its
        last good rotation, decayed towards rest); joint limits applied."""
        if local is None:
            local = self._last[i] = rot.power(self._last[i], f.decay) if f.decay else rot.EYE
        else:
            b = self._bone[i]
            if (b.limited and self.settings.limits
                    and (local[0] + local[4] + local[8] - 1.0) * 0.5 < b.cos_limit):  # fmt: skip
                local = rot.clamp(local, b.limit)
            self._last[i] = local
            f.solved[i] = True
        f.local[i] = local
        f.world[i] = rot.mul(base, local)

    # -- root ----------------------------------------------------------------------------

    def _scale_now(self, p: list, ok: list) -> float:
        if self._scale is not None:
            return self._scale
        legs = []
        for side in (0, 1):
            hip, ankle = self.plan.hip_points[side], self.plan.ankle_points[side]
            knee = self._knees[side]
            if min(hip, ankle, knee) >= 0 and ok[hip] and ok[knee] and ok[ankle]:
                legs.append(_length(rot.sub(p[knee], p[hip])) + _length(rot.sub(p[ankle], p[knee])))
        if legs:
            self._legs.append(sum(legs) / len(legs))
        if len(self._legs) >= 30:  # settle on the median of the first confident frames
            self._scale = self.plan.leg_length / statistics.median(self._legs)
            return self._scale
        return self.plan.leg_length / statistics.median(self._legs) if self._legs else 1.0

    def _knee(self, side: int) -> int:
        st = self.plan.role_steps.get("shin." + "LR"[side])
        return -1 if st is None else self.plan.steps[st].origin

    def _solve_root(self, f: _Frame) -> None:
        ok = f.ok
        keep = [r for r, k in enumerate(self._root_points) if ok[k]]
        rest = self._hips_rest
        if len(keep) < 3:
            self._finish(f, 0, rest, None)
            f.heads[0] = self._root
            return
        s = self._scale_now(f.p, ok)
        idx = [self._root_points[r] for r in keep]
        a = [self._root_offsets[r] for r in keep]
        b = [_scaled(f.p[k], s) for k in idx]
        wt = [f.w[k] for k in idx]
        total = sum(wt)
        ca, cb = (
            _scaled(rot.weighted_sum(a, wt), 1 / total),
            _scaled(rot.weighted_sum(b, wt), 1 / total),
        )
        r = rot.kabsch([rot.sub(v, ca) for v in a], [rot.sub(v, cb) for v in b], wt)
        if r is None:
            self._finish(f, 0, rest, None)
            f.heads[0] = self._root
            return
        hl, hr = self.plan.hip_points
        if hl in idx and hr in idx:  # the hip line exactly, the tilt from the fit
            il, ir = idx.index(hl), idx.index(hr)
            r = rot.mul(rot.arc(rot.apply(r, rot.sub(a[il], a[ir])), rot.sub(b[il], b[ir])), r)
            mid_b = _scaled(rot.add(b[il], b[ir]), 0.5)
            t = rot.sub(mid_b, rot.apply(r, _scaled(rot.add(a[il], a[ir]), 0.5)))
        else:
            t = rot.sub(cb, rot.apply(r, ca))
        lift = self._lift(f, s)
        self._finish(f, 0, rest, rot.tmul(rest, r))
        f.heads[0] = self._root = (t[0], t[1], t[2] + lift)
        if s != 1.0 or lift != 0.0:
            # Every later step compares keypoints with bone heads: put them in the rig's
            # space, as the root was (scaled to the rig, on its floor).
            f.p = [(x * s, y * s, z * s + lift) for x, y, z in f.p]

    def _lift(self, f: _Frame, s: float) -> float:
        floor = self.settings.floor
        if floor is None:
            return 0.0
        if floor == "ground":
            seen = [f.p[k][2] for k in self.plan.ankle_points if k >= 0 and f.ok[k]]
            if seen:
                self._ground = self._rest_ankle - min(seen) * s
            return self._ground
        if floor != "auto":
            return -float(floor) * s
        heights = [f.p[k][2] for k in self.plan.ankle_points if k >= 0 and f.ok[k]]
        if heights:
            self._floor = min(self._floor, min(heights) * s)
        if not math.isfinite(self._floor):
            return 0.0
        return self._rest_ankle - self._floor

    # -- chains (spine, neck) --------------------------------------------------------------

    def _solve_chain(self, f: _Frame, c: _Chain, mode: str = "once") -> None:
        """One turn shared along the chain (bone k of n takes (k+1)/n of it), fitted to the
        chain's keypoints, then refined twice for the points the shared bend moves.

        mode: "once"; "first" (the spine before its tips, the clavicles, are solved: only
        what they hang on is placed, and the initial fit is kept in the frame) and "again"
        (after them: the kept fit, the same inputs, reused)."""
        fit = f.fits.pop(c.name, None) if mode == "again" else None
        if fit is None:
            fit = self._chain_fit(f, c)
            if mode == "first":
                f.fits[c.name] = fit
        base0, head0, keep, b, wt, turn, hops = fit
        if turn is None:
            for i in c.steps:
                base, f.heads[i] = self._inherit(f, i)
                self._finish(f, i, base, None)
            return
        levers, fixed = self._chain_levers(f, c, base0, keep)
        two = len(b) >= 2
        for _ in range(2):  # the shared bend moves the points: fit the residual turn
            axis, angle = rot.log(turn)
            got = self._chain_points(c, keep, axis, angle, hops, levers, fixed)
            fix = (rot.kabsch(got, b, wt) if two
                   else rot.arc(rot.weighted_sum(got, wt), rot.weighted_sum(b, wt)))  # fmt: skip
            if fix is None or rot.angle(fix) < 1e-5:
                break
            turn = rot.mul(fix, turn)
        axis, angle = rot.log(turn)
        if mode == "first":
            self._place_tips_anchor(f, c, base0, head0, axis, angle, hops)
        else:
            self._place_chain(f, c, base0, head0, axis, angle, hops)

    def _chain_fit(self, f: _Frame, c: _Chain) -> tuple:
        """The chain's inputs and initial turn: (its base rotation and head, kept points,
        their positions from the head and weights, the turn (None: nothing seen), the hops
        between its heads in world axes at rest)."""
        base0, head0 = self._inherit(f, c.steps[0])
        p, ok, w, points = f.p, f.ok, f.w, c.points
        keep = [j for j, k in enumerate(points) if ok[k]]
        hx, hy, hz = head0
        b = [(p[points[j]][0] - hx, p[points[j]][1] - hy, p[points[j]][2] - hz) for j in keep]
        wt = [w[points[j]] for j in keep]
        a = [rot.apply(base0, c.offsets[j]) for j in keep]
        turn = rot.kabsch(a, b, wt) if len(b) >= 2 else None
        if turn is None and len(b) >= 1:
            turn = rot.arc(rot.weighted_sum(a, wt), rot.weighted_sum(b, wt))
        hops = [rot.apply(base0, h) for h in c.hops] if turn is not None else []
        return base0, head0, keep, b, wt, turn, hops

    def _chain_levers(self, f: _Frame, c: _Chain, base0: rot.M, keep: list[int]):
        """Per kept point, the vector its carrier's turn moves (world axes, at rest) and a
        fixed part (the neck's head posed by its own rigid fit: not turned by the chain)."""
        given: dict[int, rot.M | None] = {}
        if c.name == "neck_chain":  # the head's own rigid fit places and turns it
            given = {r: self._rigid(f, i) for r, i in enumerate(c.tip_ids)}
        levers, fixed = [], []
        for j in keep:
            r = c.tip[j]
            if r < 0:
                levers.append(rot.apply(base0, c.lever[j]))
                fixed.append(rot.ZERO)
                continue
            tip, _, tip_head, tip_rest = c.tips[r]
            g = given.get(r)
            if g is None:  # the tip in its latest pose relative to the chain
                pose = rot.mul(tip_rest, self._last[tip])
                levers.append(rot.apply(base0, rot.add(tip_head, rot.apply(pose, c.lever[j]))))
                fixed.append(rot.ZERO)
            else:
                levers.append(rot.apply(base0, tip_head))
                fixed.append(rot.apply(g, c.lever[j]))
        return levers, fixed

    def _chain_points(self, c: _Chain, keep, axis, angle, hops, levers, fixed) -> list[rot.V]:
        """The kept keypoints relative to the chain's first head, with the chain's bones
        turned by ``angle`` * (k+1)/n about ``axis``."""
        n = len(c.steps)
        needed = max(c.carrier[j] for j in keep)
        trig = [(math.cos(angle * ((k + 1) / n)), math.sin(angle * ((k + 1) / n)))
                for k in range(needed + 1)]  # fmt: skip
        heads = [rot.ZERO]
        for k in range(1, needed + 1):
            cos_k, sin_k = trig[k - 1]
            heads.append(rot.add(heads[-1], rot.rotate(axis, cos_k, sin_k, hops[k])))
        out = []
        for j, lever, extra in zip(keep, levers, fixed, strict=True):
            k = c.carrier[j]
            moved = rot.rotate(axis, trig[k][0], trig[k][1], lever)
            h = heads[k]
            out.append((h[0] + moved[0] + extra[0], h[1] + moved[1] + extra[1],
                        h[2] + moved[2] + extra[2]))  # fmt: skip
        return out

    def _place_chain(self, f: _Frame, c: _Chain, base0: rot.M, head0: rot.V, axis: rot.V,
                     angle: float, hops: list[rot.V]) -> None:  # fmt: skip
        """Pose the chain's bones: bone k of n turned by angle * (k+1)/n about ``axis`` from
        its rest pose on the chain's base; bone by bone (``_finish``) where a joint limit
        bites. Relative to the bone before, each is turned by angle / n about that axis as
        its own rest frame sees it (rest frames are rigid), which gives its local rotation
        without a product of the posed frames; heads are the hops turned (Rodrigues)."""
        n = len(c.steps)
        if self._chain_bites(c, angle):
            for k, i in enumerate(c.steps):
                at_rest = rot.mul(base0, c.rest_rel[k])
                world_k = rot.mul(rot.turn(axis, angle * ((k + 1) / n)), at_rest)
                base_k, f.heads[i] = self._inherit(f, i)
                self._finish(f, i, base_k, rot.tmul(base_k, world_k))
            return
        ax0 = rot.tapply(base0, axis)  # the axis in the first bone's rest frame
        step = angle / n
        s, co = math.sin(step), math.cos(step)
        t = 1.0 - co
        world, head = base0, head0
        for k, i in enumerate(c.steps):
            x, y, z = rot.tapply(c.rest_rel[k], ax0)  # the axis in bone k's rest frame
            own = (co + t * x * x, t * x * y - s * z, t * x * z + s * y,
                   t * x * y + s * z, co + t * y * y, t * y * z - s * x,
                   t * x * z - s * y, t * y * z + s * x, co + t * z * z)  # fmt: skip
            if k:
                a_k = angle * (k / n)
                hx, hy, hz = rot.rotate(axis, math.cos(a_k), math.sin(a_k), hops[k])
                head = (head[0] + hx, head[1] + hy, head[2] + hz)
                world = rot.mul(world, c.rel[k])
            world = rot.mul(world, own)
            f.heads[i] = head
            self._last[i] = f.local[i] = own
            f.solved[i] = True
            f.world[i] = world

    def _place_tips_anchor(self, f: _Frame, c: _Chain, base0: rot.M, head0: rot.V,
                           axis: rot.V, angle: float, hops: list[rot.V]) -> None:  # fmt: skip
        """The first of two passes (``_solve_chain`` "first"): place only the chain bones
        its tips hang on (what the tips' solve reads), unless a limit bites."""
        if self._chain_bites(c, angle):
            self._place_chain(f, c, base0, head0, axis, angle, hops)
            return
        n = len(c.steps)
        head = head0
        for k in range(1, max(c.tip_on) + 1):
            a_k = angle * (k / n)
            hx, hy, hz = rot.rotate(axis, math.cos(a_k), math.sin(a_k), hops[k])
            head = (head[0] + hx, head[1] + hy, head[2] + hz)
            if k in c.tip_on:
                f.heads[c.steps[k]] = head
        for k in set(c.tip_on):
            at_rest = rot.mul(base0, c.rest_rel[k])
            f.world[c.steps[k]] = rot.mul(rot.turn(axis, angle * ((k + 1) / n)), at_rest)
        if 0 in c.tip_on:
            f.heads[c.steps[0]] = head0

    def _chain_bites(self, c: _Chain, angle: float) -> bool:
        """Whether a joint limit stops a chain bone's share of ``angle`` (radians, >= 0)."""
        if not self.settings.limits:
            return False
        n = len(c.steps)
        return any(angle * ((k + 1) / n) - angle * (k / n) > c.limits[k] for k in range(n))

    def _rigid(self, f: _Frame, i: int) -> rot.M | None:
        """World rotation of bone i from a rigid fit (rotation and translation) of its own
        keypoints, or None when they do not fix one."""
        b = self._bone[i]
        keep = [r for r, k in enumerate(b.points) if f.ok[k]]
        if len(keep) < 3:
            return None
        a = [b.offsets[r] for r in keep]
        q = [f.p[b.points[r]] for r in keep]
        wt = [f.w[b.points[r]] for r in keep]
        total = sum(wt)
        ca = _scaled(rot.weighted_sum(a, wt), 1 / total)
        cb = _scaled(rot.weighted_sum(q, wt), 1 / total)
        return rot.kabsch([rot.sub(v, ca) for v in a], [rot.sub(v, cb) for v in q], wt)

    # -- single bones ---------------------------------------------------------------------

    def _solve_bone(self, f: _Frame, i: int) -> None:
        """Swing (and twist) a bone onto its keypoints: a rigid turn where two or more
        points fix one, else the shortest arc onto their weighted direction, twisted into
        the limb's plane for upper arms and thighs. Solved in the bone's rest frame on its
        anchor (``base``): the same turn as in the world, conjugated, one product fewer."""
        b = self._bone[i]
        wa = f.world[b.anchor]
        base = rot.mul(wa, b.rel)
        head = f.heads[i] = rot.add(f.heads[b.anchor], rot.apply(wa, b.step))
        ok, p = f.ok, f.p
        if len(b.points) == 1:  # most bones: one keypoint, a swing (written out: hot path)
            k = b.points[0]
            if not ok[k]:
                self._finish(f, i, base, None)
                return
            origin = p[b.origin] if b.origin >= 0 and ok[b.origin] else head
            wk, q = f.w[k], p[k]
            along = ((q[0] - origin[0]) * wk, (q[1] - origin[1]) * wk, (q[2] - origin[2]) * wk)
            o = b.offsets[0]
            swing = _arc_in(base, (o[0] * wk, o[1] * wk, o[2] * wk), along)
            if b.pole is not None:
                swing = self._twist(f, b, base, swing, along)
            self._finish(f, i, base, swing)
            return
        keep = [r for r, k in enumerate(b.points) if ok[k]]
        if not keep:
            self._finish(f, i, base, None)
            return
        origin = p[b.origin] if b.origin >= 0 and ok[b.origin] else head
        seen = [rot.sub(p[b.points[r]], origin) for r in keep]  # world, from the joint
        wt = [f.w[b.points[r]] for r in keep]
        rest = [b.offsets[r] for r in keep]
        local = None
        if len(keep) >= 2:
            local = rot.kabsch(rest, [rot.tapply(base, v) for v in seen], wt)
        if local is None:
            along = rot.weighted_sum(seen, wt)
            local = _arc_in(base, rot.weighted_sum(rest, wt), along)
            if b.pole is not None:
                local = self._twist(f, b, base, local, along)
        self._finish(f, i, base, local)

    def _twist(self, f: _Frame, b: _Bone, base: rot.M, local: rot.M, along: rot.V) -> rot.M:
        """Turn a limb's upper bone about its own axis so its bend axis lies along the
        normal of the observed plane of the limb's three joints (weighted by how bent the
        limb is: a straight limb keeps the swing's twist). In the base frame."""
        assert b.pole is not None
        mid, far, pole_axis = b.pole
        ok, p = f.ok, f.p
        if not (b.origin >= 0 and ok[b.origin] and ok[mid] and ok[far]):
            return local
        upper, lower = rot.sub(p[mid], p[b.origin]), rot.sub(p[far], p[mid])
        normal = rot.cross(upper, lower)
        bend = math.sqrt(rot.dot(normal, normal)) / (
            math.sqrt(rot.dot(upper, upper) * rot.dot(lower, lower)) + 1e-12
        )
        weight = min(max((bend - 0.05) / 0.15, 0.0), 1.0)  # sin of the bend: 3..11 degrees
        if not weight > 0:
            return local
        d = rot.unit(rot.tapply(base, along))
        have = rot.apply(local, pole_axis)
        have = rot.sub(have, _scaled(d, rot.dot(have, d)))
        want = rot.tapply(base, normal)
        want = rot.sub(want, _scaled(d, rot.dot(want, d)))
        if rot.dot(have, have) < 1e-12 or rot.dot(want, want) < 1e-12:
            return local
        angle = math.atan2(rot.dot(rot.cross(have, want), d), rot.dot(have, want))
        return rot.mul(rot.turn(d, weight * angle), local)

    # -- output ----------------------------------------------------------------------------

    def _output(self, f: _Frame, t: float, contacts: np.ndarray) -> SolvedFrame:
        n = self._count
        frames = np.array(f.local + f.world)  # (2S, 9): one conversion for both
        rotations = self._identity.copy()
        rotations[self._bones] = rot.quaternions(frames[:n])
        translations = np.zeros((len(self._identity), 3))
        translations[self._hips] = rot.tapply(self._hips_rest, rot.sub(f.heads[0], self._hips_head))
        points = np.full((len(self.rig.keypoints.names), 3), np.nan)
        own = self._point_owner
        world = frames[n:].reshape(-1, 3, 3)[own]
        points[self._point_ids] = np.array(f.heads)[own] + (world @ self._point_offsets)[:, :, 0]
        return SolvedFrame(rotations, translations, points, t, np.array(f.solved), contacts)


def _length(v: Sequence[float]) -> float:
    return math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])


def _scaled(v: Sequence[float], s: float) -> rot.V:
    return (v[0] * s, v[1] * s, v[2] * s)


def _arc_in(base: rot.M, rest: rot.V, along: rot.V) -> rot.M:
    """The shortest arc taking the world direction ``base @ rest`` onto ``along``, as a turn
    in the frame ``base`` (``base.T @ arc @ base``). When the two are parallel or either is
    zero the arc is the identity or a half turn whose axis depends on the frame: that rare
    case is computed in world axes, as before, and brought into the frame."""
    mine = rot.tapply(base, along)
    ax, ay, az = rot.unit(rest)
    bx, by, bz = rot.unit(mine)
    cx, cy, cz = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx
    s2 = cx * cx + cy * cy + cz * cz
    if s2 >= 1e-17:  # ``rot.arc(rest, mine)``, written out (s > 1e-9: its general case)
        s = math.sqrt(s2)
        return rot.turn((cx / s, cy / s, cz / s), math.atan2(s, ax * bx + ay * by + az * bz))
    world = rot.arc(rot.apply(base, rest), along)
    return rot.tmul(base, rot.mul(world, base))


@dataclass(slots=True)
class _Frame:
    """One frame's working state: keypoints (K) as 3-sequences, ok (K) bools, weights (K),
    and per solved bone (S, in the plan's order) world rotations and local rotations (9-
    tuples, row-major), heads (3-tuples, metres) and solved flags."""

    p: list
    ok: list
    w: list
    world: list
    heads: list
    local: list
    solved: list
    decay: float
    fits: dict  # chain name -> its initial fit, kept between the spine's two passes


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

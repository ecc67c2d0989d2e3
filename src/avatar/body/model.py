"""The parametric body: parameters -> vertex positions of the full MakeHuman mesh.

Parameters (all floats):
- the eleven macros of ``macros.MACROS`` (0..1, MakeHuman 1.1 semantics; gender 0 = female);
- local modifiers by MakeHuman name (``torso/torso-scale-depth-decr|incr``; -1..1 or 0..1),
  also reachable by their short name (``torso-scale-depth``) when that is unique;
- the seven semantic attributes ``pca/<name>`` (see ``attributes``; in standard deviations);
- the 52 ARKit face units ``expression/<name>`` (0..1).

Out-of-range values are clamped to the range (and logged); non-finite values and unknown
names raise ``ParameterError``.
"""

from __future__ import annotations

import logging
import math
import os
import threading
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from avatar.body import assets, macros
from avatar.body.attributes import ATTRIBUTES, basis
from avatar.body.modifiers import Modifier, modifiers_from_target_json
from avatar.errors import ParameterError, unknown_name
from avatar.mesh import Mesh
from avatar.rig.skinning import SkinWeights

_SHARED = threading.local()  # BodyModel.shared: (environment key, model) per thread

log = logging.getLogger(__name__)

BODY_VERTICES = 13380  # vertices 0..13379 are skin; the rest is helper geometry, eyes, teeth
FLAT_INDEX_CACHE = 128  # local targets whose flat scatter indices are kept (see _flat_index)


_SCRATCH = threading.local()  # _axpy's product buffer, one per thread (grown on demand)


def _axpy(a: float, x: np.ndarray, y: np.ndarray, first: int = 0, end: int | None = None) -> None:
    """``y[first:end] += a * x[first:end]`` in place for float32 vectors, single-threaded.

    Two numpy passes through a per-thread scratch buffer (no allocation): BLAS ``saxpy``
    would fuse them, but OpenBLAS runs it on every core, and on a loaded machine a thread
    hand-off costs far more than the arithmetic (32 ms a call against 0.006 ms; issue 13).
    The product is rounded to float32 before the add, so a sum may differ from a fused
    multiply-add by an ulp (~1e-8 m here).
    """
    end = len(y) if end is None else end
    n = end - first
    buffer = getattr(_SCRATCH, "buffer", None)
    if buffer is None or len(buffer) < n:
        buffer = _SCRATCH.buffer = np.empty(max(n, 1 << 16), dtype=np.float32)  # 256 kB
    product = buffer[:n]
    target = y[first:end]
    np.multiply(x[first:end], np.float32(a), out=product)
    np.add(target, product, out=target)


# Level names of each macro group, as ``macros.level_weights`` names them. A group's level
# weights depend on its own macros only; the races form one group (they are normalised together).
GROUP_LEVELS: dict[str, tuple[str, ...]] = {
    "gender": ("female", "male"),
    "age": ("baby", "child", "young", "old"),
    "muscle": ("minmuscle", "averagemuscle", "maxmuscle"),
    "weight": ("minweight", "averageweight", "maxweight"),
    "height": ("minheight", "averageheight", "maxheight"),
    "proportions": ("uncommonproportions", "regularproportions", "idealproportions"),
    "cupsize": ("mincup", "averagecup", "maxcup"),
    "firmness": ("minfirmness", "averagefirmness", "maxfirmness"),
    "race": macros.RACES,
}
MACRO_GROUP = {m: "race" if m in macros.RACES else m for m in macros.MACROS}


class MacroSum:
    """The weighted sum of MakeHuman's macro targets, fast for interactive editing.

    A full sum adds each active row of the dense (M, V*3) matrix with one BLAS axpy over the
    range the row touches: ~80 rows, ~18 MB read, memory-bound (~0.75 ms on a 2-core EPYC,
    see bench/shape.py). Two memos make the common edits cheaper:

    - the last full sum, reused when the macros did not change (a local or attribute edit);
    - a contraction on one macro group, built when the same group changes twice in a row
      (a slider being dragged). The sum is linear in that group's level weights,
      ``D = C0 + sum_l w_l C_l``, so after one pass building C0 and the C_l (~1.5 full
      sums) each new value of that slider costs at most four axpys. Its results are not
      copied into the first memo: re-evaluating is as cheap, and every 230 kB buffer saved
      spares the allocator (fresh pages cost more than the arithmetic here).

    Memos are replaced whole, never mutated, and every result is a fresh array: ``shape``
    stays a pure function of its parameters. Results agree with a plain float32 sum within
    float32 rounding (~1e-7 m); with ``contract`` off (``BodyModel.shared``, outside
    ``BodyModel.dragging``) they are that sum exactly, whatever bodies came before
    (reproducible datasets): a contraction built earlier is then not used either.
    """

    contract = True  # build and use the drag contraction (faster edits, history-dependent rounding)

    def __init__(self, table: macros.MacroTable, dense: np.ndarray, spans: list[tuple[int, int]]):
        self.table = table
        self.dense = dense  # (M, V*3) float32
        self.spans = spans  # per row, the [first, end) range of the flat layout it touches
        self._last: tuple[tuple[float, ...], np.ndarray | None, str | None] | None = None
        self._contraction: _Contraction | None = None

    def __call__(self, values: Mapping[str, float]) -> np.ndarray:
        """(V*3,) float32 sum of the macro targets for resolved ``values`` (a fresh array)."""
        key = tuple(float(values.get(k, d)) for k, (_, d) in macros.MACROS.items())
        last, con = self._last, self._contraction
        if self.contract and con is not None and con.others == _others(key, con.group):
            flat = con.evaluate(values)  # cheap: no need to keep a copy of the result
            self._last = (key, None, con.group)
            return flat
        if last is not None and last[0] == key and last[1] is not None:
            return last[1].copy()
        edited = _changed_group(last[0], key) if last is not None else None
        if self.contract and edited is not None and last is not None and edited == last[2]:
            con = self._contraction = self._contract(edited, values, key)
            self._last = (key, None, edited)
            return con.evaluate(values)
        flat = self.full(values)
        self._last = (key, flat.copy(), edited)
        return flat

    def full(self, values: Mapping[str, float]) -> np.ndarray:
        """(V*3,) float32 sum of every active macro target, without memos."""
        mw = self.table.weights(values)
        flat = np.zeros(self.dense.shape[1], dtype=np.float32)
        for r in np.flatnonzero(mw).tolist():
            _axpy(float(mw[r]), self.dense[r], flat, *self.spans[r])
        return flat

    def _contract(self, group: str, values: Mapping[str, float], key: tuple) -> _Contraction:
        """``group``'s contraction at ``values``: C_l per level and C0 (key None) for the rest."""
        mine = GROUP_LEVELS[group]
        levels = macros.level_weights(values)
        names = self.table.level_names
        vec = np.array([1.0 if n in mine else levels.get(n, 0.0) for n in names] + [1.0])
        rest = np.prod(vec[self.table.factor_index], axis=1)  # row weights less group's factor
        parts: dict[str | None, np.ndarray] = {None: np.zeros(self.dense.shape[1], np.float32)}
        for r in np.flatnonzero(rest).tolist():
            level = next((c for c in self.table.components[r] if c in mine), None)
            part = parts.setdefault(level, np.zeros(self.dense.shape[1], np.float32))
            _axpy(float(rest[r]), self.dense[r], part, *self.spans[r])
        return _Contraction(group, _others(key, group), parts)


@dataclass(frozen=True)
class _Contraction:
    """The macro sum as a linear function of one group's level weights (see ``MacroSum``)."""

    group: str
    others: tuple  # the values of the other macros, fixed
    parts: dict[str | None, np.ndarray]  # level -> C_l; None -> C0

    def evaluate(self, values: Mapping[str, float]) -> np.ndarray:
        """(V*3,) float32 C0 + sum_l w_l C_l at ``values``."""
        levels = macros.level_weights(values)
        flat = self.parts[None].copy()
        for level, part in self.parts.items():
            if level is not None and levels[level] != 0.0:
                _axpy(levels[level], part, flat)
        return flat


def _others(key: tuple[float, ...], group: str) -> tuple:
    """``key`` (macro values in ``MACROS`` order) with ``group``'s own values blanked."""
    return tuple(
        None if MACRO_GROUP[m] == group else v for m, v in zip(macros.MACROS, key, strict=True)
    )


def _changed_group(old: tuple[float, ...], new: tuple[float, ...]) -> str | None:
    """The one macro group whose values differ between two keys, else None."""
    groups = {MACRO_GROUP[m] for m, a, b in zip(macros.MACROS, old, new, strict=True) if a != b}
    return groups.pop() if len(groups) == 1 else None


@dataclass(frozen=True)
class Parameter:
    """A named body parameter with its range and default."""

    name: str
    kind: str  # "macro" | "modifier" | "attribute" | "expression"
    minimum: float
    maximum: float
    default: float
    mhm_name: str | None = None


class BodyModel:
    """MakeHuman 1.1's body model over compiled assets. Immutable; ``shape`` is pure."""

    def __init__(self, compiled: assets.CompiledAssets):
        self.assets = compiled
        self.base: Mesh = compiled.base
        a = compiled.arrays
        # Plain ndarray views of the memory-mapped cache (no copy): np.memmap runs Python hooks
        # on every slice, which cost more than the arithmetic on a small target.
        self._macro_dense = np.asarray(a["macro_dense"])
        self._offsets = np.asarray(a["target_offsets"])
        self._index = np.asarray(a["target_index"])
        self._delta = np.asarray(a["target_delta"])
        self.target_names: list[str] = compiled.target_names
        self.target_id = {n: i for i, n in enumerate(self.target_names)}
        self.macro_table = macros.MacroTable(self.target_names)
        self.modifiers: list[Modifier] = modifiers_from_target_json(
            compiled.meta["target_json"], self.target_names
        )
        self._attributes: dict[str, np.ndarray] = {}
        self._flat_indices: dict[int, np.ndarray] = {}  # target id -> flat positions (lazy)
        self._skin_weights: dict[tuple, SkinWeights] = {}  # (rig, bone names) -> weights
        self.macro_sum = MacroSum(self.macro_table, self._macro_dense, self._macro_spans())

    @classmethod
    def load(cls, data_dir: str | None = None, progress: bool = False) -> BodyModel:
        """The body model over the installed MakeHuman assets (compiled on first use, with
        a progress bar when ``progress``)."""
        return cls(assets.load(data_dir, progress=progress))

    @classmethod
    def shared(cls, progress: bool = False) -> BodyModel:
        """This thread's model over the default assets, loaded once (a load takes ~50 ms,
        a body ~1 ms): what ``Human`` uses when given no model. Per thread because a model
        memoises its last shape; a change of ``AVATAR_ASSETS`` or ``AVATAR_CACHE`` loads
        anew. Its shapes are exact sums (no drag contraction, except inside ``dragging``),
        so a body is bit for bit the same whichever bodies were made before it."""
        key = (os.environ.get("AVATAR_ASSETS"), os.environ.get("AVATAR_CACHE"))
        cached = getattr(_SHARED, "model", None)
        if cached is None or cached[0] != key:
            model = cls.load(progress=progress)
            model.macro_sum.contract = False
            _SHARED.model = cached = (key, model)
        return cached[1]

    @contextmanager
    def dragging(self) -> Iterator[BodyModel]:
        """Within the block, shapes may use the drag contraction (``MacroSum``): a slider
        dragged live costs ~4 axpys a step instead of a full macro sum, its bodies within
        float32 rounding of the exact sum (~1e-7 m, depending on the bodies made before).
        After it the model's setting is back (a shared model's sums exact again)."""
        before = self.macro_sum.contract
        self.macro_sum.contract = True
        try:
            yield self
        finally:
            self.macro_sum.contract = before

    def skin_weights(self, rig: str, bone_names: tuple[str, ...]) -> SkinWeights:
        """Skin weights of all base-mesh vertices over a rig's bones (built once per rig)."""
        key = (rig, bone_names)
        if key not in self._skin_weights:
            bones, offsets, vertex, weight = self.assets.weights(rig)
            bone_ids = self._weight_bones(rig, bones, bone_names)
            bone_of_entry = np.repeat(bone_ids, np.diff(offsets))
            keep = bone_of_entry >= 0
            bone_of_entry, vertex, weight = bone_of_entry[keep], vertex[keep], weight[keep]
            # several bones of the weights' rig may land on one bone of this rig: one entry
            pairs = vertex.astype(np.int64) * len(bone_names) + bone_of_entry
            merged, inverse = np.unique(pairs, return_inverse=True)
            if len(merged) < len(pairs):
                weight = np.bincount(inverse, weights=weight)
                bone_of_entry, vertex = merged % len(bone_names), merged // len(bone_names)
            self._skin_weights[key] = SkinWeights.from_lists(
                len(self.base.vertices), bone_of_entry, vertex, weight
            )
        return self._skin_weights[key]

    def _weight_bones(self, rig: str, bones: list[str], bone_names: tuple[str, ...]):
        """(len(bones),) index in ``bone_names`` of each bone of the rig's weights file; a
        bone this rig lacks (default_no_toes uses the default rig's weights, toes included)
        gives its weights to its nearest ancestor that the rig has, as MakeHuman does
        (else the toes would follow the root); -1: none."""
        index = {b: i for i, b in enumerate(bone_names)}
        source = self.assets.rig(assets.WEIGHTS_FILE.get(rig, rig))
        out = []
        for b in bones:
            while b is not None and b not in index:
                b = source.get(b, {}).get("parent")
            out.append(index[b] if b is not None else -1)
        return np.array(out, dtype=int)

    # ------------------------------------------------------------------ parameters
    @cached_property
    def parameters(self) -> dict[str, Parameter]:
        """Every parameter by canonical name."""
        out: dict[str, Parameter] = {}
        for name, (mhm, default) in macros.MACROS.items():
            out[name] = Parameter(name, "macro", 0.0, 1.0, default, mhm)
        for m in self.modifiers:
            out[m.name] = Parameter(m.name, "modifier", m.minimum, 1.0, 0.0, m.name)

        for attr in ATTRIBUTES:
            out[f"pca/{attr.name}"] = Parameter(f"pca/{attr.name}", "attribute", -3.0, 3.0, 0.0)
        for n in self.target_names:
            if n.startswith("faceunits/"):
                name = "expression/" + n.split("/", 1)[1]
                out[name] = Parameter(name, "expression", 0.0, 1.0, 0.0)
        return out

    @cached_property
    def aliases(self) -> dict[str, str]:
        """Alternative names -> canonical: short modifier names and MakeHuman macro names."""
        out = {p.mhm_name: p.name for p in self.parameters.values() if p.mhm_name}
        shorts: dict[str, list[str]] = {}
        for m in self.modifiers:
            shorts.setdefault(m.short_name, []).append(m.name)
        out |= {s: names[0] for s, names in shorts.items() if len(names) == 1}
        return out

    def canonical(self, name: str) -> str:
        """Canonical parameter name for ``name`` or one of its aliases."""
        if name in self.parameters:
            return name
        if name in self.aliases:
            return self.aliases[name]
        raise unknown_name("parameter", name, list(self.parameters) + list(self.aliases))

    def resolve(self, params: Mapping[str, float] | None) -> dict[str, float]:
        """Validated canonical values, clamped to each parameter's range."""
        out: dict[str, float] = {}
        for key, raw in (params or {}).items():
            name = self.canonical(key)
            try:
                value = float(raw)
            except (TypeError, ValueError):
                raise ParameterError(f"parameter {key!r} must be a number, got {raw!r}") from None
            if not math.isfinite(value):
                raise ParameterError(f"parameter {key!r} must be finite, got {value}")
            p = self.parameters[name]
            clamped = min(max(value, p.minimum), p.maximum)
            if clamped != value:
                log.warning("%s=%g clamped to [%g, %g]", key, value, p.minimum, p.maximum)
            out[name] = clamped
        return out

    def defaults(self) -> dict[str, float]:
        """The default value of every macro (other parameters default to 0)."""
        return {n: d for n, (_, d) in macros.MACROS.items()}

    # ------------------------------------------------------------------ evaluation
    def target_weights(
        self, values: Mapping[str, float]
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Active targets for resolved ``values``.

        Returns (macro rows (m,), their weights (m,), local target ids (n,), weights (n,)).
        """
        mw = self.macro_table.weights(values) if any(k in values for k in macros.MACROS) else None
        rows = np.flatnonzero(mw) if mw is not None else np.zeros(0, np.int64)
        local_ids, local_w = [], []
        for name, v in values.items():
            if v == 0.0 or "/" not in name:
                continue
            kind, _, rest = name.partition("/")
            if kind == "expression":
                local_ids.append(self.target_id["faceunits/" + rest])
                local_w.append(v)
            elif kind != "pca":
                mod = self._modifier_by_name[name]
                target = mod.positive if v > 0 else mod.negative
                assert target is not None
                local_ids.append(self.target_id[target])
                local_w.append(abs(v))
        row_w = mw[rows] if mw is not None else np.zeros(0)
        return rows, row_w, np.asarray(local_ids, np.int64), np.asarray(local_w, np.float64)

    @cached_property
    def _modifier_by_name(self) -> dict[str, Modifier]:
        return {m.name: m for m in self.modifiers}

    def _macro_spans(self) -> list[tuple[int, int]]:
        """Per macro row, the [first, end) range of the flat (V*3,) layout its target touches.

        Adding a row is then one contiguous BLAS axpy over that range; even the sparse breast
        targets (~3% of the vertices) are 3x cheaper so than scattered by index.
        """
        spans = []
        for t in self.macro_table.columns:
            idx = self._index[self._offsets[t] : self._offsets[t + 1]]
            spans.append((3 * int(idx.min()), 3 * int(idx.max()) + 3) if len(idx) else (0, 0))
        return spans

    def _flat_index(self, t: int) -> np.ndarray:
        """(3n,) positions of target ``t``'s offsets in the flat (V*3,) layout (cached).

        Scattering into a flat array is ~2x faster than into (V, 3) rows, which numpy copies
        one 12-byte row at a time.
        """
        idx = self._flat_indices.get(t)
        if idx is None:
            if len(self._flat_indices) >= FLAT_INDEX_CACHE:  # bound the memory (~0.1 MB each)
                self._flat_indices.clear()
            rows = self._index[self._offsets[t] : self._offsets[t + 1]].astype(np.intp)
            idx = self._flat_indices[t] = (3 * rows[:, None] + np.arange(3)).ravel()
        return idx

    def displacement(self, values: Mapping[str, float]) -> np.ndarray:
        """(V, 3) float32 sum of the weighted targets of resolved ``values``.

        Macro targets count only when ``values`` names a macro (``shape`` passes all of them).
        """
        if any(k in values for k in macros.MACROS):
            flat = self.macro_sum(values)
        else:
            flat = np.zeros(self._macro_dense.shape[1], dtype=np.float32)
        _, _, ids, ids_w = self.target_weights({k: v for k, v in values.items() if "/" in k})
        for t, w in zip(ids.tolist(), ids_w.tolist(), strict=True):
            delta = self._delta[self._offsets[t] : self._offsets[t + 1]].reshape(-1)
            flat[self._flat_index(t)] += np.float32(w) * delta
        return flat.reshape(-1, 3)

    def shape(self, params: Mapping[str, float] | None = None) -> np.ndarray:
        """(19158, 3) float32 vertex positions (metres, Z-up) of the body with ``params``.

        Includes helper geometry (joint cubes, tights, skirt, hair) that drives rigging and
        clothes fitting. Unlisted macros take their defaults.
        """
        values = self.defaults() | self.resolve(params)
        verts = self.displacement(values)
        attrs = {k[4:]: v for k, v in values.items() if k.startswith("pca/") and v != 0.0}
        if attrs:
            flat, components = verts.reshape(-1), basis(self)
            for name, v in attrs.items():
                _axpy(v, components[name].reshape(-1), flat)
        verts += self.base.vertices
        return verts

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
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from avatar import assets
from avatar.body import macros
from avatar.body.modifiers import Modifier, modifiers_from_target_json
from avatar.errors import ParameterError, unknown_name
from avatar.mesh import Mesh

log = logging.getLogger(__name__)

BODY_VERTICES = 13380  # vertices 0..13379 are skin; the rest is helper geometry, eyes, teeth


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
        self._macro_dense = a["macro_dense"]
        self._offsets = np.asarray(a["target_offsets"])
        self._index = a["target_index"]
        self._delta = a["target_delta"]
        self.target_names: list[str] = compiled.target_names
        self.target_id = {n: i for i, n in enumerate(self.target_names)}
        self.macro_table = macros.MacroTable(self.target_names)
        self.modifiers: list[Modifier] = modifiers_from_target_json(
            compiled.meta["target_json"], self.target_names
        )
        self._attributes: dict[str, np.ndarray] = {}

    @classmethod
    def load(cls, data_dir: str | None = None) -> BodyModel:
        """The body model over the installed MakeHuman assets (compiled on first use)."""
        return cls(assets.load(data_dir))

    # ------------------------------------------------------------------ parameters
    @cached_property
    def parameters(self) -> dict[str, Parameter]:
        """Every parameter by canonical name."""
        out: dict[str, Parameter] = {}
        for name, (mhm, default) in macros.MACROS.items():
            out[name] = Parameter(name, "macro", 0.0, 1.0, default, mhm)
        for m in self.modifiers:
            out[m.name] = Parameter(m.name, "modifier", m.minimum, 1.0, 0.0, m.name)
        from avatar.body.attributes import ATTRIBUTES

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

    def displacement(self, values: Mapping[str, float]) -> np.ndarray:
        """(V, 3) float32 sum of the weighted targets of resolved ``values``.

        Macro targets count only when ``values`` names a macro (``shape`` passes all of them).
        """
        rows, row_w, ids, ids_w = self.target_weights(values)
        flat = np.zeros(self._macro_dense.shape[1], dtype=np.float32)
        scratch = np.empty_like(flat)
        for r, w in zip(rows.tolist(), row_w.tolist(), strict=True):
            np.multiply(self._macro_dense[r], np.float32(w), out=scratch)
            flat += scratch
        out = flat.reshape(-1, 3)
        for t, w in zip(ids.tolist(), ids_w.tolist(), strict=True):
            s, e = self._offsets[t], self._offsets[t + 1]
            out[self._index[s:e]] += np.float32(w) * self._delta[s:e]
        return out

    def shape(self, params: Mapping[str, float] | None = None) -> np.ndarray:
        """(19158, 3) float32 vertex positions (metres, Z-up) of the body with ``params``.

        Includes helper geometry (joint cubes, tights, skirt, hair) that drives rigging and
        clothes fitting. Unlisted macros take their defaults.
        """
        values = self.defaults() | self.resolve(params)
        verts = self.base.vertices + self.displacement(values)
        attrs = {k[4:]: v for k, v in values.items() if k.startswith("pca/") and v != 0.0}
        if attrs:
            from avatar.body.attributes import attribute_displacement

            verts = verts + attribute_displacement(self, attrs)
        return verts.astype(np.float32)

"""MakeHuman proxy files (``.mhclo``: clothes, hair, eyebrows, eyelashes, proxies).

Spec: MakeHuman 1.1 ``apps/proxy.py`` (``loadTextProxy``). ``key value`` lines; after
``verts 0`` each line is a reference, either one base-mesh vertex index or three indices,
three weights and an optional offset ``dx dy dz`` (decimetres, Y-up). ``x_scale a b d`` (and
``y_``, ``z_``) give the offset's per-axis scale. After ``delete_verts``, lines list base-mesh
vertices to hide, ``a - b`` meaning the inclusive range. Keyword lines may appear anywhere,
including between reference lines (MakeHuman checks keywords before the section state).

``Binding`` (the reference lines as arrays) is defined here, with its format, and used by
``avatar.clothes.binding``, which evaluates it on a body.

Reading converts to Avatar's frame once (``Binding`` is in metres, Z-up); writing converts
back and chooses, per number, the shortest decimal that reads back to the same float, so
``read(write(p)) == p`` exactly.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from avatar.errors import FormatError
from avatar.io import atomic

BASE_VERTEX_COUNT = 19158  # hm08
# MakeHuman scale line -> the Avatar axis it measures (x -> x, y-up -> z, z-forward -> y).
_MH_TO_AVATAR = {"x_scale": 0, "y_scale": 2, "z_scale": 1}
_STRING_KEYS = ("name", "uuid", "basemesh", "obj_file", "material", "vertexboneweights_file")


@dataclass(frozen=True)
class Binding:
    """A garment's attachment to the body (N garment vertices).

    indices: (N, 3) int32 body vertex indices (a single-vertex reference repeats its index).
    weights: (N, 3) float64 barycentric weights; (1, 0, 0) for single-vertex references.
    offsets: (N, 3) float64 offsets in metres, Avatar axes, before scaling.
    single: (N,) bool, True where the vertex was stored as a single-vertex reference.
    scale_refs: (3, 2) int32 body vertex pair measuring each Avatar axis (x, y, z);
        (-1, -1) for an axis without scaling (S = 1).
    scale_lengths: (3,) float64 the pair's extent along that axis on the authoring body (m).
    """

    indices: np.ndarray
    weights: np.ndarray
    offsets: np.ndarray
    single: np.ndarray
    scale_refs: np.ndarray
    scale_lengths: np.ndarray

    def __len__(self) -> int:
        return int(self.indices.shape[0])

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Binding):
            return NotImplemented
        return all(
            np.array_equal(getattr(self, k), getattr(other, k))
            for k in ("indices", "weights", "offsets", "single", "scale_refs", "scale_lengths")
        )

    __hash__ = None  # type: ignore[assignment]

    def subset(self, index: np.ndarray) -> Binding:
        """The binding of the garment vertices ``index`` only (e.g. after dropping faces)."""
        return Binding(
            self.indices[index],
            self.weights[index],
            self.offsets[index],
            self.single[index],
            self.scale_refs,
            self.scale_lengths,
        )


def make_binding(
    indices: np.ndarray,
    weights: np.ndarray,
    offsets: np.ndarray,
    scale_refs: np.ndarray | None = None,
    scale_lengths: np.ndarray | None = None,
    single: np.ndarray | None = None,
) -> Binding:
    """A Binding from array-likes, with dtypes and shapes normalised (no scaling by default)."""
    indices = np.asarray(indices, dtype=np.int32).reshape(-1, 3)
    n = len(indices)
    refs = np.full((3, 2), -1, np.int32) if scale_refs is None else scale_refs
    lengths = np.ones(3) if scale_lengths is None else scale_lengths
    return Binding(
        indices=indices,
        weights=np.asarray(weights, dtype=np.float64).reshape(n, 3),
        offsets=np.asarray(offsets, dtype=np.float64).reshape(n, 3),
        single=np.zeros(n, bool) if single is None else np.asarray(single, bool).reshape(n),
        scale_refs=np.asarray(refs, dtype=np.int32).reshape(3, 2),
        scale_lengths=np.asarray(lengths, dtype=np.float64).reshape(3),
    )


@dataclass(frozen=True)
class ProxyFile:
    """The contents of a ``.mhclo`` file.

    binding: the N reference lines (Avatar frame).
    delete_verts: (D,) int32 sorted base-mesh vertices the garment hides.
    z_depth: layer order (MakeHuman: 5 face proxies, 50 clothes, higher = outer).
    obj_file, material, vertexboneweights_file: names relative to the file's folder.
    tags: lower-case tags in file order.
    meta: other keyword lines (key, rest of line) in file order, kept verbatim
        (``author``, ``license``, ``description``, ``version``, ``special_pose``, ...).
    comments: the leading ``#`` comment lines (MakeHuman keeps licence text there).
    """

    name: str
    binding: Binding
    uuid: str = ""
    basemesh: str = "hm08"
    obj_file: str = ""
    material: str = ""
    vertexboneweights_file: str = ""
    z_depth: int = 50
    tags: tuple[str, ...] = ()
    delete_verts: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int32))
    meta: tuple[tuple[str, str], ...] = ()
    comments: tuple[str, ...] = ()

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, ProxyFile):
            return NotImplemented
        plain = [k for k in self.__dataclass_fields__ if k != "delete_verts"]
        return all(getattr(self, k) == getattr(other, k) for k in plain) and np.array_equal(
            self.delete_verts, other.delete_verts
        )

    __hash__ = None  # type: ignore[assignment]


class _Parser:
    """Line-by-line state of one file; collects references and keywords."""

    def __init__(self, path: str | os.PathLike[str] | None, vertex_count: int):
        self.path = path
        self.vertex_count = vertex_count
        self.section = ""
        self.refs: list[list[str]] = []
        self.ref_lines: list[int] = []
        self.deleted: list[int] = []
        self.strings: dict[str, str] = {}
        self.scales: dict[str, tuple[int, int, float]] = {}
        self.z_depth = 50
        self.tags: list[str] = []
        self.meta: list[tuple[str, str]] = []
        self.comments: list[str] = []

    def error(self, line: int, message: str) -> FormatError:
        return FormatError(self.path, line, message)

    def feed(self, lineno: int, raw: str) -> None:
        words = raw.split()
        if not words:
            return
        key = words[0]
        if key.startswith("#"):
            if not self.refs and not self.strings:
                self.comments.append(raw.rstrip("\n"))
            return
        rest = raw.strip()[len(key) :].strip()
        if key[0].isdigit() or key == "-":
            self._number_line(lineno, words)
        elif key in ("verts", "delete_verts"):
            self.section = key
        elif key in _STRING_KEYS:
            self.strings[key] = rest
        elif key == "tag":
            self.tags.append(rest.lower())
        elif key == "z_depth":
            self.z_depth = self._int(lineno, words, 1)
        elif key in _MH_TO_AVATAR:
            if len(words) != 4:
                raise self.error(lineno, f"{key} needs 'vertex vertex length', got {rest!r}")
            a, b = self._int(lineno, words, 1), self._int(lineno, words, 2)
            self._check_index(lineno, [a, b])
            self.scales[key] = (a, b, self._float(lineno, words[3]))
        else:
            self.meta.append((key, rest))

    def _number_line(self, lineno: int, words: list[str]) -> None:
        if self.section == "verts":
            if len(words) not in (1, 6, 9):
                raise self.error(
                    lineno, f"a reference has 1, 6 or 9 numbers, this one has {len(words)}"
                )
            self.refs.append(words)
            self.ref_lines.append(lineno)
        elif self.section == "delete_verts":
            self.deleted.extend(self._ranges(lineno, words))
        else:
            raise self.error(lineno, "numbers before any 'verts' or 'delete_verts' line")

    def _ranges(self, lineno: int, words: list[str]) -> list[int]:
        out: list[int] = []
        pending_range = False
        for w in words:
            if w == "-":
                if not out or pending_range:
                    raise self.error(lineno, "a '-' range needs a start vertex")
                pending_range = True
                continue
            v = self._int(lineno, [w], 0)
            if pending_range:
                if v < out[-1]:
                    raise self.error(lineno, f"range {out[-1]} - {v} runs backwards")
                out.extend(range(out[-1] + 1, v + 1))
                pending_range = False
            else:
                out.append(v)
        if pending_range:
            raise self.error(lineno, "a '-' range needs an end vertex on the same line")
        self._check_index(lineno, out)
        return out

    def _int(self, lineno: int, words: list[str], i: int) -> int:
        try:
            return int(words[i])
        except (ValueError, IndexError):
            raise self.error(lineno, f"expected an integer, got {' '.join(words)!r}") from None

    def _float(self, lineno: int, word: str) -> float:
        try:
            value = float(word)
        except ValueError:
            raise self.error(lineno, f"expected a number, got {word!r}") from None
        if not np.isfinite(value):
            raise self.error(lineno, f"non-finite number {word!r}")
        return value

    def _check_index(self, lineno: int, values: list[int]) -> None:
        bad = [v for v in values if not 0 <= v < self.vertex_count]
        if bad:
            raise self.error(
                lineno,
                f"vertex index {bad[0]} out of range (the base mesh has {self.vertex_count})",
            )

    def binding(self) -> Binding:
        n = len(self.refs)
        idx = np.zeros((n, 3), np.int32)
        w = np.zeros((n, 3))
        off = np.zeros((n, 3))
        single = np.zeros(n, bool)
        for r, (words, lineno) in enumerate(zip(self.refs, self.ref_lines, strict=True)):
            ints = [self._int(lineno, words, i) for i in range(min(3, len(words)))]
            self._check_index(lineno, ints)
            if len(words) == 1:
                idx[r] = ints[0]
                w[r, 0] = 1.0
                single[r] = True
                continue
            idx[r] = ints
            w[r] = [self._float(lineno, x) for x in words[3:6]]
            if len(words) == 9:
                off[r] = [self._float(lineno, x) for x in words[6:9]]
        refs = np.full((3, 2), -1, np.int32)
        lengths = np.ones(3)
        for key, (a, b, d) in self.scales.items():
            refs[_MH_TO_AVATAR[key]] = (a, b)
            lengths[_MH_TO_AVATAR[key]] = d / 10.0
        return make_binding(idx, w, _offsets_to_avatar(off), refs, lengths, single)

    def result(self) -> ProxyFile:
        if not self.refs:
            raise self.error(0, "no vertex references (a 'verts' section is required)")
        s = self.strings
        return ProxyFile(
            name=s.get("name", ""),
            binding=self.binding(),
            uuid=s.get("uuid", ""),
            basemesh=s.get("basemesh", "hm08"),
            obj_file=s.get("obj_file", ""),
            material=s.get("material", ""),
            vertexboneweights_file=s.get("vertexboneweights_file", ""),
            z_depth=self.z_depth,
            tags=tuple(self.tags),
            delete_verts=np.unique(np.asarray(self.deleted, np.int32)),
            meta=tuple(self.meta),
            comments=tuple(self.comments),
        )


def _offsets_to_avatar(off: np.ndarray) -> np.ndarray:
    """MakeHuman (dx, dy, dz) dm -> Avatar (dx, -dz, dy) m (division: it inverts exactly more
    often than multiplying by 0.1)."""
    return np.stack([off[:, 0], -off[:, 2], off[:, 1]], axis=-1) / 10.0


def _offsets_to_makehuman(off: np.ndarray) -> np.ndarray:
    return np.stack([off[:, 0], off[:, 2], -off[:, 1]], axis=-1) * 10.0


def loads(
    text: str, path: str | os.PathLike[str] | None = None, vertex_count: int = BASE_VERTEX_COUNT
) -> ProxyFile:
    """Parse ``.mhclo`` text. Raises FormatError(path, line, ...) on any malformed line or
    a vertex index outside ``0..vertex_count-1``."""
    parser = _Parser(path, vertex_count)
    for lineno, raw in enumerate(text.splitlines(), 1):
        parser.feed(lineno, raw)
    return parser.result()


def read(path: str | os.PathLike[str], vertex_count: int = BASE_VERTEX_COUNT) -> ProxyFile:
    """Read a ``.mhclo`` file (see ``loads``)."""
    try:
        text = Path(path).read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise FormatError(path, 0, f"cannot read: {exc.strerror}") from None
    return loads(text, path, vertex_count)


def shortest(encoded: np.ndarray, target: np.ndarray | None = None, decode=None) -> list[str]:
    """Shortest ``%g`` strings s with ``decode(float(s)) == target`` for each value.

    encoded: (n,) float64 values in file units; target: (n,) what the reader must recover
    (default ``encoded``); decode: the reader's arithmetic on a parsed number (default none).
    """
    encoded = np.asarray(encoded, dtype=np.float64)
    target = encoded if target is None else np.asarray(target, dtype=np.float64)
    decode = decode or (lambda x: x)
    out = np.empty(len(encoded), dtype=object)
    todo = np.ones(len(encoded), bool)
    for digits in range(5, 18):
        if not todo.any():
            break
        text = np.char.mod(f"%.{digits}g", encoded[todo])
        ok = decode(text.astype(np.float64)) == target[todo]
        if digits == 17:  # not every float is x / 10 of a float; keep the closest
            ok[:] = True
        where = np.flatnonzero(todo)[ok]
        out[where] = text[ok]
        todo[where] = False
    return [str(s) for s in out]


def _ref_lines(b: Binding) -> list[str]:
    # The reader divides by 10 after the axis swap; aim at the unscaled swapped values.
    target = np.stack([b.offsets[:, 0], b.offsets[:, 2], -b.offsets[:, 1]], axis=-1)
    off_text = np.asarray(
        shortest(_offsets_to_makehuman(b.offsets).ravel(), target.ravel(), lambda x: x / 10.0),
        dtype=object,
    ).reshape(-1, 3)
    w_text = np.asarray(shortest(b.weights.ravel()), dtype=object).reshape(-1, 3)
    lines = []
    for i in range(len(b)):
        a, bb, c = (int(x) for x in b.indices[i])
        if b.single[i]:
            lines.append(str(a))
        else:
            lines.append(f"{a} {bb} {c} {' '.join(w_text[i])} {' '.join(off_text[i])}")
    return lines


def _delete_lines(verts: np.ndarray) -> list[str]:
    """Ranges ``a - b`` for runs, at most ~12 items per line like MakeHuman's writer."""
    items: list[str] = []
    v = np.asarray(verts, dtype=np.int64)
    if len(v) == 0:
        return []
    breaks = np.flatnonzero(np.diff(v) != 1) + 1
    for run in np.split(v, breaks):
        items.append(str(run[0]) if len(run) == 1 else f"{run[0]} - {run[-1]}")
    return [" ".join(items[i : i + 12]) for i in range(0, len(items), 12)]


def dumps(proxy: ProxyFile) -> str:
    """``.mhclo`` text that ``loads`` reads back to an equal ProxyFile."""
    lines = list(proxy.comments)
    if lines:
        lines.append("")
    for key in ("uuid", "basemesh"):
        if getattr(proxy, key):
            lines.append(f"{key} {getattr(proxy, key)}")
    lines += [f"tag {t}" for t in proxy.tags]
    for key in ("name", "obj_file"):
        if getattr(proxy, key):
            lines.append(f"{key} {getattr(proxy, key)}")
    lines += _scale_lines(proxy.binding)
    lines.append(f"z_depth {proxy.z_depth}")
    for key in ("material", "vertexboneweights_file"):
        if getattr(proxy, key):
            lines.append(f"{key} {getattr(proxy, key)}")
    lines += [f"{k} {v}".rstrip() for k, v in proxy.meta]
    lines.append("verts 0")
    lines += _ref_lines(proxy.binding)
    if len(proxy.delete_verts):
        lines += ["", "delete_verts", *_delete_lines(proxy.delete_verts)]
    return "\n".join(lines) + "\n"


def _scale_lines(b: Binding) -> list[str]:
    out = []
    for key in ("x_scale", "z_scale", "y_scale"):  # MakeClothes' order
        axis = _MH_TO_AVATAR[key]
        a, c = (int(x) for x in b.scale_refs[axis])
        if a < 0:
            continue
        length_m = b.scale_lengths[axis : axis + 1]
        (length,) = shortest(length_m * 10.0, length_m, lambda x: x / 10.0)
        out.append(f"{key} {a} {c} {length}")
    return out


def write(path: str | os.PathLike[str], proxy: ProxyFile) -> None:
    """Write a ``.mhclo`` file atomically."""
    atomic.write_text(path, dumps(proxy))


def with_binding(proxy: ProxyFile, binding: Binding) -> ProxyFile:
    """The same file with another binding (e.g. after re-binding a garment)."""
    return replace(proxy, binding=binding)

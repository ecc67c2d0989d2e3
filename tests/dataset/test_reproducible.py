"""Same config and seed -> the same label bytes on another machine.

No second machine here, so the test changes what a second machine changes for Blender and
numpy: a fresh process, another core count for Cycles (1 thread against 2) and for the
native thread pools, another working folder. Every label file must come out byte for byte
the same; the RGB picture may not (Cycles adds samples up in another order on other cores),
and the issue does not ask it to.
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import pytest
from tests.dataset.test_dataset_render import CONFIG

pytestmark = pytest.mark.skipif(
    importlib.util.find_spec("bpy") is None or importlib.util.find_spec("OpenEXR") is None
    or importlib.util.find_spec("pycocotools") is None,
    reason="needs bpy, OpenEXR and pycocotools (the dataset extra)",
)  # fmt: skip

LABELS = ("depth.exr", "normals.exr", "instances.png", "parts.png", "meta.json")

RENDER_ONE = """
import sys
from pathlib import Path
from avatar.dataset import config, worker
c = config.loads(Path(sys.argv[1]).read_text(), "ds.toml")
worker.render_sample(c, int(sys.argv[2]), Path(sys.argv[3]), threads=int(sys.argv[4]))
"""


def _render(tmp_path: Path, name: str, index: int, threads: int) -> Path:
    """Sample ``index`` rendered in a fresh Python process on ``threads`` Cycles threads
    (and as many native threads), started in its own folder; its sample folder."""
    home = tmp_path / name
    home.mkdir()
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), OPENBLAS_NUM_THREADS=str(threads))
    env["PYTHONPATH"] = os.pathsep.join([str(Path(__file__).resolve().parents[2] / "src"),
                                         env.get("PYTHONPATH", "")])  # fmt: skip
    done = subprocess.run(
        [sys.executable, "-c", RENDER_ONE, str(tmp_path / "ds.toml"), str(index),
         str(home / "out"), str(threads)],  # fmt: skip
        cwd=home, env=env, capture_output=True, text=True, timeout=600,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    return home / "out" / "samples" / f"{index:08d}"


def _digests(folder: Path) -> dict[str, str]:
    return {name: hashlib.sha256((folder / name).read_bytes()).hexdigest() for name in LABELS}


def test_labels_are_the_same_bytes_on_another_core_count(tmp_path):
    (tmp_path / "ds.toml").write_text(CONFIG)
    one = _render(tmp_path, "one-core", 1, threads=1)
    two = _render(tmp_path, "two-cores", 1, threads=2)
    assert (one / "rgb.png").stat().st_size > 0 and (two / "rgb.png").stat().st_size > 0
    assert _digests(one) == _digests(two)
